#include "nearest_point.h"

#include <gtest/gtest.h>

#include <random>

namespace mpath {
namespace {

// The linear scan NearestPoint must agree with exactly: the first of the
// least squared distances among the points `accept` takes.
template <typename Accept>
int scan(const std::vector<Vec3>& points, const Vec3& q, const Accept& accept) {
  double best = INFINITY;
  int found = -1;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!accept(static_cast<int>(i))) continue;
    const Vec3 d = points[i] - q;
    if (dot(d, d) < best) {
      best = dot(d, d);
      found = static_cast<int>(i);
    }
  }
  return found;
}

// Points as a polygon's patch centres lie: on a grid in a plane (many at
// equal distances from a query on the grid, and repeated points), a line,
// or scattered in space; planes in every orientation, axis-aligned or not.
std::vector<Vec3> layout(std::mt19937& rng, int kind, int n) {
  std::uniform_real_distribution<double> u(-1, 1);
  const Vec3 o{u(rng) * 10, u(rng) * 10, u(rng) * 10};
  Vec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)};
  if (rng() % 2) a = Vec3{1, 0, 0}, b = Vec3{0, 0, 0.5};  // an axis-aligned wall (constant y)
  std::vector<Vec3> p;
  const int side = std::max(1, static_cast<int>(std::sqrt(n)));
  for (int i = 0; i < n; ++i) switch (kind) {
      case 0: p.push_back(o + a * (i % side) + b * (i / side)); break;      // a grid
      case 1: p.push_back(o + a * u(rng) + b * u(rng)); break;              // scattered in a plane
      case 2: p.push_back(o + a * (0.1 * (i % 7))); break;                  // a line, with repeats
      default: p.push_back(o + Vec3{u(rng), u(rng), u(rng)}); break;        // in space
    }
  return p;
}

TEST(NearestPoint, AgreesWithALinearScanOnManyLayoutsAndSeeds) {
  int compared = 0, ties = 0;
  for (unsigned seed = 1; seed <= 60; ++seed) {
    std::mt19937 rng(seed);
    for (int kind = 0; kind < 4; ++kind) {
      const int n = 1 + static_cast<int>(rng() % 400);
      const std::vector<Vec3> points = layout(rng, kind, n);
      const NearestPoint index(points);
      ASSERT_EQ(index.size(), points.size());
      std::vector<bool> allowed(points.size());
      for (size_t i = 0; i < allowed.size(); ++i) allowed[i] = rng() % 3 != 0;
      const auto some = [&](int i) { return allowed[static_cast<size_t>(i)]; };
      const auto all = [](int) { return true; };
      const auto none = [](int) { return false; };
      for (int k = 0; k < 50; ++k) {
        // Queries at the points themselves (ties on a grid) and near them.
        Vec3 q = points[rng() % points.size()];
        if (k % 2) q = q + Vec3{0.3, -0.2, 0.1} * (static_cast<double>(rng() % 5) - 2.0);
        for (int which = 0; which < 2; ++which) {
          const int expected = which == 0 ? scan(points, q, all) : scan(points, q, some);
          const int got = which == 0 ? index.nearest(q, all) : index.nearest(q, some);
          ASSERT_EQ(got, expected) << "seed " << seed << " layout " << kind << " query " << k;
          if (expected >= 0) {
            const Vec3 d = points[static_cast<size_t>(expected)] - q;
            for (size_t i = 0; i < static_cast<size_t>(expected); ++i) {
              const Vec3 e = points[i] - q;
              ties += dot(e, e) == dot(d, d);
            }
          }
          ++compared;
        }
        EXPECT_EQ(index.nearest(q, none), -1);
      }
    }
  }
  EXPECT_EQ(compared, 60 * 4 * 50 * 2);
  EXPECT_GT(ties, 100) << "the layouts should give equal distances, where the order decides";
}

TEST(NearestPoint, NaNAndInfiniteCoordinatesAnswerAsTheScanDoes) {
  const std::vector<Vec3> points = {{NAN, 0, 0}, {1, 0, 0}, {INFINITY, 0, 0}, {2, 0, 0}, {-INFINITY, 0, 0}};
  const NearestPoint index(points);
  const auto all = [](int) { return true; };
  for (const Vec3 q : {Vec3{0, 0, 0}, Vec3{1.6, 0, 0}, Vec3{5, 0, 0}, Vec3{-5, 0, 0}})
    EXPECT_EQ(index.nearest(q, all), scan(points, q, all));
  const std::vector<Vec3> nowhere = {{NAN, NAN, NAN}};
  EXPECT_EQ(NearestPoint(nowhere).nearest(Vec3{0, 0, 0}, all), -1);
  EXPECT_EQ(NearestPoint({}).nearest(Vec3{0, 0, 0}, all), -1);
}

}  // namespace
}  // namespace mpath
