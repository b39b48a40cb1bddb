// A planar polygon seen in its plane: its unit normal, centroid, and its
// corners projected onto the two axes other than the normal's dominant one,
// with their bounds. Shared by the load-time searches for coplanar polygons
// (coplanar_overlap.h, contact.h).
#pragma once

#include <cmath>
#include <vector>

#include "scene.h"

namespace mpath {

struct P2 {
  double u, v;
};

struct PlaneView {
  Vec3 n;         // unit normal (Newell's)
  Vec3 c;         // centroid of the corners
  int axis = 0;   // the dominant axis of the normal: projected away
  std::vector<P2> points;
  double lo_u = 0, hi_u = 0, lo_v = 0, hi_v = 0;
};

// False when the polygon has no area (fewer than 3 corners, or collinear).
inline bool plane_view(const std::vector<Vec3>& vs, double min_length, PlaneView& out) {
  if (vs.size() < 3) return false;
  const Vec3 n = newell_normal(vs);
  const double len = length(n);
  if (!(len > min_length)) return false;
  out.n = n * (1.0 / len);
  out.c = Vec3{0, 0, 0};
  for (const Vec3& p : vs) out.c = out.c + p * (1.0 / static_cast<double>(vs.size()));
  const Vec3& m = out.n;
  out.axis = std::fabs(m.x) >= std::fabs(m.y) && std::fabs(m.x) >= std::fabs(m.z) ? 0 : std::fabs(m.y) >= std::fabs(m.z) ? 1 : 2;
  const int ua = (out.axis + 1) % 3, va = (out.axis + 2) % 3;
  out.points.clear();
  out.lo_u = out.lo_v = INFINITY;
  out.hi_u = out.hi_v = -INFINITY;
  for (const Vec3& p : vs) {
    const P2 q{p[ua], p[va]};
    out.points.push_back(q);
    out.lo_u = std::min(out.lo_u, q.u);
    out.hi_u = std::max(out.hi_u, q.u);
    out.lo_v = std::min(out.lo_v, q.v);
    out.hi_v = std::max(out.hi_v, q.v);
  }
  return true;
}

}  // namespace mpath
