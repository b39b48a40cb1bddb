// Small double-precision 3-vector used by scene, mesh and sampling code.
#pragma once

#include <array>
#include <cmath>

namespace mpath {

// A colour or per-channel quantity (red, green, blue).
using Rgb = std::array<double, 3>;

struct Vec3 {
  double x = 0, y = 0, z = 0;

  constexpr Vec3() = default;
  constexpr Vec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}

  constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  constexpr Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
  constexpr Vec3 operator/(double s) const { return {x / s, y / s, z / s}; }
  Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
  constexpr bool operator==(const Vec3& o) const = default;
};

constexpr Vec3 operator*(double s, const Vec3& v) { return v * s; }
constexpr double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(const Vec3& v) { return std::sqrt(dot(v, v)); }
inline Vec3 normalize(const Vec3& v) { return v / length(v); }
inline bool is_finite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Two unit vectors completing n to an orthonormal frame (Duff et al. 2017).
inline void orthonormal_basis(const Vec3& n, Vec3& t, Vec3& b) {
  const double sign = std::copysign(1.0, n.z);
  const double a = -1.0 / (sign + n.z);
  const double c = n.x * n.y * a;
  t = {1.0 + sign * n.x * n.x * a, sign * c, -sign * n.x};
  b = {c, sign + n.y * n.y * a, -n.y};
}

struct Bounds {
  Vec3 lo{INFINITY, INFINITY, INFINITY};
  Vec3 hi{-INFINITY, -INFINITY, -INFINITY};

  // std::fmin and std::fmax, inline (as calls into libm they took 5 % of a
  // solve's start): a NaN gives the other operand, as theirs do, and of
  // equal values p is taken (which zero fmin(+0, -0) gives, C leaves open).
  // The bounds are never NaN unless every point was.
  void extend(const Vec3& p) {
    for (int i = 0; i < 3; ++i) {
      lo[i] = lo[i] < p[i] || p[i] != p[i] ? lo[i] : p[i];
      hi[i] = hi[i] > p[i] || p[i] != p[i] ? hi[i] : p[i];
    }
  }
  bool empty() const { return !(lo.x <= hi.x); }
  Vec3 size() const { return hi - lo; }
  Vec3 center() const { return (lo + hi) * 0.5; }
  double diagonal() const { return length(size()); }
  double surface_area() const {
    const Vec3 s = size();
    return 2.0 * (s.x * s.y + s.y * s.z + s.z * s.x);
  }
};

}  // namespace mpath
