#include "transform.h"

#include <gtest/gtest.h>

namespace mpath {
namespace {

void expect_near(const Vec3& a, const Vec3& b) {
  EXPECT_NEAR(a.x, b.x, 1e-12);
  EXPECT_NEAR(a.y, b.y, 1e-12);
  EXPECT_NEAR(a.z, b.z, 1e-12);
}

TEST(Transform, RotatesCounterClockwiseAboutEachAxis) {
  expect_near(Transform::rotate(2, 90).point({1, 0, 0}), {0, 1, 0});
  expect_near(Transform::rotate(0, 90).point({0, 1, 0}), {0, 0, 1});
  expect_near(Transform::rotate(1, 90).point({0, 0, 1}), {1, 0, 0});
}

TEST(Transform, ComposesInTheOrderApplied) {
  const Transform t = Transform::translate({1, 0, 0}).after(Transform::rotate(2, 90));
  expect_near(t.point({1, 0, 0}), {1, 1, 0});  // rotate first, then translate
  EXPECT_NEAR(Transform::scaling(2).scale(), 2.0, 1e-12);
  EXPECT_LT(Transform::mirror(0).determinant(), 0);
  expect_near(Transform::translate({5, 5, 5}).vector({1, 2, 3}), {1, 2, 3});
}

}  // namespace
}  // namespace mpath
