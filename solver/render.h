// Camera images of a solution: primary visibility with Embree, radiance B/pi
// interpolated from the vertices of each polygon's patches (smooth across
// patches, never across polygons), and any other per-point value seen
// through a camera.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "config.h"
#include "image_writer.h"
#include "radiosity_state.h"
#include "tracer.h"

namespace mpath {

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

}  // namespace mpath
