// zstd compression with one context per thread, kept from call to call
// (making one per chunk costs its tables' allocation every time).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace mpath::linestore {

// A zstd frame of `raw` at `level`, with zstd's checksum when asked.
std::string zstd_compress(std::string_view raw, int level, bool checksum);
// The size of that frame without a checksum, without keeping it.
size_t zstd_compressed_size(std::string_view raw, int level);
// An estimate of zstd_compressed_size for long inputs at a fraction of its
// cost: the frame of evenly spaced slices of `raw` (about 128 KB in all),
// scaled to raw's size; the exact size below that.
double zstd_sampled_size(std::string_view raw, int level);

}  // namespace mpath::linestore
