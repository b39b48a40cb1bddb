#include "image_writer.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFloatAttribute.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStringAttribute.h>

#include <algorithm>
#include <cmath>

#include "atomic_file.h"
#include "color.h"
#include "error.h"
#include "interrupt.h"
#include "png_writer.h"

namespace mpath {

namespace {

// Float channels (interleaved, `names.size()` per pixel) into an EXR, atomically.
void write_float_exr(const std::filesystem::path& path, int width, int height, std::vector<float> pixels,
                     const std::vector<const char*>& names, Imf::Header header) {
  const auto temp = temporary_path(path);
  const int slot = remember_temporary(temp);
  try {
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const char* name : names) header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    Imf::OutputFile file(temp.c_str(), header);
    Imf::FrameBuffer fb;
    const size_t xs = names.size() * sizeof(float), ys = xs * static_cast<size_t>(width);
    char* base = reinterpret_cast<char*>(pixels.data());
    for (size_t k = 0; k < names.size(); ++k) fb.insert(names[k], Imf::Slice(Imf::FLOAT, base + k * sizeof(float), xs, ys));
    file.setFrameBuffer(fb);
    file.writePixels(height);
  } catch (const std::exception& e) {
    std::error_code ec;
    std::filesystem::remove(temp, ec);
    forget_temporary(slot);
    throw InputError(fmt::format("{}: writing the EXR image failed: {}", path.string(), e.what()));
  }
  forget_temporary(slot);
  commit_temporary(temp, path);
}

Imf::Header header_with(int width, int height, const std::map<std::string, std::string>& metadata) {
  Imf::Header header(width, height);
  for (const auto& [key, value] : metadata) header.insert(key, Imf::StringAttribute(value));
  return header;
}

}  // namespace

void write_exr(const std::filesystem::path& path, const Image& image, double exposure,
               const std::map<std::string, std::string>& metadata) {
  Imf::Header header = header_with(image.width, image.height, metadata);
  // What the RGB means: Rec. 709 primaries, white-balanced to equal energy (docs/colour.md).
  Imf::addChromaticities(header, Imf::Chromaticities(Imath::V2f(0.64f, 0.33f), Imath::V2f(0.30f, 0.60f),
                                                     Imath::V2f(0.15f, 0.06f), Imath::V2f(1 / 3.f, 1 / 3.f)));
  Imf::addWhiteLuminance(header, static_cast<float>(kWhiteEfficacy));
  header.insert("exposure", Imf::FloatAttribute(static_cast<float>(exposure)));
  write_float_exr(path, image.width, image.height, image.rgb, {"R", "G", "B"}, std::move(header));
}

void write_scalar_exr(const std::filesystem::path& path, int width, int height, std::vector<float> values,
                      const std::map<std::string, std::string>& metadata) {
  write_float_exr(path, width, height, std::move(values), {"Y"}, header_with(width, height, metadata));
}

std::vector<float> luminance_cd_m2(const Image& image) {
  std::vector<float> y(static_cast<size_t>(image.width) * image.height);
  for (size_t i = 0; i < y.size(); ++i)
    y[i] = static_cast<float>(kWhiteEfficacy * luminance({image.rgb[3 * i], image.rgb[3 * i + 1], image.rgb[3 * i + 2]}));
  return y;
}

void write_png(const std::filesystem::path& path, const Image& image, double exposure) {
  const double scale = std::exp2(exposure);
  std::vector<uint8_t> bytes(image.rgb.size());
  for (size_t i = 0; i < bytes.size(); ++i) {
    const double v = std::clamp(image.rgb[i] * scale, 0.0, 1.0);
    const double srgb = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
    bytes[i] = static_cast<uint8_t>(std::lround(255.0 * srgb));
  }
  write_png_rgb8(path, image.width, image.height, bytes);
}

}  // namespace mpath
