#include "coplanar_overlap.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "plane_view.h"

namespace mpath {
namespace {

double orient(const P2& a, const P2& b, const P2& c) { return (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u); }

// A polygon projected onto its plane's two dominant axes.
struct Flat {
  int polygon;
  std::array<long long, 3> normal_key;  // the unit normal rounded to 1e-5
  double offset;                        // n . x on the plane
  std::vector<P2> points;
  double lo_u, lo_v, hi_u, hi_v;
};

// Distance of p from segment ab.
double segment_distance(const P2& p, const P2& a, const P2& b) {
  const double du = b.u - a.u, dv = b.v - a.v, len2 = du * du + dv * dv;
  const double t = len2 > 0 ? std::clamp(((p.u - a.u) * du + (p.v - a.v) * dv) / len2, 0.0, 1.0) : 0.0;
  return std::hypot(p.u - (a.u + t * du), p.v - (a.v + t * dv));
}

// p strictly inside the polygon: inside by the crossing rule and farther than
// eps from its boundary.
bool strictly_inside(const P2& p, const std::vector<P2>& poly, double eps) {
  bool inside = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const P2 &a = poly[i], &b = poly[j];
    if (segment_distance(p, a, b) <= eps) return false;
    if ((a.v > p.v) != (b.v > p.v) && p.u < (b.u - a.u) * (p.v - a.v) / (b.v - a.v) + a.u) inside = !inside;
  }
  return inside;
}

// Segments ab and cd cross at a point inside both (not at an end, not along a shared line).
bool cross_properly(const P2& a, const P2& b, const P2& c, const P2& d, double eps) {
  const double lab = std::hypot(b.u - a.u, b.v - a.v), lcd = std::hypot(d.u - c.u, d.v - c.v);
  const double o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
  return ((o1 > eps * lab && o2 < -eps * lab) || (o1 < -eps * lab && o2 > eps * lab)) &&
         ((o3 > eps * lcd && o4 < -eps * lcd) || (o3 < -eps * lcd && o4 > eps * lcd));
}

bool overlap(const Flat& a, const Flat& b, double eps, size_t& budget) {
  const size_t na = a.points.size(), nb = b.points.size();
  budget = budget > na * nb ? budget - na * nb : 0;
  for (size_t i = 0; i < na; ++i)
    for (size_t j = 0; j < nb; ++j)
      if (cross_properly(a.points[i], a.points[(i + 1) % na], b.points[j], b.points[(j + 1) % nb], eps)) return true;
  // No boundaries cross: one holds the other, or they only touch.
  for (const auto* pair : {&a, &b}) {
    const Flat& x = *pair;
    const Flat& y = pair == &a ? b : a;
    const size_t n = x.points.size();
    for (size_t i = 0; i < n; ++i) {
      const P2& p = x.points[i];
      const P2& q = x.points[(i + 1) % n];
      if (strictly_inside(p, y.points, eps) || strictly_inside({0.5 * (p.u + q.u), 0.5 * (p.v + q.v)}, y.points, eps))
        return true;
    }
  }
  return false;
}

bool same_vertex_set(const Polygon& a, const Polygon& b) {
  if (a.vertices.size() != b.vertices.size()) return false;
  auto sorted = [](const Polygon& p) {
    std::vector<std::array<double, 3>> v;
    for (const Vec3& x : p.vertices) v.push_back({x.x, x.y, x.z});
    std::sort(v.begin(), v.end());
    return v;
  };
  return sorted(a) == sorted(b);
}

}  // namespace

CoplanarOverlaps find_coplanar_overlaps(const Scene& scene, size_t budget) {
  CoplanarOverlaps result;
  const double size = std::max(scene.bounds().diagonal(), 1e-30);
  const double plane_eps = 1e-7 * size, eps = 1e-9 * size;
  std::vector<Flat> flats;
  PlaneView view;
  for (size_t k = 0; k < scene.polygons.size(); ++k) {
    if (!plane_view(scene.polygons[k].vertices, 1e-12 * size * size, view)) continue;  // no area
    const Vec3& n = view.n;
    Flat f;
    f.polygon = static_cast<int>(k);
    f.normal_key = {std::llround(n.x * 1e5), std::llround(n.y * 1e5), std::llround(n.z * 1e5)};
    f.offset = dot(n, view.c);
    f.points = view.points;
    f.lo_u = view.lo_u;
    f.hi_u = view.hi_u;
    f.lo_v = view.lo_v;
    f.hi_v = view.hi_v;
    flats.push_back(std::move(f));
  }
  // Planes: the same rounded normal (so the same facing), offsets within plane_eps.
  std::sort(flats.begin(), flats.end(), [](const Flat& a, const Flat& b) {
    return a.normal_key != b.normal_key ? a.normal_key < b.normal_key : a.offset < b.offset;
  });
  std::vector<bool> overlapping(scene.polygons.size(), false);
  std::vector<size_t> group;
  for (size_t i = 0; i < flats.size() && budget > 0;) {
    size_t j = i + 1;
    while (j < flats.size() && flats[j].normal_key == flats[i].normal_key &&
           flats[j].offset - flats[j - 1].offset <= plane_eps)
      ++j;
    if (j - i > 1) {
      // Sweep the plane's polygons by their boxes' low u.
      group.clear();
      for (size_t k = i; k < j; ++k) group.push_back(k);
      std::sort(group.begin(), group.end(), [&](size_t a, size_t b) { return flats[a].lo_u < flats[b].lo_u; });
      for (size_t x = 0; x < group.size() && budget > 0; ++x) {
        const Flat& a = flats[group[x]];
        for (size_t y = x + 1; y < group.size() && flats[group[y]].lo_u < a.hi_u - eps && budget > 0; ++y) {
          const Flat& b = flats[group[y]];
          --budget;  // a box test counts too: a column of a million tiles is no hang
          if (b.lo_v >= a.hi_v - eps || a.lo_v >= b.hi_v - eps) continue;
          if (same_vertex_set(scene.polygons[a.polygon], scene.polygons[b.polygon])) continue;
          if (!overlap(a, b, eps, budget)) continue;
          if (result.first < 0) {
            result.first = std::min(a.polygon, b.polygon);
            result.second = std::max(a.polygon, b.polygon);
          }
          overlapping[a.polygon] = overlapping[b.polygon] = true;
        }
      }
    }
    i = j;
  }
  result.polygons = static_cast<size_t>(std::count(overlapping.begin(), overlapping.end(), true));
  return result;
}

}  // namespace mpath
