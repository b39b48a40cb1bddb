// FNV-1a 64-bit: detects changed inputs and damaged files (not an adversary).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace mpath::linestore {

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

// Hash of a whole file, as 16 hex digits; throws InputError if unreadable.
std::string hash_file(const std::filesystem::path& path);
std::string hex64(uint64_t v);

}  // namespace mpath::linestore
