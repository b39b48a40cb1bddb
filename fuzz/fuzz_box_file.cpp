// libFuzzer target for the store's box file reader: open, then decode every
// chunk. A damaged or foreign file may only end in InputError.
#include "box_file.h"
#include "error.h"
#include "fuzz_common.h"

using namespace mpath;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = fuzz::write_input("box0000.lines", data, size);
  try {
    linestore::BoxFileReader reader(path);
    linestore::DecodedChunk chunk;
    for (size_t c = 0; c < reader.chunks().size(); ++c) reader.read_chunk(c, chunk);
  } catch (const InputError&) {
  }
  return 0;
}
