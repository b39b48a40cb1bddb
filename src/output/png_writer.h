// Minimal 8-bit RGB PNG writer (zlib), for previews that any viewer opens.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

namespace mpath {

// `rgb` holds width * height * 3 bytes, top row first. Written atomically.
void write_png_rgb8(const std::filesystem::path& path, int width, int height, const std::vector<uint8_t>& rgb);

}  // namespace mpath
