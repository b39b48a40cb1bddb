#include "png_writer.h"

#include <zlib.h>

#include <string>

#include "atomic_file.h"
#include "error.h"

namespace mpath {
namespace {

void put_u32(std::string& out, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<char>((v >> shift) & 0xFF));
}

void chunk(std::ostream& out, const char* type, const std::string& data) {
  std::string c;
  put_u32(c, static_cast<uint32_t>(data.size()));
  c.append(type, 4);
  c += data;
  uLong crc = crc32(0L, Z_NULL, 0);
  crc = crc32(crc, reinterpret_cast<const Bytef*>(c.data() + 4), static_cast<uInt>(c.size() - 4));
  put_u32(c, static_cast<uint32_t>(crc));
  out.write(c.data(), static_cast<std::streamsize>(c.size()));
}

}  // namespace

void write_png_rgb8(const std::filesystem::path& path, int width, int height, const std::vector<uint8_t>& rgb) {
  MPATH_CHECK(rgb.size() == static_cast<size_t>(width) * height * 3, "png buffer size");
  std::string raw;  // each row starts with filter type 0
  raw.reserve(static_cast<size_t>(height) * (width * 3 + 1));
  for (int y = 0; y < height; ++y) {
    raw.push_back(0);
    raw.append(reinterpret_cast<const char*>(rgb.data()) + static_cast<size_t>(y) * width * 3, width * 3);
  }
  uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
  std::string packed(packed_size, '\0');
  MPATH_CHECK(compress2(reinterpret_cast<Bytef*>(packed.data()), &packed_size,
                        reinterpret_cast<const Bytef*>(raw.data()), static_cast<uLong>(raw.size()), 6) == Z_OK,
              "zlib compress failed");
  packed.resize(packed_size);

  std::string header;
  put_u32(header, static_cast<uint32_t>(width));
  put_u32(header, static_cast<uint32_t>(height));
  header += std::string("\x08\x02\x00\x00\x00", 5);  // 8-bit RGB, no interlace
  AtomicFile file(path);
  file.stream().write("\x89PNG\r\n\x1a\n", 8);
  chunk(file.stream(), "IHDR", header);
  chunk(file.stream(), "IDAT", packed);
  chunk(file.stream(), "IEND", "");
  file.commit();
}

}  // namespace mpath
