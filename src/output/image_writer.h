// Camera images as files: float EXR with run metadata, and an 8-bit sRGB PNG preview.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace mpath {

struct Image {
  int width = 0, height = 0;
  std::vector<float> rgb;  // row-major, top row first
};

// Writes pixel = radiance * 2^exposure as float RGB; `metadata` becomes string attributes.
void write_exr(const std::filesystem::path& path, const Image& image, double exposure,
               const std::map<std::string, std::string>& metadata);

// 8-bit sRGB preview of the EXR (radiance * 2^exposure, clipped).
void write_png(const std::filesystem::path& path, const Image& image, double exposure);

}  // namespace mpath
