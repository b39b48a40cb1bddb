// A radix sort of 32-bit values, for the many short lists of codes a stored
// shot writes.
#pragma once

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

namespace mpath {

// Sorts `values` ascending, as std::sort would: where there are many, a
// least-significant-digit radix sort of bytes (a byte every value shares
// skipped), `scratch` its second buffer; few, std::sort.
inline void sort_u32(std::vector<uint32_t>& values, std::vector<uint32_t>& scratch) {
  const size_t n = values.size();
  if (n < 64) {
    std::sort(values.begin(), values.end());
    return;
  }
  uint32_t count[4][256] = {};
  for (uint32_t v : values)
    for (int d = 0; d < 4; ++d) ++count[d][(v >> (8 * d)) & 0xff];
  scratch.resize(n);
  for (int d = 0; d < 4; ++d) {
    if (count[d][(values[0] >> (8 * d)) & 0xff] == n) continue;
    uint32_t start[256], sum = 0;
    for (int k = 0; k < 256; ++k) start[k] = std::exchange(sum, sum + count[d][k]);
    for (uint32_t v : values) scratch[start[(v >> (8 * d)) & 0xff]++] = v;
    values.swap(scratch);
  }
}

}  // namespace mpath
