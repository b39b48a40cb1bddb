#include "mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iterator>
#include <random>

#include "error.h"
#include "test_util.h"

namespace mpath {
namespace {

Scene one_polygon(std::vector<Vec3> vertices, bool two_sided = false) {
  Scene s;
  test::add_material(s, "m", 0.5, 0.0, two_sided);
  test::add_object(s, "o");
  s.polygons.push_back(Polygon{std::move(vertices), 0, 0});
  return s;
}

double total_area(const PatchMesh& m) {
  double a = 0;
  for (const Patch& p : m.patches) a += p.area;
  return a;
}

TEST(Mesh, KeepsAPolygonAlreadySmallEnoughAsOnePatch) {
  const PatchMesh m = build_mesh(one_polygon({{0, 0, 0}, {1, 0, 0}, {1.2, 1, 0}, {0, 1, 0}}), 2.0);
  ASSERT_EQ(m.patches.size(), 1u);
  EXPECT_FALSE(m.patches[0].is_triangle());
  EXPECT_NEAR(m.patches[0].area, 1.1, 1e-12);
  EXPECT_NEAR(m.patches[0].normal.z, 1.0, 1e-12);
}

TEST(Mesh, SplitsAParallelogramIntoAGridWithinTheMaximumArea) {
  const PatchMesh m = build_mesh(one_polygon({{0, 0, 0}, {3, 0, 0}, {3.5, 2, 0}, {0.5, 2, 0}}), 0.25);
  // Edges of length 3 and 2.06 in steps of at most sqrt(0.25): 6 x 5 cells of area 0.2.
  EXPECT_EQ(m.patches.size(), 6u * 5u);
  for (const Patch& p : m.patches) {
    EXPECT_LE(p.area, 0.25 + 1e-12);
    EXPECT_NEAR(p.normal.z, 1.0, 1e-12);
  }
  EXPECT_NEAR(total_area(m), 6.0, 1e-9);
}

TEST(Mesh, SplitsOtherPolygonsIntoTrianglesWithinTheMaximumArea) {
  const PatchMesh m = build_mesh(one_polygon({{0, 0, 0}, {4, 0, 0}, {0, 0, 3}}), 0.1);
  EXPECT_GE(m.patches.size(), 60u);
  for (const Patch& p : m.patches) {
    EXPECT_TRUE(p.is_triangle());
    EXPECT_LE(p.area, 0.1 * (1 + 1e-9));
    EXPECT_NEAR(p.normal.y, -1.0, 1e-12);  // counter-clockwise seen from -y
  }
  EXPECT_NEAR(total_area(m), 6.0, 1e-9);
}

TEST(Mesh, TriangulatesAConcavePolygonWithoutChangingItsArea) {
  const std::vector<Vec3> l_shape{{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}, {1, 2, 0}, {0, 2, 0}};
  const auto triangles = triangulate(l_shape);
  ASSERT_EQ(triangles.size(), 4u);
  double area = 0;
  for (const auto& t : triangles) {
    const Vec3 n = cross(l_shape[t[1]] - l_shape[t[0]], l_shape[t[2]] - l_shape[t[0]]);
    EXPECT_GT(n.z, 0);  // same orientation as the polygon
    area += 0.5 * length(n);
  }
  EXPECT_NEAR(area, 3.0, 1e-12);
  const PatchMesh m = build_mesh(one_polygon(l_shape), 10.0);
  EXPECT_EQ(m.patches.size(), 4u);
}

// A wall with a window cut as one polygon running to the hole and back along
// a seam (a repeated corner), as RenderPark's office3 has: the patches cover
// the wall less the window, none of them without area (a sliver along the
// seam once made a patch of area 0 and radiosity NaN), none in the window.
TEST(Mesh, TriangulatesAPolygonWithAKeyholeSeam) {
  const std::vector<Vec3> wall{{30, 15.5, 30}, {-30, 15.5, 30}, {-30, 51, 30}, {30, 51, 30}, {30, 26, 30},
                               {23.5, 26, 30}, {23.5, 43, 30}, {-23.5, 43, 30}, {-23.5, 26, 30}, {30, 26, 30}};
  const double expected = 60 * 35.5 - 47 * 17;
  for (const double max_area : {1e4, 40.0}) {
    const PatchMesh m = build_mesh(one_polygon(wall), max_area);
    EXPECT_NEAR(total_area(m), expected, 1e-9 * expected) << max_area;
    for (const Patch& p : m.patches) {
      EXPECT_GT(p.area, 1e-9) << max_area;
      Vec3 c;
      const int n = p.is_triangle() ? 3 : 4;
      for (int k = 0; k < n; ++k) c += m.vertices[p.v[k]];
      c = c / n;
      EXPECT_FALSE(c.x > -23.5 && c.x < 23.5 && c.y > 26 && c.y < 43) << "a patch in the window at " << c.x << ", "
                                                                       << c.y;
    }
  }
}

TEST(Mesh, DropsAndCountsDegeneratePolygons) {
  Scene s = one_polygon({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}});  // collinear
  s.polygons.push_back(Polygon{{{0, 0, 0}, {0, 0, 0}, {1, 1, 0}}, 0, 0});  // repeated corner
  s.polygons.push_back(Polygon{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, 0, 0});
  const PatchMesh m = build_mesh(s, 1.0);
  EXPECT_EQ(m.dropped_polygons, 2u);
  EXPECT_EQ(m.patches.size(), 1u);
}

TEST(Mesh, GivesTwoSidedPatchesABackFace) {
  const PatchMesh one = build_mesh(one_polygon({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}), 0.5);
  EXPECT_EQ(one.face_count(), one.patches.size());
  EXPECT_EQ(one.patch_faces[0][1], -1);
  const PatchMesh two = build_mesh(one_polygon({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, true), 0.5);
  EXPECT_EQ(two.face_count(), 2 * two.patches.size());
  const int back = two.patch_faces[0][1];
  EXPECT_EQ(two.face_side[back], 1);
  EXPECT_NEAR(two.face_normal(back).z, -1.0, 1e-12);
}

TEST(Mesh, RefusesAPatchSizeThatWouldFillMemory) {
  try {
    build_mesh(test::furnace_scene(0.5, 1.0), 1e-9);
    FAIL() << "a patch size giving ~1e10 patches must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'mesh.max_patch_area': 1e-09 gives about"), std::string::npos) << e.what();
  }
}

TEST(Mesh, AutomaticPatchAreaFollowsTheSceneSize) {
  const Scene s = test::furnace_scene(0.5, 1.0);
  const PatchMesh m = build_mesh(s, 0.0);
  EXPECT_NEAR(m.max_patch_area, s.bounds().surface_area() / 2000.0, 1e-12);
}

}  // namespace
}  // namespace mpath

namespace mpath {
namespace {

// A scene whose every polygon is degenerate (collinear or repeated
// vertices) is an error naming the file, not an internal check.
TEST(Mesh, ASceneOfDegeneratePolygonsOnlyIsAnError) {
  Scene scene;
  scene.file = "flat.obj";
  const int m = test::add_material(scene, "light", 0.5, 1.0);
  const int o = test::add_object(scene, "line");
  scene.polygons.push_back({{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, m, o});
  scene.polygons.push_back({{{0, 0, 0}, {0, 0, 0}, {0, 0, 1}}, m, o});
  for (const double area : {0.0, 0.1}) {
    try {
      build_mesh(scene, area);
      ADD_FAILURE() << area;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("flat.obj: no polygon of the scene has an area (all 2 are degenerate"),
                std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace mpath

namespace mpath {
namespace {

// Bounds::extend gives what std::fmin and std::fmax give (it does their
// work inline): random values, zeros of both signs, infinities and NaNs
// (which neither lets into a bound), many seeds. Equal values compare
// equal: which zero fmin(+0, -0) gives is left open by C, and GCC may swap
// the operands of the call.
TEST(Bounds, ExtendGivesWhatFminAndFmaxGive) {
  const double special[] = {0.0, -0.0, 0.0, -0.0, 1.0, -1.0, INFINITY, -INFINITY, NAN, 1e-300, -1e300};
  for (unsigned seed = 1; seed <= 20; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> value(-10.0, 10.0);
    Bounds b;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int k = 0; k < 200; ++k) {
      Vec3 p;
      // Odd seeds: special values only (zeros of both signs meeting a bound at zero); even: some among random ones.
      for (int i = 0; i < 3; ++i)
        p[i] = seed % 2 == 1 || rng() % 4 == 0 ? special[rng() % std::size(special)] : value(rng);
      if (seed % 2 == 1 && k % 50 == 0) b = Bounds{}, lo[0] = lo[1] = lo[2] = INFINITY, hi[0] = hi[1] = hi[2] = -INFINITY;
      b.extend(p);
      for (int i = 0; i < 3; ++i) {
        lo[i] = std::fmin(lo[i], p[i]);
        hi[i] = std::fmax(hi[i], p[i]);
        ASSERT_TRUE(b.lo[i] == lo[i]) << "seed " << seed << " step " << k << ": " << b.lo[i] << " against " << lo[i];
        ASSERT_TRUE(b.hi[i] == hi[i]) << "seed " << seed << " step " << k << ": " << b.hi[i] << " against " << hi[i];
      }
    }
  }
}

}  // namespace
}  // namespace mpath
