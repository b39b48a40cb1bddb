// libFuzzer target for the store's manifest reader.
#include "error.h"
#include "fuzz_common.h"
#include "manifest.h"

using namespace mpath;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = fuzz::write_input("manifest.json", data, size);
  try {
    (void)linestore::read_manifest(path);
  } catch (const InputError&) {
  }
  return 0;
}
