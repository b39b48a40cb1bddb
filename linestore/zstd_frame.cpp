#include "zstd_frame.h"

#include <fmt/format.h>
#include <zstd.h>

#include <algorithm>
#include <vector>

#include "error.h"

namespace mpath::linestore {

namespace {

// Compresses `raw` into the thread's buffer; returns the frame's size.
size_t compress_to_buffer(std::string_view raw, int level, bool checksum, std::vector<char>*& out) {
  struct Context {
    ZSTD_CCtx* cctx = ZSTD_createCCtx();
    ~Context() { ZSTD_freeCCtx(cctx); }
  };
  thread_local Context context;
  thread_local std::vector<char> buffer;  // no zero-filling of a fresh bound-sized string per chunk
  ZSTD_CCtx* cctx = context.cctx;
  ZSTD_CCtx_reset(cctx, ZSTD_reset_session_and_parameters);
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_compressionLevel, level);
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_checksumFlag, checksum ? 1 : 0);
  buffer.resize(std::max(buffer.size(), ZSTD_compressBound(raw.size())));
  const size_t n = ZSTD_compress2(cctx, buffer.data(), buffer.size(), raw.data(), raw.size());
  if (ZSTD_isError(n)) throw InputError(fmt::format("zstd compression failed: {}", ZSTD_getErrorName(n)));
  out = &buffer;
  return n;
}

}  // namespace

std::string zstd_compress(std::string_view raw, int level, bool checksum) {
  std::vector<char>* buffer;
  const size_t n = compress_to_buffer(raw, level, checksum, buffer);
  return std::string(buffer->data(), n);
}

size_t zstd_compressed_size(std::string_view raw, int level) {
  std::vector<char>* buffer;
  return compress_to_buffer(raw, level, false, buffer);
}

double zstd_sampled_size(std::string_view raw, int level) {
  constexpr size_t kSlices = 8, kSlice = size_t{16} << 10;
  if (raw.size() <= kSlices * kSlice) return static_cast<double>(zstd_compressed_size(raw, level));
  thread_local std::string sample;
  sample.clear();
  for (size_t k = 0; k < kSlices; ++k) sample.append(raw.substr((raw.size() - kSlice) * k / (kSlices - 1), kSlice));
  return static_cast<double>(zstd_compressed_size(sample, level)) * static_cast<double>(raw.size()) /
         static_cast<double>(sample.size());
}

}  // namespace mpath::linestore
