// FNV-1a 64-bit and a block hash: detect changed inputs and damaged files
// (not an adversary).
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <fstream>

#include "error.h"

namespace mpath {

class Fnv1a {
 public:
  void add(const void* data, size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < size; ++i) {
      h_ ^= p[i];
      h_ *= 0x100000001b3ull;
    }
  }
  void add(std::string_view s) { add(s.data(), s.size()); }
  uint64_t value() const { return h_; }

 private:
  uint64_t h_ = 0xcbf29ce484222325ull;
};

inline std::string hex64(uint64_t v) {
  static const char* digits = "0123456789abcdef";
  std::string s(16, '0');
  for (int i = 15; i >= 0; --i, v >>= 4) s[i] = digits[v & 15];
  return s;
}

// Hash of a byte string for damage detection, at memory speed: four lanes
// of 8-byte words, each xored, multiplied and rotated, then folded with the
// length and the last bytes (FNV-1a). Not an adversary's hash.
inline uint64_t block_hash(const unsigned char* data, size_t size) {
  constexpr uint64_t k1 = 0x9e3779b185ebca87ull, k2 = 0xc2b2ae3d27d4eb4full;
  uint64_t lane[4] = {k1, k2, k1 ^ 0x165667b19e3779f9ull, k2 ^ 0x27d4eb2f165667c5ull};
  size_t i = 0;
  for (; i + 32 <= size; i += 32)
    for (int k = 0; k < 4; ++k) {
      uint64_t w;
      std::memcpy(&w, data + i + 8 * k, 8);
      lane[k] = (lane[k] ^ w) * k1;
      lane[k] = ((lane[k] << 31) | (lane[k] >> 33)) * k2;
    }
  Fnv1a tail;
  tail.add(lane, sizeof lane);
  tail.add(&size, sizeof size);
  tail.add(data + i, size - i);
  return tail.value();
}

// block_hash of each MiB of a byte stream, chained with FNV-1a: the same
// value however the stream is cut into add() calls.
class StreamHash {
 public:
  StreamHash() : buffer_(kBlock, '\0') {}
  void add(const void* data, size_t size) {
    const auto* p = static_cast<const char*>(data);
    // Whole blocks are hashed where they lie (a file read a MiB at a time
    // is not copied again).
    for (; used_ == 0 && size >= kBlock; p += kBlock, size -= kBlock) {
      const uint64_t block = block_hash(reinterpret_cast<const unsigned char*>(p), kBlock);
      h_.add(&block, sizeof block);
    }
    while (size > 0) {
      const size_t n = std::min(size, kBlock - used_);
      std::memcpy(buffer_.data() + used_, p, n);
      used_ += n;
      p += n;
      size -= n;
      if (used_ == kBlock) flush();
    }
  }
  uint64_t value() {
    if (used_ > 0) flush();
    return h_.value();
  }

 private:
  static constexpr size_t kBlock = size_t{1} << 20;
  void flush() {
    const uint64_t block = block_hash(reinterpret_cast<const unsigned char*>(buffer_.data()), used_);
    h_.add(&block, sizeof block);
    used_ = 0;
  }
  std::string buffer_;
  size_t used_ = 0;
  Fnv1a h_;
};

// StreamHash of the first `bytes` of a file (all of it by default), as 16
// hex digits; throws InputError if unreadable or shorter.
inline std::string hash_file(const std::filesystem::path& path, uint64_t bytes = UINT64_MAX) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot read file", path.string()));
  const bool limited = bytes != UINT64_MAX;
  StreamHash h;
  std::string buffer(1 << 20, '\0');
  while (bytes > 0) {
    in.read(buffer.data(), static_cast<std::streamsize>(std::min<uint64_t>(buffer.size(), bytes)));
    const auto n = static_cast<size_t>(in.gcount());
    if (n == 0) break;
    h.add(buffer.data(), n);
    bytes -= std::min<uint64_t>(bytes, n);
  }
  if (in.bad() || (limited && bytes > 0))
    throw InputError(fmt::format("{}: read error or cut short", path.string()));
  return hex64(h.value());
}

}  // namespace mpath
