// Camera images of a solution: primary visibility with Embree, radiance B/pi
// interpolated from the vertices of each polygon's patches (smooth across
// patches, never across polygons), written as float EXR with run metadata and
// optionally as a tone-mapped PNG preview.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "config.h"
#include "radiosity_state.h"
#include "tracer.h"

namespace mpath {

struct Image {
  int width = 0, height = 0;
  std::vector<float> rgb;  // row-major, top row first
};

// Area-weighted radiosity of every (vertex, side), for smooth shading.
class VertexRadiosity {
 public:
  VertexRadiosity(const PatchMesh& mesh, const RadiosityState& state);
  // Interpolated radiosity at point p of `patch`, seen from `side`.
  std::array<double, 3> at(int patch, int side, const Vec3& p) const;

 private:
  const PatchMesh& mesh_;
  std::vector<double> values_;  // (side * vertices + vertex) * 3
};

Image render_camera(const CameraOptions& camera, const PatchMesh& mesh, const Tracer& tracer,
                    const VertexRadiosity& radiosity, unsigned long long seed);

// Any per-point value seen through the camera: the mean of `shade(patch,
// side, point)` over the pixel's samples (0 where nothing or a black back is hit).
using Shader = std::function<std::array<double, 3>(int patch, int side, const Vec3& point)>;
Image render_camera(const CameraOptions& camera, const PatchMesh& mesh, const Tracer& tracer, const Shader& shade,
                    unsigned long long seed);

// Writes pixel = radiance * 2^exposure as float RGB; `metadata` becomes string attributes.
void write_exr(const std::filesystem::path& path, const Image& image, double exposure,
               const std::map<std::string, std::string>& metadata);

// 8-bit sRGB preview of the EXR (radiance * 2^exposure, clipped).
void write_png(const std::filesystem::path& path, const Image& image, double exposure);

}  // namespace mpath
