// Physics of the classic solver against analytic answers: the furnace
// (B = E / (1 - rho) in a closed uniform scene), form factors of unit squares
// (Howell's catalogue C-11 and C-14), and the energy balance. Tolerances come
// from the number of samples, as each test states.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "sampling.h"
#include "scene_readers.h"
#include "test_util.h"
#include "transport.h"

namespace mpath {
namespace {

using test::furnace_scene;
using test::solve_classic_in_memory;
using test::test_options;

struct FurnaceError {
  double mean_abs = 0;   // mean over faces of |B (1 - rho) / E - 1|
  double mean = 0;       // signed mean
  double predicted = 0;  // expected mean_abs from the crossing counts
  size_t faces = 0;
};

// Each face's incoming power is a sum over ~c line crossings (c its expected
// crossing count), so its relative error is about 1/sqrt(c) and that of
// B (1 - rho) / E about rho / sqrt(c); a normal error has mean |x| = sqrt(2/pi) sigma.
FurnaceError furnace_error(const test::Solved& s, double rho, double exitance, long long lines_per_pass) {
  FurnaceError e;
  const double box_area = line_box(s.mesh.bounds).surface_area();
  for (size_t f = 0; f < s.state.faces; ++f) {
    const double b = s.state.radiosity(s.mesh, f)[0];
    const double err = b * (1 - rho) / exitance - 1;
    e.mean_abs += std::fabs(err);
    e.mean += err;
    const double crossings = static_cast<double>(lines_per_pass) * 2.0 * s.mesh.face_area(static_cast<int>(f)) / box_area;
    e.predicted += std::sqrt(2.0 / std::numbers::pi) * rho / std::sqrt(crossings);
  }
  e.faces = s.state.faces;
  e.mean_abs /= e.faces;
  e.mean /= e.faces;
  e.predicted /= e.faces;
  return e;
}

class Furnace : public ::testing::TestWithParam<double> {};

TEST_P(Furnace, GivesEOverOneMinusRhoOnEveryFace) {
  const double rho = GetParam(), exitance = 2.0;
  Options o = test_options(2'000'000, 200'000, 0.025);
  o.solver.iterations = 30;
  o.solver.tolerance = 1e-4;
  const auto s = solve_classic_in_memory(furnace_scene(rho, exitance), o);
  ASSERT_TRUE(s.log.converged);
  const FurnaceError e = furnace_error(s, rho, exitance, o.lines.total);
  // The unshot power left at the end is missing from B: at most rho * tolerance.
  const double bias_bound = rho * o.solver.tolerance;
  // Noise: 1.5x the predicted mean |error| (the model neglects later bounces).
  EXPECT_LT(e.mean_abs, 1.5 * e.predicted + bias_bound) << "faces " << e.faces;
  // Unbiased: the signed mean is within 5 standard errors of zero.
  const double sigma_mean = e.predicted / std::sqrt(2.0 / std::numbers::pi) / std::sqrt(static_cast<double>(e.faces));
  EXPECT_LT(std::fabs(e.mean), 5 * sigma_mean + bias_bound);
  EXPECT_LT(std::fabs(s.state.energy_residual()) / s.state.emitted_total(), 1e-10);
}

INSTANTIATE_TEST_SUITE_P(Reflectances, Furnace, ::testing::Values(0.5, 0.9));

TEST(Furnace, WithLocalLineFirstShotStaysUnbiased) {
  const double rho = 0.5, exitance = 1.0;
  Options o = test_options(1'000'000, 2'000'000, 0.05);
  o.first_shot.mode = "local";
  const auto s = solve_classic_in_memory(furnace_scene(rho, exitance), o);
  const FurnaceError e = furnace_error(s, rho, exitance, o.lines.total);
  // Local lines add the first bounce's noise: each face gets about
  // n_local * A / A_total of them, relative error 1/sqrt of that, times rho.
  double total_area = 0;
  for (const Patch& p : s.mesh.patches) total_area += p.area;
  double local_noise = 0;
  for (size_t f = 0; f < s.state.faces; ++f) {
    const double received = static_cast<double>(first_shot_lines(o)) * s.mesh.face_area(static_cast<int>(f)) / total_area;
    local_noise += std::sqrt(2.0 / std::numbers::pi) * rho / std::sqrt(received);
  }
  local_noise /= s.state.faces;
  const double predicted = std::hypot(e.predicted, local_noise);
  EXPECT_LT(e.mean_abs, 1.5 * predicted + rho * o.solver.tolerance);
  EXPECT_LT(std::fabs(e.mean), 5 * predicted / std::sqrt(static_cast<double>(e.faces)) + rho * o.solver.tolerance);
}

TEST(EnergyBalance, ClosesInAClosedSceneWithNothingEscaping) {
  // Robust Embree traversal and edge de-duplication: no line slips through a
  // closed room 2 mm, 2 m or 200 m long (one line escaping would carry about
  // 1e-6 of the power).
  for (const double scale : {1.0, 1e-3, 100.0}) {
    Scene scene = furnace_scene(0.7, 1.0);
    for (Polygon& p : scene.polygons)
      for (Vec3& v : p.vertices) v = v * scale;
    const auto s = solve_classic_in_memory(scene, test_options(500'000, 100'000, 0.05 * scale * scale));
    const double emitted = s.state.emitted_total();
    EXPECT_LT(std::fabs(s.state.energy_residual()) / emitted, 1e-10) << "scale " << scale;
    EXPECT_LT((s.state.energy.escaped[0]) / emitted, 1e-9) << "scale " << scale;
  }
}

// A millimetre emitting cube in a black kilometre room, near the origin and
// 500 m from it: a convex object cannot light itself, so B = E exactly on
// every face of it (local lines start a hair behind their patch; the hair is
// sized by the patch and the float spacing at its place, not only by the
// scene, and its own object met within float rounding is not a surface).
TEST(LocalLines, ATinyObjectInAHugeSceneDoesNotLightItself) {
  for (const Vec3 at : {Vec3{3, 2, 1}, Vec3{400, 300, 2}}) {
    Scene scene;
    const int black = test::add_material(scene, "black", 0.0, 0.0);
    const int lamp = test::add_material(scene, "lamp", 0.5, 1.0);
    test::add_box(scene, {-500, -500, -500}, {500, 500, 500}, true, black, test::add_object(scene, "room"));
    test::add_box(scene, at, at + Vec3{1e-3, 1e-3, 1e-3}, false, lamp, test::add_object(scene, "cube"));
    Options o = test_options(100'000, 200'000, 0.0);
    o.mesh.max_patch_area = 1e9;  // one patch a face
    const auto s = solve_classic_in_memory(scene, o);
    for (size_t f = 0; f < s.mesh.face_count(); ++f) {
      if (s.mesh.patches[s.mesh.face_patch[f]].material != lamp) continue;
      const double e = s.state.face_exitance(f)[0];
      EXPECT_NEAR(s.state.radiosity(s.mesh, f)[0], e, 1e-9 * e) << "cube at " << at.x << ", face " << f;
    }
  }
}

TEST(EnergyBalance, ClosesInTheOpenCornellBoxWherePowerEscapes) {
  Options o = test_options(500'000, 200'000, 0.002);
  o.scene.file = std::string(MPATH_SOURCE_DIR) + "/configs/cornell_box/cornell_box.obj";
  std::vector<std::string> warnings;
  const Scene scene = load_scene(o.scene, o.mesh.curve_segments, warnings);
  const auto s = solve_classic_in_memory(scene, o);
  ASSERT_EQ(s.state.channels, 3);
  for (int c = 0; c < 3; ++c) {
    const auto& e = s.state.energy;
    double unshot = 0;
    for (size_t f = 0; f < s.state.faces; ++f) unshot += s.state.unshot[s.state.at(f, c)];
    EXPECT_NEAR(e.emitted[c], e.absorbed[c] + e.escaped[c] + unshot, 1e-10 * e.emitted[c]) << "channel " << c;
    // The front is open: a good part of the light leaves the box.
    EXPECT_GT(e.escaped[c], 0.1 * e.emitted[c]);
  }
}

// Two unit squares: A emits (rho 0), B receives with rho 0.5 and nothing else
// reflects, so the power reaching B over the power A sends is F_AB.
Scene two_squares(bool perpendicular) {
  Scene scene;
  scene.file = "squares";
  const int emitter = test::add_material(scene, "emitter", 0.0, 1.0 / std::numbers::pi);
  const int receiver = test::add_material(scene, "receiver", 0.5, 0.0);
  const int a = test::add_object(scene, "A"), b = test::add_object(scene, "B");
  test::add_quad(scene, {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, emitter, a);  // faces +z
  if (perpendicular) test::add_quad(scene, {0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}, receiver, b);  // faces +x
  else test::add_quad(scene, {0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}, receiver, b);  // faces -z
  return scene;
}

// Howell C-11 (parallel, distance 1) and C-14 (perpendicular, common edge).
constexpr double kParallelF = 0.19982, kPerpendicularF = 0.20004;

class FormFactor : public ::testing::TestWithParam<bool> {};

TEST_P(FormFactor, FromLocalLinesMatchesHowell) {
  const bool perpendicular = GetParam();
  const double expected = perpendicular ? kPerpendicularF : kParallelF;
  const Scene scene = two_squares(perpendicular);
  const PatchMesh mesh = build_mesh(scene, 1.0);
  ASSERT_EQ(mesh.face_count(), 2u);
  const Tracer tracer(mesh);
  RadiosityState state = make_state(scene, mesh);
  const long long lines = 1'000'000;
  first_shot(mesh, tracer, state, lines, 7, 2);
  const double arrived = (state.phi[1] - state.emitted_power[1]) / 0.5;
  const double f = arrived / state.emitted_total();
  // Binomial: each local line reaches B with probability F.
  const double sigma = std::sqrt(expected * (1 - expected) / lines);
  EXPECT_NEAR(f, expected, 4 * sigma);
}

TEST_P(FormFactor, FromGlobalLinesMatchesHowell) {
  const bool perpendicular = GetParam();
  const double expected = perpendicular ? kPerpendicularF : kParallelF;
  const Scene scene = two_squares(perpendicular);
  const PatchMesh mesh = build_mesh(scene, 1.0);
  const Tracer tracer(mesh);
  RadiosityState state = make_state(scene, mesh);
  // A's emission is unshot power for one pass of global lines.
  state.unshot[0] = state.emitted_power[0];
  const uint64_t lines = 2'000'000;
  classic_pass(mesh, tracer, state, lines, 11, 1, 2);
  const double sent = state.emitted_power[0] - state.unshot[0];
  const double arrived = (state.phi[1] - state.emitted_power[1]) / 0.5;
  // Ratio of arrivals to sends: binomial over the ~N 2A/S crossings of A.
  const double crossings = lines * 2.0 / line_box(mesh.bounds).surface_area();
  const double sigma = std::sqrt(expected * (1 - expected) / crossings);
  EXPECT_NEAR(arrived / sent, expected, 4 * sigma);
  EXPECT_GT(sent, 0.99 * state.emitted_power[0]);  // the forecast holds to about 1/sqrt(crossings)
  EXPECT_LT(std::fabs(state.energy_residual()) / state.emitted_total(), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Squares, FormFactor, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? "Perpendicular" : "Parallel"; });

TEST(Reproducibility, SameSeedAndThreadsGiveIdenticalResults) {
  const Options o = test_options(200'000, 50'000, 0.05);
  const auto a = solve_classic_in_memory(furnace_scene(0.6, 1.0), o);
  const auto b = solve_classic_in_memory(furnace_scene(0.6, 1.0), o);
  EXPECT_EQ(a.state.phi, b.state.phi);
  Options other = o;
  other.lines.seed = 2;
  const auto c = solve_classic_in_memory(furnace_scene(0.6, 1.0), other);
  EXPECT_NE(a.state.phi, c.state.phi);
}

TEST(Channels, GreySceneIsSolvedInOneChannelAndColouredInThree) {
  Scene grey = furnace_scene(0.5, 1.0);
  EXPECT_EQ(make_state(grey, build_mesh(grey, 0.5)).channels, 1);
  grey.materials[0].rho = {0.5, 0.4, 0.3};
  EXPECT_EQ(make_state(grey, build_mesh(grey, 0.5)).channels, 3);
}

}  // namespace
}  // namespace mpath
