#include "contact.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "plane_view.h"

namespace mpath {
namespace {

using Poly2 = std::vector<P2>;

double cross2(const P2& a, const P2& b, const P2& c) { return (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u); }

double signed_area(const Poly2& p) {
  double s = 0;
  for (size_t i = 0, j = p.size() - 1; i < p.size(); j = i++) s += p[j].u * p[i].v - p[i].u * p[j].v;
  return 0.5 * s;
}

double perimeter(const Poly2& p) {
  double s = 0;
  for (size_t i = 0, j = p.size() - 1; i < p.size(); j = i++) s += std::hypot(p[i].u - p[j].u, p[i].v - p[j].v);
  return s;
}

// The part of convex `x` where side * cross(a, b, p) >= 0 (Sutherland-Hodgman, one edge).
Poly2 clip(const Poly2& x, const P2& a, const P2& b, double side) {
  Poly2 out;
  const size_t n = x.size();
  for (size_t i = 0; i < n; ++i) {
    const P2& p = x[i];
    const P2& q = x[(i + 1) % n];
    const double dp = side * cross2(a, b, p), dq = side * cross2(a, b, q);
    if (dp >= 0) out.push_back(p);
    if ((dp > 0 && dq < 0) || (dp < 0 && dq > 0)) {
      const double t = dp / (dp - dq);
      out.push_back({p.u + t * (q.u - p.u), p.v + t * (q.v - p.v)});
    }
  }
  return out;
}

// The part of convex `x` inside convex `q` (`q_side`: the sign of q's area).
Poly2 clip_inside(Poly2 x, const Poly2& q, double q_side) {
  for (size_t k = 0; k < q.size() && x.size() >= 3; ++k) x = clip(x, q[k], q[(k + 1) % q.size()], q_side);
  return x.size() >= 3 ? x : Poly2{};
}

bool convex(const Poly2& p) {
  const double area = signed_area(p);
  if (area == 0) return false;
  const double tolerance = 1e-12 * std::fabs(area);
  for (size_t i = 0; i < p.size(); ++i)
    if (cross2(p[i], p[(i + 1) % p.size()], p[(i + 2) % p.size()]) * (area > 0 ? 1 : -1) < -tolerance) return false;
  return true;
}

// A polygon on its plane, in the 2D coordinates its plane group shares.
struct Flat {
  int polygon = 0;
  Vec3 n;                          // unit normal
  double d = 0;                    // n . x on the plane
  std::array<long long, 3> key{};  // the plane's normal, signed to be canonical, rounded to 1e-5
  double offset = 0;               // that normal . x
  bool flipped = false;            // the polygon faces against the canonical normal
  int axis = 0;                    // the dominant axis of the normal: projected away
  Poly2 points;
  double lo_u = 0, hi_u = 0, lo_v = 0, hi_v = 0;
  bool is_convex = false;
};

Flat make_flat(const Polygon& poly, int index) {
  Flat f;
  f.polygon = index;
  PlaneView view;
  if (!plane_view(poly.vertices, 0.0, view)) return f;
  f.n = view.n;
  f.d = dot(f.n, view.c);
  f.axis = view.axis;
  f.flipped = f.n[f.axis] < 0;
  const Vec3 canonical = f.flipped ? -f.n : f.n;
  f.key = {std::llround(canonical.x * 1e5), std::llround(canonical.y * 1e5), std::llround(canonical.z * 1e5)};
  f.offset = dot(canonical, view.c);
  f.points = std::move(view.points);
  f.lo_u = view.lo_u;
  f.hi_u = view.hi_u;
  f.lo_v = view.lo_v;
  f.hi_v = view.hi_v;
  f.is_convex = convex(f.points);
  return f;
}

// `p` without repeated corners and corners on a straight edge (clipping
// leaves both), so that a rectangle cut from a rectangle stays a
// rectangle, which the mesher grids, instead of a pentagon it triangulates.
Poly2 simplified(const Poly2& p, double eps) {
  Poly2 out;
  for (const P2& q : p)
    if (out.empty() || std::hypot(q.u - out.back().u, q.v - out.back().v) > eps) out.push_back(q);
  while (out.size() > 1 && std::hypot(out.front().u - out.back().u, out.front().v - out.back().v) <= eps) out.pop_back();
  for (bool changed = true; changed && out.size() > 3;) {
    changed = false;
    for (size_t i = 0; i < out.size() && out.size() > 3; ++i) {
      const P2& a = out[(i + out.size() - 1) % out.size()];
      const P2& b = out[i];
      const P2& c = out[(i + 1) % out.size()];
      const double span = std::hypot(c.u - a.u, c.v - a.v);
      if (std::fabs(cross2(a, b, c)) <= eps * span) {  // b within eps of the line a-c
        out.erase(out.begin() + static_cast<long>(i));
        changed = true;
      }
    }
  }
  return out;
}

// A piece worth keeping: wider on average than `width`.
bool substantial(const Poly2& p, double width) {
  return p.size() >= 3 && std::fabs(signed_area(p)) > width * perimeter(p);
}

// The parts of convex `x` outside convex `q`, edge by edge (each inside the
// edges before it), appended to `out`; returns the part inside q.
Poly2 cut_away(Poly2 rest, const Poly2& q, double width, std::vector<Poly2>& out) {
  const double q_side = signed_area(q) > 0 ? 1.0 : -1.0;
  for (size_t k = 0; k < q.size() && rest.size() >= 3; ++k) {
    const P2 &a = q[k], &b = q[(k + 1) % q.size()];
    Poly2 outside = clip(rest, a, b, -q_side);
    if (substantial(outside, width)) out.push_back(std::move(outside));
    rest = clip(rest, a, b, q_side);
  }
  return rest;
}

// `x` split by convex `q`: its part inside q first, then the rest. The rest
// is cut first by q's bounding rectangle, whose pieces outside it are
// rectangles where x is one (the mesher grids rectangles, and would
// triangulate wedges), then inside that rectangle by q's own edges. Empty
// when x and q share no area (x stays whole).
std::vector<Poly2> split_by(const Poly2& x, const Flat& q, double width) {
  const double q_side = signed_area(q.points) > 0 ? 1.0 : -1.0;
  Poly2 inside = clip_inside(x, q.points, q_side);
  if (!substantial(inside, width)) return {};
  std::vector<Poly2> out{std::move(inside)};
  const Poly2 box{{q.lo_u, q.lo_v}, {q.hi_u, q.lo_v}, {q.hi_u, q.hi_v}, {q.lo_u, q.hi_v}};
  cut_away(cut_away(x, box, width, out), q.points, width, out);
  return out;
}

// The polygons of `scene` on their planes, sorted so that polygons on one
// plane (normal within 1e-5, offset within `plane_eps` of the one before)
// are neighbours.
std::vector<Flat> sorted_flats(const Scene& scene) {
  std::vector<Flat> flats;
  for (size_t k = 0; k < scene.polygons.size(); ++k) {
    Flat f = make_flat(scene.polygons[k], static_cast<int>(k));
    if (!f.points.empty()) flats.push_back(std::move(f));
  }
  std::sort(flats.begin(), flats.end(), [](const Flat& a, const Flat& b) {
    return a.key != b.key ? a.key < b.key : a.offset < b.offset;
  });
  return flats;
}

// Calls f(i, j) for every run flats[i .. j) on one plane that holds
// polygons facing both ways (the only planes where surfaces can touch).
template <typename F>
void for_each_two_way_plane(const std::vector<Flat>& flats, double plane_eps, const F& f) {
  for (size_t i = 0; i < flats.size();) {
    size_t j = i + 1;
    while (j < flats.size() && flats[j].key == flats[i].key && flats[j].offset - flats[j - 1].offset <= plane_eps) ++j;
    bool both_ways = false;
    for (size_t k = i + 1; k < j; ++k) both_ways |= flats[k].flipped != flats[i].flipped;
    if (both_ways && !f(i, j)) return;
    i = j;
  }
}

double plane_tolerance(const Scene& scene) { return 1e-7 * std::max(scene.bounds().diagonal(), 1e-30); }

// Per flat, the flats it is in contact with: facing the other way on its
// plane, sharing more than `min_area` (or more than `min_share` of the
// smaller object's surface). A pair with a concave polygon whose boxes
// overlap is counted in `result.skipped`, and a partner only when
// `concave_touch`.
std::vector<std::vector<size_t>> find_partners(const Scene& scene, const std::vector<Flat>& flats, double min_area,
                                               double min_share, bool concave_touch, ContactSplit& result) {
  const double plane_eps = plane_tolerance(scene);
  std::vector<double> object_area(scene.objects.size() + 1, 0.0);
  for (const Polygon& p : scene.polygons)
    object_area.at(static_cast<size_t>(std::max(0, std::min<int>(p.object, static_cast<int>(scene.objects.size()))))) +=
        polygon_area(p.vertices);
  std::vector<std::vector<size_t>> partners(flats.size());
  size_t budget = 200'000'000;  // box tests: a column of a million tiles is no hang
  std::vector<size_t> group;
  for_each_two_way_plane(flats, plane_eps, [&](size_t i, size_t j) {
    group.clear();
    for (size_t k = i; k < j; ++k) group.push_back(k);
    std::sort(group.begin(), group.end(), [&](size_t a, size_t b) { return flats[a].lo_u < flats[b].lo_u; });
    for (size_t x = 0; x < group.size() && budget > 0; ++x) {
      const Flat& a = flats[group[x]];
      for (size_t y = x + 1; y < group.size() && flats[group[y]].lo_u < a.hi_u && budget > 0; ++y) {
        const Flat& b = flats[group[y]];
        --budget;
        if (a.flipped == b.flipped || b.lo_v >= a.hi_v || a.lo_v >= b.hi_v) continue;
        if (std::fabs(a.offset - b.offset) > plane_eps) continue;
        bool touch = false;
        if (!a.is_convex || !b.is_convex) {  // boxes overlap; not examined further
          ++result.skipped;
          touch = concave_touch;
        } else {
          const double sb = signed_area(b.points) > 0 ? 1.0 : -1.0;
          const Poly2 common = clip_inside(a.points, b.points, sb);
          if (!substantial(common, plane_eps)) continue;
          const double shared = std::fabs(signed_area(common)) / std::fabs(a.n[a.axis]);
          const double smaller = std::min(object_area[scene.polygons[a.polygon].object],
                                          object_area[scene.polygons[b.polygon].object]);
          touch = shared > min_area || (min_share > 0 && shared > min_share * smaller);
        }
        if (!touch) continue;
        partners[group[x]].push_back(group[y]);
        partners[group[y]].push_back(group[x]);
        ++result.pairs;
      }
    }
    return budget > 0;
  });
  return partners;
}

}  // namespace

ContactPlanes contact_planes(const Scene& scene) {
  ContactPlanes out;
  out.plane.assign(scene.polygons.size(), -1);
  out.partner_bounds.resize(scene.polygons.size());
  const std::vector<Flat> flats = sorted_flats(scene);
  ContactSplit counts;
  const auto partners = find_partners(scene, flats, -1.0, 0.0, true, counts);
  // A plane index per run of touching flats (partners lie on one plane).
  std::vector<int> plane_of(flats.size(), -1);
  int planes = 0;
  for (size_t k = 0; k < flats.size(); ++k) {
    if (partners[k].empty() || plane_of[k] >= 0) continue;
    std::vector<size_t> todo{k};
    plane_of[k] = planes;
    while (!todo.empty()) {
      const size_t x = todo.back();
      todo.pop_back();
      for (const size_t y : partners[x])
        if (plane_of[y] < 0) {
          plane_of[y] = planes;
          todo.push_back(y);
        }
    }
    ++planes;
  }
  for (size_t k = 0; k < flats.size(); ++k) {
    if (plane_of[k] < 0) continue;
    const size_t polygon = static_cast<size_t>(flats[k].polygon);
    out.plane[polygon] = plane_of[k];
    for (const size_t q : partners[k]) {
      Bounds b;
      for (const Vec3& v : scene.polygons[static_cast<size_t>(flats[q].polygon)].vertices) b.extend(v);
      out.partner_bounds[polygon].push_back(b);
    }
  }
  return out;
}

ContactSplit split_contacts(Scene& scene, double min_area, double min_share) {
  ContactSplit result;
  const double size = std::max(scene.bounds().diagonal(), 1e-30);
  const double plane_eps = plane_tolerance(scene);
  const std::vector<Flat> flats = sorted_flats(scene);
  // Partners of each polygon: the polygons it is in contact with (indices into flats).
  const auto partners = find_partners(scene, flats, min_area, min_share, false, result);
  if (result.pairs == 0) return result;

  // Each polygon in contact becomes its pieces, in its place.
  std::vector<std::vector<Polygon>> replaced(scene.polygons.size());
  for (size_t k = 0; k < flats.size(); ++k) {
    if (partners[k].empty()) continue;
    const Flat& f = flats[k];
    std::vector<Poly2> pieces{f.points};
    for (const size_t q : partners[k]) {
      std::vector<Poly2> next;
      for (const Poly2& x : pieces) {
        auto parts = split_by(x, flats[q], plane_eps);
        if (parts.empty()) next.push_back(x);
        for (auto& p : parts) next.push_back(std::move(p));
      }
      pieces = std::move(next);
    }
    if (pieces.size() < 2) continue;  // wholly in contact: it stays as it is
    const Polygon& original = scene.polygons[static_cast<size_t>(f.polygon)];
    const int ua = (f.axis + 1) % 3, va = (f.axis + 2) % 3;
    for (const Poly2& raw : pieces) {
      const Poly2 piece = simplified(raw, 1e-9 * size);
      Polygon p;
      p.material = original.material;
      p.object = original.object;
      for (const P2& q : piece) {
        Vec3 x;
        x[ua] = q.u;
        x[va] = q.v;
        x[f.axis] = (f.d - f.n[ua] * q.u - f.n[va] * q.v) / f.n[f.axis];
        p.vertices.push_back(x);
      }
      replaced[static_cast<size_t>(f.polygon)].push_back(std::move(p));
    }
    ++result.split;
    result.pieces += pieces.size();
  }
  std::vector<Polygon> polygons;
  polygons.reserve(scene.polygons.size() + result.pieces);
  for (size_t k = 0; k < scene.polygons.size(); ++k) {
    if (replaced[k].empty()) polygons.push_back(std::move(scene.polygons[k]));
    else for (Polygon& p : replaced[k]) polygons.push_back(std::move(p));
  }
  scene.polygons = std::move(polygons);
  return result;
}

}  // namespace mpath
