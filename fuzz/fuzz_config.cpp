// libFuzzer target for the config loader (TOML and every key's checks).
#include "config.h"
#include "error.h"
#include "fuzz_common.h"

using namespace mpath;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = fuzz::write_input("config.toml", data, size);
  try {
    const Options o = load_options(path, {});
    (void)options_to_toml(o);
    (void)options_to_json(o);
  } catch (const InputError&) {
  }
  return 0;
}
