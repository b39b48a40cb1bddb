#include "image_writer.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFloatAttribute.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>

#include <algorithm>
#include <cmath>

#include "atomic_file.h"
#include "error.h"
#include "interrupt.h"
#include "png_writer.h"

namespace mpath {

void write_exr(const std::filesystem::path& path, const Image& image, double exposure,
               const std::map<std::string, std::string>& metadata) {
  const float scale = static_cast<float>(std::exp2(exposure));
  std::vector<float> pixels(image.rgb.size());
  for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = image.rgb[i] * scale;
  const auto temp = temporary_path(path);
  const int slot = remember_temporary(temp);
  try {
    Imf::Header header(image.width, image.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const char* name : {"R", "G", "B"}) header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    header.insert("exposure", Imf::FloatAttribute(static_cast<float>(exposure)));
    for (const auto& [key, value] : metadata) header.insert(key, Imf::StringAttribute(value));
    Imf::OutputFile file(temp.c_str(), header);
    Imf::FrameBuffer fb;
    const size_t xs = 3 * sizeof(float), ys = xs * image.width;
    char* base = reinterpret_cast<char*>(pixels.data());
    fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
    fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
    fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
    file.setFrameBuffer(fb);
    file.writePixels(image.height);
  } catch (const std::exception& e) {
    std::error_code ec;
    std::filesystem::remove(temp, ec);
    forget_temporary(slot);
    throw InputError(fmt::format("{}: writing the EXR image failed: {}", path.string(), e.what()));
  }
  forget_temporary(slot);
  commit_temporary(temp, path);
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
