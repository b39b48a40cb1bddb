#include "transform.h"

#include <cmath>
#include <numbers>

namespace mpath {

Vec3 Transform::point(const Vec3& p) const {
  Vec3 r;
  for (int i = 0; i < 3; ++i) r[i] = m[i][0] * p.x + m[i][1] * p.y + m[i][2] * p.z + m[i][3];
  return r;
}

Vec3 Transform::vector(const Vec3& v) const {
  Vec3 r;
  for (int i = 0; i < 3; ++i) r[i] = m[i][0] * v.x + m[i][1] * v.y + m[i][2] * v.z;
  return r;
}

double Transform::determinant() const {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

double Transform::scale() const { return std::cbrt(std::fabs(determinant())); }

Transform Transform::after(const Transform& first) const {
  Transform r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) {
      double s = j == 3 ? m[i][3] : 0.0;
      for (int k = 0; k < 3; ++k) s += m[i][k] * first.m[k][j];
      r.m[i][j] = s;
    }
  }
  return r;
}

Transform Transform::translate(const Vec3& t) {
  Transform r;
  for (int i = 0; i < 3; ++i) r.m[i][3] = t[i];
  return r;
}

Transform Transform::rotate(int axis, double degrees) {
  const double a = degrees * std::numbers::pi / 180.0, c = std::cos(a), s = std::sin(a);
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  Transform r;
  r.m[u][u] = c;
  r.m[u][v] = -s;
  r.m[v][u] = s;
  r.m[v][v] = c;
  return r;
}

Transform Transform::scaling(double s) {
  Transform r;
  for (int i = 0; i < 3; ++i) r.m[i][i] = s;
  return r;
}

Transform Transform::mirror(int axis) {
  Transform r;
  r.m[axis][axis] = -1;
  return r;
}

}  // namespace mpath
