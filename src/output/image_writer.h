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

// Writes the scene-referred radiance (W/sr/m2) as float RGB, with the
// standard `chromaticities` (mpath's RGB: Rec. 709 primaries, equal-energy
// white) and `whiteLuminance` (cd/m2 of RGB 1, 1, 1) attributes, the
// viewer's `exposure` (the PNG applies it) and `metadata` as string attributes.
void write_exr(const std::filesystem::path& path, const Image& image, double exposure,
               const std::map<std::string, std::string>& metadata);

// One value per pixel (row-major, top row first) as a float Y image.
void write_scalar_exr(const std::filesystem::path& path, int width, int height, std::vector<float> values,
                      const std::map<std::string, std::string>& metadata);

// The luminance of each pixel of a radiance image, in cd/m2.
std::vector<float> luminance_cd_m2(const Image& image);

// 8-bit sRGB preview of the EXR (radiance * 2^exposure, clipped).
void write_png(const std::filesystem::path& path, const Image& image, double exposure);

}  // namespace mpath
