#include "tracer.h"

#include <gtest/gtest.h>

#include "test_util.h"

namespace mpath {
namespace {

Scene stacked_squares(int count) {
  Scene s;
  const int m = test::add_material(s, "m", 0.5, 0.0);
  for (int i = 0; i < count; ++i) {
    const int o = test::add_object(s, "square");
    const double z = i;
    test::add_quad(s, {0, 0, z}, {1, 0, z}, {1, 1, z}, {0, 1, z}, m, o);
  }
  return s;
}

TEST(Tracer, FindsEveryHitAlongALineSortedByDistance) {
  const PatchMesh mesh = build_mesh(stacked_squares(5), 1.0);
  const Tracer tracer(mesh);
  std::vector<LineHit> hits;
  tracer.all_hits({0.3, 0.4, -1}, normalize(Vec3{0.01, 0.02, 1}), 100, hits);
  ASSERT_EQ(hits.size(), 5u);
  for (size_t i = 0; i < hits.size(); ++i) {
    EXPECT_EQ(hits[i].patch, static_cast<int>(i));
    if (i) {
      EXPECT_LT(hits[i - 1].t, hits[i].t);
    }
  }
  const NearestHit n = tracer.nearest({0.5, 0.5, 10}, {0, 0, -1}, 0, 100);
  EXPECT_EQ(n.patch, 4);
  EXPECT_DOUBLE_EQ(n.t, 6.0);  // recomputed from the plane in double precision
}

TEST(Tracer, CountsACrossingOnASharedEdgeOrAQuadDiagonalOnce) {
  // A 2 x 1 grid of patches: a line through the shared edge, one through a diagonal.
  Scene s;
  const int m = test::add_material(s, "m", 0.5, 0.0);
  test::add_quad(s, {0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0, 1, 0}, m, test::add_object(s, "o"));
  const PatchMesh mesh = build_mesh(s, 1.0);
  ASSERT_EQ(mesh.patches.size(), 2u);
  const Tracer tracer(mesh);
  std::vector<LineHit> hits;
  tracer.all_hits({1.0, 0.5, 1}, {0, 0, -1}, 10, hits);
  EXPECT_EQ(hits.size(), 1u);
  tracer.all_hits({0.5, 0.5, 1}, {0, 0, -1}, 10, hits);
  EXPECT_EQ(hits.size(), 1u);
  tracer.all_hits({0.0, 0.0, 1}, {0, 0, -1}, 10, hits);  // a corner
  EXPECT_LE(hits.size(), 1u);
}

TEST(Tracer, ALineLeavingAPatchSeesASurfaceTouchingIt) {
  // A block bottom lies on the floor: a line from the bottom, downwards, meets the floor at 0.
  Scene s;
  const int m = test::add_material(s, "m", 0.5, 0.0);
  test::add_quad(s, {0, 0, 0}, {0, 0, 2}, {2, 0, 2}, {2, 0, 0}, m, test::add_object(s, "floor"));  // faces +y
  test::add_quad(s, {0.5, 0, 0.5}, {1.5, 0, 0.5}, {1.5, 0, 1.5}, {0.5, 0, 1.5}, m, test::add_object(s, "bottom"));  // faces -y
  const PatchMesh mesh = build_mesh(s, 10.0);
  const Tracer tracer(mesh);
  const NearestHit down = tracer.nearest_from(1, {1, 0, 1}, normalize(Vec3{0.1, -1, 0}), 10);
  EXPECT_EQ(down.patch, 0);
  EXPECT_NEAR(down.t, 0.0, 1e-6);
  // From the floor, upwards, outside the block: nothing; under it: the block.
  EXPECT_EQ(tracer.nearest_from(0, {0.2, 0, 0.2}, {0, 1, 0}, 10).patch, -1);
  EXPECT_EQ(tracer.nearest_from(0, {1, 0, 1}, {0, 1, 0}, 10).patch, 1);
}

}  // namespace
}  // namespace mpath
