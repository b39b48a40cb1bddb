#include "tessellate.h"

#include <algorithm>
#include <numbers>

#include "scene.h"

namespace mpath {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

std::vector<Vec3> oriented(std::vector<Vec3> p, bool flip) {
  if (flip) std::reverse(p.begin(), p.end());
  return p;
}

// Drops repeated corners (apexes of cones and sphere poles).
std::vector<Vec3> without_repeats(const std::vector<Vec3>& p) {
  std::vector<Vec3> out;
  for (const Vec3& v : p)
    if (out.empty() || !(v == out.back())) out.push_back(v);
  while (out.size() > 1 && out.front() == out.back()) out.pop_back();
  return out;
}

// Unit directions around `axis` at segments + 1 evenly spaced angles (the last equals the first).
std::vector<Vec3> circle(const Vec3& axis, int segments) {
  Vec3 u, v;
  orthonormal_basis(normalize(axis), u, v);
  std::vector<Vec3> d;
  for (int i = 0; i <= segments; ++i) {
    const double a = kTwoPi * (i % segments) / segments;
    d.push_back(u * std::cos(a) + v * std::sin(a));
  }
  return d;
}

}  // namespace

PolygonList tessellate_cone(Vec3 c1, double r1, Vec3 c2, double r2, int segments, bool inward) {
  const std::vector<Vec3> d = circle(c2 - c1, segments);
  PolygonList out;
  for (int i = 0; i < segments; ++i) {
    // Counter-clockwise seen from outside: bottom edge forward, top edge back.
    std::vector<Vec3> quad{c1 + d[i] * r1, c1 + d[i + 1] * r1, c2 + d[i + 1] * r2, c2 + d[i] * r2};
    out.push_back(oriented(without_repeats(quad), inward));
  }
  return out;
}

PolygonList tessellate_sphere(Vec3 c, double r, int segments, bool inward) {
  const int rings = std::max(2, segments / 2);
  PolygonList out;
  auto point = [&](int ring, int seg) {
    const double theta = std::numbers::pi * ring / rings;
    const double phi = kTwoPi * seg / segments;
    return c + Vec3{std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)} * r;
  };
  for (int j = 0; j < rings; ++j)
    for (int i = 0; i < segments; ++i) {
      std::vector<Vec3> quad{point(j, i), point(j + 1, i), point(j + 1, i + 1), point(j, i + 1)};
      out.push_back(oriented(without_repeats(quad), inward));
    }
  return out;
}

PolygonList tessellate_ring(Vec3 c, Vec3 normal, double r_in, double r_out, int segments) {
  const std::vector<Vec3> d = circle(normal, segments);
  PolygonList out;
  for (int i = 0; i < segments; ++i) {
    out.push_back(without_repeats({c + d[i] * r_in, c + d[i] * r_out, c + d[i + 1] * r_out, c + d[i + 1] * r_in}));
  }
  return out;
}

PolygonList tessellate_torus(Vec3 c, Vec3 normal, double r_in, double r_out, int segments, bool inward) {
  const Vec3 n = normalize(normal);
  Vec3 u, v;
  orthonormal_basis(n, u, v);
  const double major = 0.5 * (r_in + r_out), minor = 0.5 * (r_out - r_in);
  const int tube = std::max(3, segments / 2);
  auto point = [&](int i, int j) {
    const double a = kTwoPi * i / segments, b = kTwoPi * j / tube;
    const Vec3 radial = u * std::cos(a) + v * std::sin(a);
    return c + radial * (major + minor * std::cos(b)) + n * (minor * std::sin(b));
  };
  PolygonList out;
  for (int i = 0; i < segments; ++i)
    for (int j = 0; j < tube; ++j) {
      std::vector<Vec3> quad{point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1)};
      out.push_back(oriented(quad, inward));
    }
  return out;
}

PolygonList tessellate_prism(const std::vector<Vec3>& base, double length) {
  const Vec3 n = normalize(newell_normal(base));
  const Vec3 h = n * (-length);
  PolygonList out;
  out.push_back(base);
  std::vector<Vec3> top;
  for (auto it = base.rbegin(); it != base.rend(); ++it) top.push_back(*it + h);
  out.push_back(top);
  for (size_t i = 0; i < base.size(); ++i) {
    const Vec3 a = base[i], b = base[(i + 1) % base.size()];
    out.push_back({a, a + h, b + h, b});
  }
  return out;
}

}  // namespace mpath
