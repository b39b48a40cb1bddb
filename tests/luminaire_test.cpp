// Point sources ([[light]]): intensity distributions from IESNA LM-63 files,
// their flux and sampling against analytic integrals, and the first shot and
// the sensors of a lit room.
#include "luminaire.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "error.h"
#include "first_shot.h"
#include "photometry.h"
#include "test_util.h"

namespace mpath {
namespace {

using test::TempDir;
using test::write_file;

// An LM-63 file of type C with the given angles and candela (horizontal major).
std::string ies_text(const std::vector<double>& vertical, const std::vector<double>& horizontal,
                     const std::vector<double>& candela, const std::string& tilt = "NONE") {
  std::string s = "IESNA:LM-63-2002\n[TEST] mpath\nTILT=" + tilt + "\n";
  s += fmt::format("1 1000 1.0 {} {} 1 2 0.1 0.1 0.0\n1.0 1.0 20\n", vertical.size(), horizontal.size());
  for (double a : vertical) s += fmt::format("{} ", a);
  s += "\n";
  for (double a : horizontal) s += fmt::format("{} ", a);
  s += "\n";
  for (double c : candela) s += fmt::format("{} ", c);
  return s + "\n";
}

TEST(Luminaire, FluxIsTheIntegralOfTheIntensity) {
  EXPECT_NEAR(LightDistribution(100.0).flux(), 4 * std::numbers::pi * 100, 1e-9);
  TempDir dir;
  // Constant 100 cd over the sphere, given as a table.
  write_file(dir / "flat.ies", ies_text({0, 90, 180}, {0}, {100, 100, 100}));
  EXPECT_NEAR(read_ies(dir / "flat.ies").flux(), 4 * std::numbers::pi * 100, 1e-6);
  // A Lambertian downlight, I = 100 cos(theta) below the horizon: pi 100 lm
  // (the table's linear interpolation and the 1 degree bins err below 1e-3).
  std::vector<double> v, c;
  for (int a = 0; a <= 90; a += 5) {
    v.push_back(a);
    c.push_back(100 * std::cos(a * std::numbers::pi / 180));
  }
  const LightDistribution down = (write_file(dir / "down.ies", ies_text(v, {0}, c)), read_ies(dir / "down.ies"));
  EXPECT_NEAR(down.flux(), std::numbers::pi * 100, 1e-3 * std::numbers::pi * 100);
  EXPECT_EQ(down.intensity(std::numbers::pi * 0.75, 1.0), 0.0);  // nothing above the horizon
  // Sampled in proportion to I: P(theta < 45 degrees) = sin^2(45) = 1/2, within 4 sigma of a binomial count.
  const int n = 100000;
  int below = 0;
  uint64_t x = 12345;
  const auto u = [&] {
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(x >> 11) / 9007199254740992.0;
  };
  for (int k = 0; k < n; ++k) {
    double theta, phi;
    down.sample(u(), u(), u(), theta, phi);
    below += theta < std::numbers::pi / 4;
  }
  EXPECT_NEAR(below / double(n), 0.5, 4 * std::sqrt(0.25 / n));
}

TEST(Luminaire, ReadsSymmetriesTiltAndThePublishedLedaliteFile) {
  TempDir dir;
  // Bilateral symmetry (0 to 180): 180 + a reads as 180 - a.
  write_file(dir / "b.ies", ies_text({0, 90}, {0, 90, 180}, {10, 10, 20, 20, 30, 30}, "INCLUDE\n1\n2\n0 90\n1 1"));
  const LightDistribution b = read_ies(dir / "b.ies");
  const double deg = std::numbers::pi / 180;
  EXPECT_NEAR(b.intensity(0, 45 * deg), 15, 1e-9);
  EXPECT_NEAR(b.intensity(0, 315 * deg), 15, 1e-9);
  EXPECT_NEAR(b.intensity(0, 180 * deg), 30, 1e-9);
  const auto path = test::shared_scene("rpk_extra/examp1.ies");
  if (!path.empty()) {
    const LightDistribution d = read_ies(path);
    EXPECT_NEAR(d.intensity(0, 0), 778.4, 1e-9);  // the first candela value, multiplier and factors 1
    EXPECT_GT(d.flux(), 1000);
    EXPECT_LT(d.flux(), 2 * 2900);  // no more than its two lamps' lumens
  }
  // What is not read is an error naming the file.
  write_file(dir / "bad.ies", "IESNA:LM-63-2002\nTILT=NONE\n1 1000 1.0 2 1 3 2 0 0 0\n1 1 20\n0 90\n0\n1 1\n");
  EXPECT_THROW(read_ies(dir / "bad.ies"), InputError);  // photometric type 3
  write_file(dir / "short.ies", "IESNA:LM-63-2002\nTILT=NONE\n1 1000 1.0 2 1 1 2 0 0 0\n1 1 20\n0 90\n0\n1\n");
  try {
    read_ies(dir / "short.ies");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("short.ies: not an IESNA LM-63 photometric file mpath reads: the file ends "
                                         "before the candela values"),
              std::string::npos)
        << e.what();
  }
}

// The cube [-1, 1]^3 seen from inside, grey (rho 0.5), a polygon a face.
Scene closed_cube() {
  Scene scene;
  const int grey = test::add_material(scene, "wall", 0.5, 0.0);
  test::add_box(scene, {-1, -1, -1}, {1, 1, 1}, true, grey, test::add_object(scene, "room"));
  return scene;
}

// A closed cube, its faces one polygon each, an isotropic light at its
// centre: the first shot sends a sixth of the light's power to each face
// (within 4 sigma of the binomial count of lines), and every watt is
// accounted for.
TEST(Luminaire, FirstShotSpreadsTheLightsPowerByItsIntensity) {
  const Scene scene = closed_cube();
  const PatchMesh mesh = build_mesh(scene, 100.0);
  ASSERT_EQ(mesh.face_count(), 6u);
  RadiosityState state = make_state(scene, mesh);
  const Tracer tracer(mesh);
  LightOptions o;
  o.intensity_cd = 179.0 / (4 * std::numbers::pi);  // 1 W
  const PointLight light = make_light(o);
  EXPECT_NEAR(light.power(), 1.0, 1e-9);
  const long long n = 60000;
  EXPECT_EQ(shoot_light(mesh, tracer, state, light, n, 1, 2, false), static_cast<uint64_t>(n));
  EXPECT_NEAR(state.emitted_total(), state.channels * 1.0, 1e-12);
  for (size_t f = 0; f < 6; ++f) {
    const double received = state.phi[state.at(f, 0)] / 0.5;
    EXPECT_NEAR(received, 1.0 / 6, 4 * std::sqrt((1.0 / 6) * (5.0 / 6) / n)) << "face " << f;
  }
  EXPECT_NEAR(state.energy_residual(), 0.0, 1e-12);
}

// The same closed cube with the light off its centre (0.4 above it) and
// its frame tilted against the faces: a face receives the light's power in
// proportion to the solid angle it subtends, 4 asin(a b / sqrt((a^2 + d^2)
// (b^2 + d^2))) for the faces above and below (half sides a = b = 1 at
// distance d) and a quarter of the rest for each side. Over 40 seeds the
// stratified lines (first_shot.sequence = "halton") receive that on average,
// within 5 of their own standard errors, and vary far less from seed to seed
// than independent lines, whose spread is the binomial one.
TEST(Luminaire, StratifiedLightLinesAreUnbiasedAndSpreadLess) {
  const Scene scene = closed_cube();
  const PatchMesh mesh = build_mesh(scene, 100.0);
  ASSERT_EQ(mesh.face_count(), 6u);
  const Tracer tracer(mesh);
  LightOptions o;
  o.position = {0, 0, 0.4};
  o.intensity_cd = 179.0 / (4 * std::numbers::pi);  // 1 W
  o.nadir = {0.3, -0.2, -1.0};
  o.c0 = {1.0, 0.4, 0.1};
  const PointLight light = make_light(o);
  const auto cap = [](double d) { return 4 * std::asin(1.0 / (1.0 + d * d)); };  // a = b = 1
  const double top = cap(0.6) / (4 * std::numbers::pi), bottom = cap(1.4) / (4 * std::numbers::pi);
  const double side = (1.0 - top - bottom) / 4;
  const long long n = 4000;
  const int seeds = 40;
  for (const bool halton : {true, false}) {
    std::vector<double> sum(6, 0.0), square(6, 0.0);
    for (int seed = 1; seed <= seeds; ++seed) {
      RadiosityState state = make_state(scene, mesh);
      ASSERT_EQ(shoot_light(mesh, tracer, state, light, n, seed, 3, halton), static_cast<uint64_t>(n));
      for (size_t f = 0; f < 6; ++f) {
        const double received = state.phi[state.at(f, 0)] / 0.5;
        sum[f] += received;
        square[f] += received * received;
      }
      ASSERT_NEAR(state.energy_residual(), 0.0, 1e-12);
    }
    for (size_t f = 0; f < 6; ++f) {
      const double nz = mesh.patches[mesh.face_patch[f]].normal.z;  // the normals face in
      const double expected = nz < -0.5 ? top : nz > 0.5 ? bottom : side;
      const double mean = sum[f] / seeds;
      const double variance = std::max(0.0, (square[f] / seeds - mean * mean) * seeds / (seeds - 1));
      const double binomial = expected * (1 - expected) / static_cast<double>(n);
      // The independent lines' spread is the binomial one (a sample variance
      // of 40 seeds lies within a factor 2 of it with near certainty); the
      // stratified lines' is a small part of it.
      if (halton) {
        EXPECT_LT(variance, 0.1 * binomial) << "face " << f;
        EXPECT_NEAR(mean, expected, 5 * std::sqrt(std::max(variance, 1e-3 * binomial) / seeds)) << "face " << f;
      } else {
        EXPECT_GT(variance, 0.5 * binomial) << "face " << f;
        EXPECT_LT(variance, 2.0 * binomial) << "face " << f;
        EXPECT_NEAR(mean, expected, 5 * std::sqrt(binomial / seeds)) << "face " << f;
      }
    }
  }
}

// A sensor in a black room (nothing reflects) under a light of I cd at
// height h reads exactly I / h^2 lux facing it, I cos / r^2 off axis, and 0
// where the light is behind it or in shadow.
TEST(Luminaire, SensorsReadThePointSourceExactly) {
  Scene scene;
  const int black = test::add_material(scene, "black", 0.0, 0.0);
  test::add_box(scene, {-2, -2, 0}, {2, 2, 3}, true, black, test::add_object(scene, "room"));
  test::add_box(scene, {0.8, -0.2, 0.0}, {1.2, 0.2, 1.0}, false, black, test::add_object(scene, "block"));
  const PatchMesh mesh = build_mesh(scene, 1.0);
  RadiosityState state = make_state(scene, mesh);
  const Tracer tracer(mesh);
  LightOptions o;
  o.position = {0, 0, 2.5};
  o.intensity_cd = 1000;
  const PointLight light = make_light(o);
  GridOptions g;
  g.origin = {-0.5, -0.5, 0.5};
  g.u = {1, 0, 0};
  g.v = {0, 1, 0};
  g.nu = g.nv = 1;  // the point (0, 0, 0.5), facing up
  g.samples = 16;
  EXPECT_NEAR(measure_grid(g, mesh, tracer, state, {light}, 1).points[0].illuminance, 1000 / 4.0, 1e-9);
  g.origin = {-1.5, -0.5, 0.5};  // (-1, 0, 0.5): r^2 = 5, cos = 2 / sqrt(5)
  EXPECT_NEAR(measure_grid(g, mesh, tracer, state, {light}, 1).points[0].illuminance, 1000 * 2 / std::pow(5, 1.5),
              1e-9);
  g.normal = {0, 0, -1};  // facing away
  EXPECT_EQ(measure_grid(g, mesh, tracer, state, {light}, 1).points[0].illuminance, 0.0);
  g.normal = {0, 0, 1};
  g.origin = {1.1, -0.5, 0.3};  // (1.6, 0, 0.3): the line to the light crosses the block at z 0.85
  EXPECT_EQ(measure_grid(g, mesh, tracer, state, {light}, 1).points[0].illuminance, 0.0);
  g.origin = {1.1, -0.5, 1.5};  // (1.6, 0, 1.5), above the block: lit, r^2 = 3.56, cos = 1 / sqrt(3.56)
  EXPECT_NEAR(measure_grid(g, mesh, tracer, state, {light}, 1).points[0].illuminance, 1000 / std::pow(3.56, 1.5), 1e-9);
}

}  // namespace
}  // namespace mpath
