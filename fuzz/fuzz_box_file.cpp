// libFuzzer target for the store's box file reader: open, then decode every
// chunk whole and, as a pass does, its lines in a reversed order (the first
// half of them), also with a table of patch sides of 1000 patches, as a
// line-set pass decodes them. A damaged or foreign file may only end in
// InputError.
#include <array>
#include <numeric>
#include <vector>

#include "box_file.h"
#include "error.h"
#include "fuzz_common.h"

using namespace mpath;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = fuzz::write_input("box0000.lines", data, size);
  try {
    linestore::BoxFileReader reader(path);
    linestore::DecodedChunk chunk;
    std::vector<uint32_t> order;
    static const std::vector<std::array<int, 4>> table(1000, std::array<int, 4>{1, -1, 0, 0});
    const linestore::EventSides sides{table.data(), sizeof(table[0]), table.size()};
    for (size_t c = 0; c < reader.chunks().size(); ++c) {
      reader.read_chunk(c, chunk);
      order.resize(chunk.lines());
      std::iota(order.rbegin(), order.rend(), 0u);
      reader.read_chunk_lines(c, order.data(), order.size() / 2, chunk);
      reader.read_chunk_lines(c, order.data(), order.size() / 2, chunk, &sides);
    }
  } catch (const InputError&) {
  }
  return 0;
}
