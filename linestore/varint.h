// LEB128 variable-length integers: 7 bits a byte, low groups first.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace mpath::linestore {

// Writes `v` at `p` (10 bytes at most); returns the end of what it wrote.
inline char* write_varint(char* p, uint64_t v) {
  while (v >= 0x80) {
    *p++ = static_cast<char>((v & 0x7F) | 0x80);
    v >>= 7;
  }
  *p++ = static_cast<char>(v);
  return p;
}

inline void put_varint(std::string& out, uint64_t v) {
  char buf[10];
  out.append(buf, static_cast<size_t>(write_varint(buf, v) - buf));
}

// A byte stream written a varint at a time, for the hot loops that write
// millions (a chunk's encoder): room for the longest varint is made before
// each write, which is then a few plain stores, where std::string::append
// checks, copies and terminates every time.
class VarintStream {
 public:
  void reserve(size_t bytes) {
    if (buf_.size() < bytes + kMaxVarint) buf_.resize(bytes + kMaxVarint);
  }
  void put(uint64_t v) {
    if (buf_.size() - size_ < kMaxVarint) buf_.resize(2 * buf_.size() + 64);
    size_ = static_cast<size_t>(write_varint(buf_.data() + size_, v) - buf_.data());
  }
  void clear() { size_ = 0; }
  std::string_view view() const { return {buf_.data(), size_}; }
  size_t size() const { return size_; }

 private:
  static constexpr size_t kMaxVarint = 10;
  std::string buf_;  // written up to size_; the rest is room
  size_t size_ = 0;
};

// Reads one varint at `pos`; false when the buffer ends inside it or it is
// longer than 10 bytes.
inline bool get_varint(const unsigned char* data, size_t size, size_t& pos, uint64_t& v) {
  v = 0;
  for (int shift = 0; shift < 70 && pos < size; shift += 7) {
    const unsigned char b = data[pos++];
    v |= static_cast<uint64_t>(b & 0x7F) << shift;
    if (!(b & 0x80)) return true;
  }
  return false;
}

}  // namespace mpath::linestore
