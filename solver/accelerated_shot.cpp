#include "accelerated_shot.h"

#include <cmath>

namespace mpath {

SubsceneNearest::SubsceneNearest(const PatchMesh& mesh, const BoxStore& store)
    : mesh_(mesh), hierarchy_(store.hierarchy()) {
  for (size_t b = 0; b < hierarchy_.boxes.size(); ++b) {
    const SceneBox& box = hierarchy_.boxes[b];
    tracers_.push_back(std::make_unique<Tracer>(mesh, box.patches));
    const auto& assoc = store.box(static_cast<int>(b)).counts.associated;
    std::vector<std::array<int, 4>> per_ar(box.ar_count());
    for (uint32_t r = 0; r < box.ar_count(); ++r)
      for (size_t k = 0; k < 4; ++k) {
        const uint32_t id = k < linestore::BoxCounts::kAssociated ? assoc[(r * linestore::BoxCounts::kAssociated + k) * 2] : 0;
        per_ar[r][k] = id == 0 || id > box.patches.size() ? -1 : static_cast<int>(box.patches[id - 1]);
      }
    associated_.push_back(std::move(per_ar));
  }
}

double SubsceneNearest::hit_patch(int patch, const Vec3& org, const Vec3& dir) const {
  const Patch& p = mesh_.patches[patch];
  const double denom = dot(p.normal, dir);
  if (std::fabs(denom) < 1e-12) return INFINITY;
  const Vec3& v0 = mesh_.vertices[p.v[0]];
  const double t = dot(p.normal, v0 - org) / denom;
  if (t < 0) return INFINITY;
  const Vec3 x = org + dir * t;
  const int n = p.is_triangle() ? 3 : 4;
  for (int i = 0; i < n; ++i) {
    const Vec3& a = mesh_.vertices[p.v[i]];
    const Vec3& b = mesh_.vertices[p.v[(i + 1) % n]];
    if (dot(cross(b - a, x - a), p.normal) < 0) return INFINITY;
  }
  return t;
}

NearestHit SubsceneNearest::nearest_from(int from, const Vec3& org, const Vec3& dir) const {
  const double tfar = 4.0 * mesh_.bounds.diagonal() + 1.0;
  const double eps = 1e-9 * mesh_.bounds.diagonal();
  int b = hierarchy_.patch_box[from];
  int skip = -1;  // the child just left
  double t0 = 0;
  for (int step = 0; step < 256; ++step) {
    const SceneBox& box = hierarchy_.boxes[b];
    const NearestHit own = step == 0 ? tracers_[b]->nearest_from(from, org, dir, tfar) : tracers_[b]->nearest(org, dir, t0, tfar);
    int child = -1;
    BoxCrossing best{INFINITY, INFINITY, -1, -1};
    for (int c : box.children) {
      BoxCrossing x;
      if (c == skip || !cross_box(hierarchy_.boxes[c].bounds, org, dir, x) || x.t_out <= t0 + eps) continue;
      if (x.t_in < best.t_in) {
        best = x;
        child = c;
      }
    }
    BoxCrossing wall{0, INFINITY, -1, -1};
    if (b > 0 && !cross_box(box.bounds, org, dir, wall)) wall.t_out = t0;
    const double t_child = child >= 0 ? std::max(best.t_in, t0) : INFINITY;
    const double t_wall = b > 0 ? wall.t_out : INFINITY;
    if (own.patch >= 0 && own.t <= std::min(t_child, t_wall)) return own;
    if (child >= 0 && t_child <= t_wall) {
      const SceneBox& inner = hierarchy_.boxes[child];
      // Entering through an AR: its associated patches first.
      if (best.t_in >= t0) {
        const uint32_t ar = inner.ar_at(best.face_in, org + dir * best.t_in, dir);
        NearestHit hit;
        hit.t = INFINITY;
        for (int p : associated_[child][ar]) {
          if (p < 0) break;
          const double t = hit_patch(p, org, dir);
          if (t >= best.t_in - eps && t < hit.t) hit = {p, t};
        }
        if (hit.patch >= 0) {
          ++shortcuts_;
          return hit;
        }
      }
      b = child;  // missed them: search the subscene itself
      skip = -1;
      t0 = t_child;
      continue;
    }
    if (b > 0 && std::isfinite(t_wall)) {  // leaving the box: on in its parent
      skip = b;
      b = box.parent;
      t0 = t_wall;
      continue;
    }
    return {};
  }
  return {};
}

}  // namespace mpath
