#include "render.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <numbers>

#include "error.h"
#include "interrupt.h"
#include "sampling.h"

namespace mpath {

VertexRadiosity::VertexRadiosity(const PatchMesh& mesh, const RadiosityState& state) : mesh_(mesh) {
  const size_t nv = mesh.vertices.size();
  values_.assign(2 * nv * 3, 0.0);
  std::vector<double> weight(2 * nv, 0.0);
  for (size_t f = 0; f < state.faces; ++f) {
    const Patch& p = mesh.patches[mesh.face_patch[f]];
    const int side = mesh.face_side[f];
    const auto b = state.radiosity(mesh, f);
    for (int k = 0; k < (p.is_triangle() ? 3 : 4); ++k) {
      const size_t slot = side * nv + p.v[k];
      for (int c = 0; c < 3; ++c) values_[slot * 3 + c] += p.area * b[c];
      weight[slot] += p.area;
    }
  }
  for (size_t slot = 0; slot < 2 * nv; ++slot)
    if (weight[slot] > 0)
      for (int c = 0; c < 3; ++c) values_[slot * 3 + c] /= weight[slot];
}

namespace {

// Barycentric coordinates of p in triangle abc (in its plane).
std::array<double, 3> barycentric(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p) {
  const Vec3 n = cross(b - a, c - a);
  const double area2 = dot(n, n);
  if (area2 <= 0) return {1.0 / 3, 1.0 / 3, 1.0 / 3};
  const double u = dot(cross(c - b, p - b), n) / area2;
  const double v = dot(cross(a - c, p - c), n) / area2;
  return {u, v, 1.0 - u - v};
}

}  // namespace

std::array<double, 3> VertexRadiosity::at(int patch, int side, const Vec3& p) const {
  const Patch& q = mesh_.patches[patch];
  const size_t nv = mesh_.vertices.size();
  std::array<uint32_t, 3> tri{q.v[0], q.v[1], q.v[2]};
  auto w = barycentric(mesh_.vertices[tri[0]], mesh_.vertices[tri[1]], mesh_.vertices[tri[2]], p);
  if (!q.is_triangle() && std::min({w[0], w[1], w[2]}) < 0) {
    // The quad's other triangle, if the point lies more inside it.
    const std::array<uint32_t, 3> other{q.v[0], q.v[2], q.v[3]};
    const auto w2 = barycentric(mesh_.vertices[other[0]], mesh_.vertices[other[1]], mesh_.vertices[other[2]], p);
    if (std::min({w2[0], w2[1], w2[2]}) > std::min({w[0], w[1], w[2]})) {
      tri = other;
      w = w2;
    }
  }
  // A hit a rounding error outside the patch takes the nearest point on it:
  // weights clipped at 0 and scaled back to a sum of 1.
  if (std::min({w[0], w[1], w[2]}) < 0) {
    double sum = 0;
    for (double& wk : w) sum += (wk = std::max(wk, 0.0));
    for (double& wk : w) wk = sum > 0 ? wk / sum : 1.0 / 3;
  }
  std::array<double, 3> out{};
  for (int k = 0; k < 3; ++k)
    for (int c = 0; c < 3; ++c) out[c] += w[k] * values_[(side * nv + tri[k]) * 3 + c];
  return out;
}

Image render_camera(const CameraOptions& cam, const PatchMesh& mesh, const Tracer& tracer,
                    const VertexRadiosity& radiosity, unsigned long long seed) {
  return render_camera(
      cam, mesh, tracer,
      [&](int patch, int side, const Vec3& p) {
        auto b = radiosity.at(patch, side, p);
        for (double& c : b) c /= std::numbers::pi;  // radiance of a diffuse surface
        return b;
      },
      seed);
}

Image render_camera(const CameraOptions& cam, const PatchMesh& mesh, const Tracer& tracer, const Shader& shade,
                    unsigned long long seed) {
  Image image{cam.width, cam.height, std::vector<float>(static_cast<size_t>(cam.width) * cam.height * 3, 0.0f)};
  const Vec3 forward = normalize(cam.look_at - cam.position);
  const Vec3 right = normalize(cross(forward, cam.up));
  const Vec3 up = cross(right, forward);
  const double half_h = std::tan(0.5 * cam.fov_deg * std::numbers::pi / 180.0);
  const double half_w = half_h * cam.width / cam.height;
  const double tfar = 1e3 * (mesh.bounds.diagonal() + length(cam.position - mesh.bounds.center()));
  tbb::parallel_for(0, cam.height, [&](int y) {
    Rng rng = make_rng(seed, 3, static_cast<unsigned long long>(y));
    for (int x = 0; x < cam.width; ++x) {
      std::array<double, 3> sum{};
      for (int s = 0; s < cam.samples; ++s) {
        const double sx = (x + (cam.samples > 1 ? uniform(rng) : 0.5)) / cam.width * 2.0 - 1.0;
        const double sy = 1.0 - (y + (cam.samples > 1 ? uniform(rng) : 0.5)) / cam.height * 2.0;
        const Vec3 dir = normalize(forward + right * (sx * half_w) + up * (sy * half_h));
        const NearestHit hit = tracer.nearest(cam.position, dir, 0.0, tfar);
        if (hit.patch < 0) continue;
        const int side = mesh.side_met(hit.patch, dir);
        if (mesh.patch_faces[hit.patch][side] < 0) continue;  // the black back of a one-sided patch
        const auto b = shade(hit.patch, side, cam.position + dir * hit.t);
        for (int c = 0; c < 3; ++c) sum[c] += b[c];
      }
      for (int c = 0; c < 3; ++c)
        image.rgb[(static_cast<size_t>(y) * cam.width + x) * 3 + c] =
            static_cast<float>(sum[c] / cam.samples);
    }
  });
  return image;
}

}  // namespace mpath
