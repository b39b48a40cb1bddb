#include "tessellate.h"

#include <gtest/gtest.h>

#include <numbers>

#include "scene.h"

namespace mpath {
namespace {

Vec3 centroid(const std::vector<Vec3>& p) {
  Vec3 c;
  for (const Vec3& v : p) c += v;
  return c / static_cast<double>(p.size());
}

// Sum of area-weighted normals: zero for a closed surface.
Vec3 normal_sum(const PolygonList& polygons) {
  Vec3 s;
  for (const auto& p : polygons) s += newell_normal(p);
  return s;
}

double area(const PolygonList& polygons) {
  double a = 0;
  for (const auto& p : polygons) a += polygon_area(p);
  return a;
}

TEST(Tessellate, SphereIsClosedFacesOutwardAndApproachesItsArea) {
  const Vec3 c{1, 2, 3};
  const PolygonList sphere = tessellate_sphere(c, 2.0, 64, false);
  EXPECT_EQ(sphere.size(), 64u * 32u);
  for (const auto& p : sphere) EXPECT_GT(dot(newell_normal(p), centroid(p) - c), 0);
  EXPECT_LT(length(normal_sum(sphere)), 1e-9);
  // Inscribed polygons: a little less than 4 pi r^2 (error ~ (pi/n)^2).
  const double exact = 4 * std::numbers::pi * 4.0;
  EXPECT_LT(area(sphere), exact);
  EXPECT_GT(area(sphere), exact * (1 - 2 * std::pow(std::numbers::pi / 32, 2)));
  for (const auto& p : tessellate_sphere(c, 2.0, 16, true)) EXPECT_LT(dot(newell_normal(p), centroid(p) - c), 0);
}

TEST(Tessellate, ConeAndCylinderFaceAwayFromTheirAxis) {
  const Vec3 a{0, 0, 0}, b{0, 0, 2};
  for (const auto& p : tessellate_cone(a, 1.0, b, 0.5, 16, false)) {
    const Vec3 c = centroid(p);
    EXPECT_GT(dot(newell_normal(p), Vec3{c.x, c.y, 0}), 0);
  }
  const PolygonList cylinder = tessellate_cone(a, 1.0, b, 1.0, 64, false);
  EXPECT_NEAR(area(cylinder), 2 * std::numbers::pi * 2.0, 0.02);
  EXPECT_EQ(tessellate_cone(a, 1.0, b, 0.0, 8, false)[0].size(), 3u);  // apex: triangles
}

TEST(Tessellate, RingFacesItsNormalAndCoversTheAnnulus) {
  const PolygonList ring = tessellate_ring({0, 0, 1}, {0, 0, 2}, 0.5, 1.0, 128);
  for (const auto& p : ring) EXPECT_GT(newell_normal(p).z, 0);
  EXPECT_NEAR(area(ring), std::numbers::pi * (1.0 - 0.25), 0.002);
}

TEST(Tessellate, TorusAndPrismAreClosed) {
  EXPECT_LT(length(normal_sum(tessellate_torus({0, 0, 0}, {0, 1, 0}, 1.0, 2.0, 16, false))), 1e-9);
  // Unit square facing -z extruded by 1: the MGF example cube in the positive octant.
  const PolygonList cube = tessellate_prism({{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}}, 1.0);
  ASSERT_EQ(cube.size(), 6u);
  EXPECT_LT(length(normal_sum(cube)), 1e-12);
  for (const auto& p : cube) {
    EXPECT_NEAR(polygon_area(p), 1.0, 1e-12);
    EXPECT_GT(dot(newell_normal(p), centroid(p) - Vec3{0.5, 0.5, 0.5}), 0);
  }
  for (const auto& p : tessellate_prism({{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}}, -1.0))
    EXPECT_LT(dot(newell_normal(p), centroid(p) - Vec3{0.5, 0.5, -0.5}), 0);
}

}  // namespace
}  // namespace mpath
