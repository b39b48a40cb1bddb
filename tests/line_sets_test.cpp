// The line-set transport of the hierarchy (hierarchy.transport = "lines") on
// furnished furnaces of random layouts (scripts/make_furnace.py --seed):
// closed rooms where every surface emits and reflects alike, so that the
// exact radiosity is B = E / (1 - rho) on every face whatever the furniture.
// Angular regions and walls would lose nothing there: any error that does
// not fall with lines is a defect.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "line_sets.h"
#include "test_util.h"

namespace mpath {
namespace {

using test::TempDir;

// A random furnished furnace of `seed` (OBJ + MTL in `dir`).
std::filesystem::path furnace(const TempDir& dir, double rho, int seed, int items = 8) {
  const auto stem = dir / ("furnace" + std::to_string(seed));
  const test::RunResult r = test::run(std::string(MPATH_PYTHON) + " " + MPATH_SOURCE_DIR + "/scripts/make_furnace.py " +
                                      std::to_string(rho) + " " + stem.string() + " --seed " + std::to_string(seed) +
                                      " --items " + std::to_string(items));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return stem.string() + ".obj";
}

struct FurnaceRun {
  double mean = 0;       // area-weighted mean of B / exact - 1
  double abs_error = 0;  // area-weighted mean of |B / exact - 1|
  size_t boxes = 0;
  int depth = 0;
  size_t iterations = 0;
  bool converged = false;
  double worst_residual = 0;  // energy balance after any iteration, relative
};

FurnaceRun solve_furnace(const std::filesystem::path& scene, double rho, SolverMethod method, long long lines,
                         const std::string& dir, int max_depth = 1) {
  Options o = test::test_options(lines, 250'000, 0.02);
  o.scene.file = scene;
  o.scene.two_sided = {"panel"};
  o.store.dir = dir;
  o.solver.method = method;
  o.solver.iterations = 200;
  o.solver.tolerance = 1e-4;
  o.lines.sequence = "halton";
  o.hierarchy.max_depth = max_depth;
  FurnaceRun run;
  const auto s = test::solve_stored(o, [&](const RadiosityState& st) {
    run.worst_residual = std::max(run.worst_residual, std::fabs(st.energy_residual()) / st.emitted_total());
  });
  const double exact = std::numbers::pi / (1 - rho);
  double area = 0;
  for (size_t f = 0; f < s.mesh.face_count(); ++f) {
    const double a = s.mesh.face_area(static_cast<int>(f));
    const double e = s.state.radiosity(s.mesh, f)[0] / exact - 1;
    area += a;
    run.mean += a * e;
    run.abs_error += a * std::fabs(e);
  }
  run.mean /= area;
  run.abs_error /= area;
  run.boxes = s.boxes;
  run.depth = s.depth;
  run.iterations = s.log.passes.size();
  run.converged = s.log.converged;
  return run;
}

// Hierarchical (the default line sets) against stored-line Multipath on the
// same layout, at 500k and 2M lines: the error falls as 1/sqrt(lines) (a
// factor 2 for 4x the lines; 1.6 allows for the noise of the error
// estimate over a few thousand faces), and stays within 1.2x Multipath's
// (the root carries 0.8 of the lines: 1/sqrt(0.8) = 1.12 where only it
// carries a face's exchange).
TEST(LineSets, FurnishedFurnacesAreExactAndTheirErrorFallsAsMultipaths) {
  TempDir dir;
  for (const int seed : {1, 2, 3}) {
    const auto scene = furnace(dir, 0.5, seed);
    FurnaceRun h[2], m[2];
    for (int k = 0; k < 2; ++k) {
      const long long lines = k == 0 ? 500'000 : 2'000'000;
      h[k] = solve_furnace(scene, 0.5, SolverMethod::hierarchical, lines, (dir / "h").string());
      m[k] = solve_furnace(scene, 0.5, SolverMethod::multipath, lines, (dir / "m").string());
      SCOPED_TRACE("seed " + std::to_string(seed) + ", " + std::to_string(lines) + " lines");
      EXPECT_GE(h[k].boxes, 2u);
      EXPECT_TRUE(h[k].converged);
      EXPECT_LT(h[k].worst_residual, 1e-11);  // energy closes after every iteration
      EXPECT_NEAR(h[k].mean, 0.0, 2e-3);
      EXPECT_LT(h[k].abs_error, 1.2 * m[k].abs_error) << "multipath " << m[k].abs_error;
    }
    EXPECT_GT(h[0].abs_error / h[1].abs_error, 1.6) << "seed " << seed << ": " << h[0].abs_error << " at 500k, "
                                                     << h[1].abs_error << " at 2M";
  }
}

// Subscenes inside subscenes (shelves whose books group, tables with items):
// a class of exchanges for every level, still exact.
TEST(LineSets, NestedSubscenesAreExact) {
  TempDir dir;
  int deepest = 0;
  for (const int seed : {1, 3}) {
    const auto scene = furnace(dir, 0.5, seed, 10);
    const FurnaceRun h = solve_furnace(scene, 0.5, SolverMethod::hierarchical, 2'000'000, (dir / "h").string(), 3);
    const FurnaceRun m = solve_furnace(scene, 0.5, SolverMethod::multipath, 2'000'000, (dir / "m").string());
    EXPECT_GE(h.boxes, 4u) << "seed " << seed;
    EXPECT_NEAR(h.mean, 0.0, 2e-3) << "seed " << seed;
    EXPECT_LT(h.abs_error, 1.2 * m.abs_error) << "seed " << seed << ", multipath " << m.abs_error;
    EXPECT_LT(h.worst_residual, 1e-11);
    deepest = std::max(deepest, h.depth);
  }
  EXPECT_GE(deepest, 2);
}

// At rho 0.99 power crosses between boxes with every bounce: the line sets
// carry it within each pass, as Multipath does, and need at most 1.5x its
// iterations (measured: 107 against 96; none is held in walls).
TEST(LineSets, HighReflectanceConvergesLikeMultipath) {
  TempDir dir;
  const auto scene = furnace(dir, 0.99, 1);
  const FurnaceRun h = solve_furnace(scene, 0.99, SolverMethod::hierarchical, 1'000'000, (dir / "h").string());
  const FurnaceRun m = solve_furnace(scene, 0.99, SolverMethod::multipath, 1'000'000, (dir / "m").string());
  EXPECT_TRUE(h.converged);
  EXPECT_LE(h.iterations, 1.5 * m.iterations) << "multipath " << m.iterations;
  EXPECT_NEAR(h.mean, 0.0, 0.01);
  EXPECT_LT(h.abs_error, 1.6 * m.abs_error) << "multipath " << m.abs_error;
  EXPECT_LT(h.worst_residual, 1e-10);
}

}  // namespace
}  // namespace mpath
