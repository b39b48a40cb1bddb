// Geometry of subscene boxes: where a line crosses a box, which AR a
// crossing falls in, and whether a triangle enters a box's interior.
#include "box_geometry.h"

#include <algorithm>
#include <cmath>

namespace mpath {
namespace {

// Band limits: cos(theta) = sqrt(2/3) and sqrt(1/3) split the projected
// solid angle of a hemisphere into thirds.
const double kBand0 = std::sqrt(2.0 / 3.0);
const double kBand1 = std::sqrt(1.0 / 3.0);

}  // namespace

uint32_t SceneBox::ar_at(int face, const Vec3& point, const Vec3& dir) const {
  const int axis = face / 2;
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const int n = grid[face];
  const Vec3 size = bounds.size();
  auto cell = [&](int k) {
    if (!(size[k] > 0)) return 0;
    const int c = static_cast<int>(std::floor((point[k] - bounds.lo[k]) / size[k] * n));
    return std::clamp(c, 0, n - 1);
  };
  const int column = cell(u), row = cell(v);
  // The direction turned to the face's outside: undirected lines get one AR.
  const double outward = (face % 2) ? 1.0 : -1.0;
  const double s = dir[axis] * outward >= 0 ? 1.0 : -1.0;
  const double c = std::fabs(dir[axis]) / std::max(length(dir), 1e-300);
  const int band = c > kBand0 ? 0 : (c > kBand1 ? 1 : 2);
  // Sector k holds azimuths phi = atan2(y, x) in [-pi + k pi/4, -pi + (k+1) pi/4),
  // found by comparisons instead of atan2.
  const double x = s * dir[u], y = s * dir[v];
  const double ax = std::fabs(x), ay = std::fabs(y);
  int sector;
  if (y < 0) sector = x < 0 ? (ay < ax ? 0 : 1) : (ay > ax ? 2 : 3);
  else sector = x > 0 ? (y < x ? 4 : 5) : (y > ax ? 6 : 7);
  return ar_offset[face] + static_cast<uint32_t>(((row * n + column) * kSectors + sector) * kBands + band);
}

SceneBox::ArPlace SceneBox::place(uint32_t ar) const {
  int face = 0;
  while (face < 5 && ar >= ar_offset[face + 1]) ++face;
  uint32_t local = ar - ar_offset[face];
  ArPlace p;
  p.face = face;
  p.band = static_cast<int>(local % kBands);
  local /= kBands;
  p.sector = static_cast<int>(local % kSectors);
  local /= kSectors;
  p.column = static_cast<int>(local % grid[face]);
  p.row = static_cast<int>(local / grid[face]);
  return p;
}

uint32_t SceneBox::ar_of(const ArPlace& p) const {
  return ar_offset[p.face] +
         static_cast<uint32_t>(((p.row * grid[p.face] + p.column) * kSectors + p.sector) * kBands + p.band);
}


void SceneBox::set_ar_offsets() {
  ar_offset[0] = 0;
  for (int f = 0; f < 6; ++f) ar_offset[f + 1] = ar_offset[f] + static_cast<uint32_t>(grid[f] * grid[f] * kArsPerVp);
}

bool cross_box(const Bounds& box, const Vec3& org, const Vec3& dir, BoxCrossing& out) {
  double t0 = -INFINITY, t1 = INFINITY;
  int f0 = -1, f1 = -1;
  for (int i = 0; i < 3; ++i) {
    if (dir[i] == 0) {
      if (org[i] < box.lo[i] || org[i] > box.hi[i]) return false;
      continue;
    }
    double a = (box.lo[i] - org[i]) / dir[i], b = (box.hi[i] - org[i]) / dir[i];
    int fa = 2 * i, fb = 2 * i + 1;
    if (a > b) {
      std::swap(a, b);
      std::swap(fa, fb);
    }
    if (a > t0) {
      t0 = a;
      f0 = fa;
    }
    if (b < t1) {
      t1 = b;
      f1 = fb;
    }
  }
  if (f0 < 0 || f1 < 0 || !(t1 > t0)) return false;
  out = {t0, t1, f0, f1};
  return true;
}

// Separating-axis test of a triangle against an axis-aligned box (the box's
// three axes, the triangle's normal and the nine edge cross products). Touching
// counts as not meeting, so polygons lying on a box wall stay outside.
bool triangle_meets_box(const Vec3& a, const Vec3& b, const Vec3& c, const Bounds& box) {
  // Most triangles a caller asks about lie clear of the box along an axis.
  for (int i = 0; i < 3; ++i)
    if (std::max({a[i], b[i], c[i]}) <= box.lo[i] || std::min({a[i], b[i], c[i]}) >= box.hi[i]) return false;
  const Vec3 center = box.center(), half = box.size() * 0.5;
  const Vec3 v[3] = {a - center, b - center, c - center};
  const Vec3 e[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  auto separated = [&](const Vec3& axis) {
    const double len = length(axis);
    if (len < 1e-300) return false;
    double lo = INFINITY, hi = -INFINITY;
    for (const Vec3& p : v) {
      const double d = dot(p, axis);
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    const double r = half.x * std::fabs(axis.x) + half.y * std::fabs(axis.y) + half.z * std::fabs(axis.z);
    return lo >= r || hi <= -r;
  };
  for (int i = 0; i < 3; ++i) {
    Vec3 axis;
    axis[i] = 1;
    if (separated(axis)) return false;
  }
  if (separated(cross(e[0], e[1]))) return false;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      Vec3 axis;
      axis[j] = 1;
      if (separated(cross(e[i], axis))) return false;
    }
  return true;
}

Bounds line_box(const Bounds& b) {
  Bounds out = b;
  const double margin = 1e-3 * std::max(b.diagonal(), 1e-30);
  for (int i = 0; i < 3; ++i) {
    out.lo[i] -= margin;
    out.hi[i] += margin;
  }
  return out;
}

}  // namespace mpath
