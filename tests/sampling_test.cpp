#include "sampling.h"

#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace mpath
