// LEB128 variable-length integers: 7 bits a byte, low groups first.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace mpath::linestore {

inline void put_varint(std::string& out, uint64_t v) {
  char buf[10];
  size_t n = 0;
  while (v >= 0x80) {
    buf[n++] = static_cast<char>((v & 0x7F) | 0x80);
    v >>= 7;
  }
  buf[n++] = static_cast<char>(v);
  out.append(buf, n);
}

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
