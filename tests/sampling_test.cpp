#include "sampling.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "test_util.h"
#include "tracer.h"

namespace mpath {
namespace {

TEST(Sampling, CosineDirectionsHaveMeanCosineTwoThirds) {
  Rng rng = make_rng(3, 0, 0);
  const Vec3 n = normalize(Vec3{1, 2, 3});
  const int count = 200'000;
  double sum = 0;
  for (int i = 0; i < count; ++i) {
    const Vec3 d = cosine_direction(n, rng);
    ASSERT_NEAR(length(d), 1.0, 1e-12);
    ASSERT_GE(dot(d, n), 0);
    sum += dot(d, n);
  }
  // cos theta has variance 1/2 - 4/9 = 1/18 under the cosine density.
  EXPECT_NEAR(sum / count, 2.0 / 3.0, 4 * std::sqrt(1.0 / 18 / count));
}

TEST(Sampling, RadicalInverseMirrorsDigits) {
  EXPECT_DOUBLE_EQ(radical_inverse(1, 2), 0.5);
  EXPECT_DOUBLE_EQ(radical_inverse(6, 2), 0.375);  // 110 -> 0.011
  EXPECT_NEAR(radical_inverse(5, 3), 7.0 / 9.0, 1e-15);  // 12 -> 0.21
  // The specialised bases give exactly the digit loop of any other base.
  for (unsigned base : {2u, 3u, 5u, 7u})
    for (uint64_t i : {0ull, 1ull, 2186ull, 2187ull, 12345ull, 4'000'000ull, 4'294'967'295ull, (1ull << 40) + 977ull}) {
      double f = 1.0 / base, expected = 0;
      for (uint64_t k = i; k > 0; k /= base, f /= base) expected += f * static_cast<double>(k % base);
      if (base == 2) {
        EXPECT_DOUBLE_EQ(radical_inverse(i, base), expected) << i;
      }
      else EXPECT_NEAR(radical_inverse(i, base), expected, 1e-15) << base << " " << i;
    }
}

// A square of area A inside a box of surface S is crossed by a uniform line
// through the box with probability 2A/S (Cauchy-Crofton).
TEST(Sampling, GlobalLinesCrossAFaceWithProbabilityTwoAOverS) {
  Scene scene;
  const int m = test::add_material(scene, "m", 0.5, 0.0);
  const int o = test::add_object(scene, "o");
  test::add_quad(scene, {0.2, 0.3, 0.5}, {0.7, 0.3, 0.5}, {0.7, 0.6, 0.6}, {0.2, 0.6, 0.6}, m, o);
  const PatchMesh mesh = build_mesh(scene, 1.0);
  const Tracer tracer(mesh);
  Bounds box;
  box.extend({0, 0, 0});
  box.extend({1, 1.5, 2});
  const BoxLineSampler sampler(box);
  const double p = 2 * mesh.patches[0].area / box.surface_area();
  const int lines = 400'000;
  auto crossings = [&](const std::string& sequence, unsigned pass) {
    const LineSequence points(sequence, 5, pass);
    Rng rng = make_rng(5, 0, pass);
    std::vector<LineHit> hits;
    int k = 0;
    for (int i = 0; i < lines; ++i) {
      double u[4];
      points.point(i, rng, u);
      const GlobalLine line = sampler.sample(u);
      tracer.all_hits(line.org, line.dir, line.length, hits);
      k += static_cast<int>(hits.size());
    }
    return k;
  };
  const double sigma = std::sqrt(lines * p * (1 - p));
  EXPECT_NEAR(crossings("random", 1), lines * p, 4 * sigma);
  // Halton lines: unbiased too, and over several random shifts their counts
  // vary less than independent lines' binomial counts.
  double sum = 0, sum2 = 0;
  const int shifts = 8;
  for (int s = 0; s < shifts; ++s) {
    const double k = crossings("halton", 10 + s);
    sum += k;
    sum2 += k * k;
  }
  const double mean = sum / shifts, var = sum2 / shifts - mean * mean;
  EXPECT_NEAR(mean, lines * p, 4 * sigma / std::sqrt(shifts));
  EXPECT_LT(var, 0.5 * sigma * sigma);
}

// A patch's sampler gives exactly the points and directions of
// uniform_point and cosine_direction, on triangles and on quads split
// unevenly, and a global line's direction is cosine_direction's about its
// face's inward normal.
// Every index of [0, n) once, and consecutive outputs as far apart as in a
// random permutation: for independent uniform X, Y in [0, n) the mean of
// |X - Y| is n / 3 (its standard deviation about 0.24 n, so the mean of
// n - 1 of them is n / 3 within 0.24 n / sqrt(n - 1), a few parts in a
// thousand at n = 65,536; the test allows 3 %). Sequential indices would give 1.
TEST(Sampling, IndexPermutationIsABijectionThatScattersNeighbours) {
  for (const uint64_t n : {1ull, 2ull, 3ull, 5ull, 64ull, 1000ull, 65536ull, 65537ull, 100003ull}) {
    Rng keys = make_rng(7, 0, n);
    const IndexPermutation order(n, keys);
    std::vector<uint8_t> seen(n, 0);
    double gap = 0;
    uint64_t previous = 0;
    for (uint64_t k = 0; k < n; ++k) {
      const uint64_t i = order(k);
      ASSERT_LT(i, n) << "n " << n;
      ASSERT_EQ(seen[i], 0) << "n " << n << ": index " << i << " twice";
      seen[i] = 1;
      if (k > 0) gap += std::fabs(static_cast<double>(i) - static_cast<double>(previous));
      previous = i;
    }
    if (n >= 65536) {
      EXPECT_NEAR(gap / static_cast<double>(n - 1), static_cast<double>(n) / 3, 0.03 * static_cast<double>(n) / 3)
          << "n " << n;
    }
  }
  // Other keys, another order.
  Rng a = make_rng(1, 0, 0), b = make_rng(2, 0, 0);
  const IndexPermutation first(1000, a), second(1000, b);
  int same = 0;
  for (uint64_t k = 0; k < 1000; ++k) same += first(k) == second(k);
  EXPECT_LT(same, 10);  // about 1 expected
}

TEST(Sampling, PatchSamplerGivesTheSamePointsAndDirections) {
  Rng rng = make_rng(11, 0, 0);
  Scene scene;
  const int m = test::add_material(scene, "m", 0.5, 0.0);
  const int o = test::add_object(scene, "o");
  for (int i = 0; i < 20; ++i) {
    const Vec3 c{uniform(rng), uniform(rng), uniform(rng)};
    const Vec3 u = normalize(Vec3{uniform(rng) - 0.5, uniform(rng) - 0.5, uniform(rng) - 0.5});
    const Vec3 v = normalize(cross(u, Vec3{0.3, 0.9, -0.2}));
    const double a = 0.1 + uniform(rng), b = 0.1 + uniform(rng), shrink = 0.2 + 0.8 * uniform(rng);
    if (i % 3 == 0)
      scene.polygons.push_back(Polygon{{c, c + u * a, c + v * b}, m, o});
    else  // a trapezoid: its two triangles of different areas
      test::add_quad(scene, c, c + u * a, c + u * (a * shrink) + v * b, c + v * b, m, o);
  }
  const PatchMesh mesh = build_mesh(scene, 1e9);
  bool triangles = false, quads = false;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const int face = static_cast<int>(f);
    const Patch& patch = mesh.patches[mesh.face_patch[face]];
    (patch.is_triangle() ? triangles : quads) = true;
    const PatchSampler sampler(mesh, patch, mesh.face_normal(face));
    for (int k = 0; k < 200; ++k) {
      const double r[4] = {uniform(rng), uniform(rng), uniform(rng), uniform(rng)};
      const Vec3 p = sampler.point(r[0], r[1]), q = uniform_point(mesh, patch, r[0], r[1]);
      ASSERT_TRUE(p.x == q.x && p.y == q.y && p.z == q.z) << f << " " << k;
      const Vec3 d = sampler.direction(r[2], r[3]), e = cosine_direction(mesh.face_normal(face), r[2], r[3]);
      ASSERT_TRUE(d.x == e.x && d.y == e.y && d.z == e.z) << f << " " << k;
    }
  }
  EXPECT_TRUE(triangles && quads);

  Bounds box;
  box.extend({-1, 0, 2});
  box.extend({3, 0.5, 4});
  const BoxLineSampler lines(box);
  for (int k = 0; k < 2000; ++k) {
    const double r[4] = {uniform(rng), uniform(rng), uniform(rng), uniform(rng)};
    const GlobalLine line = lines.sample(r);
    int axis = -1;  // the face the line starts on: it stands a hair outside the box there
    double outside = 0;
    for (int i = 0; i < 3; ++i) {
      const double d = std::max(box.lo[i] - line.org[i], line.org[i] - box.hi[i]);
      if (d > outside) {
        outside = d;
        axis = i;
      }
    }
    ASSERT_GE(axis, 0);
    Vec3 inward;
    inward[axis] = line.dir[axis] > 0 ? 1.0 : -1.0;
    const Vec3 e = cosine_direction(inward, r[2], r[3]);
    ASSERT_TRUE(line.dir.x == e.x && line.dir.y == e.y && line.dir.z == e.z) << k;
  }
}

}  // namespace
}  // namespace mpath
