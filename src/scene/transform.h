// Affine transforms of MGF's xf entity: rotations, uniform scale, mirrors and
// translations, composed in the order given.
#pragma once

#include <array>

#include "vec3.h"

namespace mpath {

struct Transform {
  std::array<std::array<double, 4>, 3> m{{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}};

  Vec3 point(const Vec3& p) const;
  Vec3 vector(const Vec3& v) const;
  double determinant() const;
  // Length scale of a similarity transform (cube root of |det|).
  double scale() const;
  // The transform that applies `first`, then `*this`.
  Transform after(const Transform& first) const;

  static Transform translate(const Vec3& t);
  static Transform rotate(int axis, double degrees);
  static Transform scaling(double s);
  static Transform mirror(int axis);
};

}  // namespace mpath
