// The line-set transport of the hierarchy (hierarchy.transport = "lines") on
// furnished furnaces of random layouts (scripts/make_furnace.py --seed):
// closed rooms where every surface emits and reflects alike, so that the
// exact radiosity is B = E / (1 - rho) on every face whatever the furniture.
// Angular regions and walls would lose nothing there: any error that does
// not fall with lines is a defect.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "config.h"
#include "hierarchical.h"
#include "iteration.h"
#include "line_sets.h"
#include "prepared_scene.h"
#include "preprocess.h"
#include "test_util.h"

namespace mpath {
namespace {

using test::TempDir;

// A random furnished furnace of `seed` (OBJ + MTL in `dir`); `extra`: more
// arguments of make_furnace.py.
std::filesystem::path furnace(const TempDir& dir, double rho, int seed, int items = 8, const std::string& extra = "") {
  const auto stem = dir / ("furnace" + std::to_string(seed));
  const test::RunResult r = test::run(std::string(MPATH_PYTHON) + " " + MPATH_SOURCE_DIR + "/scripts/make_furnace.py " +
                                      std::to_string(rho) + " " + stem.string() + " --seed " + std::to_string(seed) +
                                      " --items " + std::to_string(items) + " " + extra);
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
                         const std::string& dir, int max_depth = 1, const std::string& transport = "lines") {
  Options o = test::test_options(lines, 250'000, 0.02);
  o.scene.file = scene;
  o.scene.two_sided = {"panel"};
  o.store.dir = dir;
  o.solver.method = method;
  o.solver.iterations = 200;
  o.solver.tolerance = 1e-4;
  o.lines.sequence = "halton";
  o.hierarchy.max_depth = max_depth;
  o.hierarchy.transport = transport;
  FurnaceRun run;
  const auto s = test::solve_stored(o, [&](const RadiosityState& st) {
    run.worst_residual = std::max(run.worst_residual, std::fabs(st.energy_residual()) / st.emitted_total());
  });
  double area = 0;
  for (size_t f = 0; f < s.mesh.face_count(); ++f) {
    const double a = s.mesh.face_area(static_cast<int>(f));
    // pi / (1 - rho) W/m2; from the face's own values, as an MGF file's
    // emittance passes through lumens and colour.
    const double exact = s.state.face_exitance(f)[0] / (1 - s.state.face_rho(f)[0]);
    EXPECT_NEAR(exact, std::numbers::pi / (1 - rho), 1e-6);
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

// MGF's one-sided surfaces are invisible from behind: power passes a back
// to the next surface on its way, in every transport, in the first shot and
// in the preprocessor's counts. Furnished furnaces written as MGF with every
// surface but the panels one-sided, and one-sided sheets standing free in
// the room facing random ways, stay exact (every way from a front ends on a
// front); the same layouts as OBJ, where those backs are black and absorb,
// come out darker, which shows the check can fail.
TEST(Sides, InvisibleBacksKeepFurnishedFurnacesExact) {
  TempDir dir;
  for (const int seed : {4, 5}) {
    const auto obj = furnace(dir, 0.5, seed, 8, "--veils 5 --mgf");
    auto mgf = obj;
    mgf.replace_extension(".mgf");
    const long long lines = 1'000'000;
    struct Case {
      std::filesystem::path scene;
      SolverMethod method;
      int depth;
      std::string transport;
    };
    for (const Case& c : {Case{mgf, SolverMethod::hierarchical, 3, "lines"},
                          Case{mgf, SolverMethod::hierarchical, 3, "transmittance"},
                          Case{mgf, SolverMethod::multipath, 1, "lines"}}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + ", " + c.transport + " depth " + std::to_string(c.depth));
      const FurnaceRun r = solve_furnace(c.scene, 0.5, c.method, lines, (dir / "s").string(), c.depth, c.transport);
      EXPECT_TRUE(r.converged);
      EXPECT_LT(r.worst_residual, 1e-11);
      // 6,000-odd faces each within a few per cent: their mean within 2e-3.
      EXPECT_NEAR(r.mean, 0.0, 2e-3);
      EXPECT_LT(r.abs_error, 0.06);
    }
    const FurnaceRun black = solve_furnace(obj, 0.5, SolverMethod::hierarchical, lines, (dir / "b").string(), 3);
    EXPECT_LT(black.mean, -5e-3) << "seed " << seed << ": the veils' black backs absorb";
  }
}

// The class counts mpath-preprocess writes while tracing (per box, patch
// side and class) are the counts of the stored lines themselves, counted here
// again from every line of a nested hierarchy traced in three shards (whose
// files' counts the store adds up): the shares and MIS weights of the passes
// rest on them. Counted on a furnished furnace (every back black) and on one
// written as MGF with one-sided sheets facing random ways, whose invisible
// backs pair a crossing with the next one beyond them (next_seen).
TEST(LineSets, StoredClassCountsAreThoseOfTheStoredLines) {
  TempDir dir;
  const auto obj = furnace(dir, 0.5, 3, 10);
  auto mgf = furnace(dir, 0.5, 4, 8, "--veils 5 --mgf");
  mgf.replace_extension(".mgf");
  for (const auto& scene : {obj, mgf}) {
    SCOPED_TRACE(scene.filename().string());
    Options o = test::test_options(300'000, 100'000, 0.02);
    o.scene.file = scene;
    o.scene.two_sided = {"panel"};
    o.store.dir = dir / ("store-" + scene.extension().string().substr(1));
    o.solver.method = SolverMethod::hierarchical;
    o.hierarchy.max_depth = 3;
    o.store.chunk_lines = 20'000;
    for (int shard = 1; shard <= 3; ++shard) run_preprocess(o, ShardSpec{shard, 3});
    const PreparedScene prepared = prepare_scene(o);
    const PatchMesh& mesh = prepared.mesh;
    const BoxStore store(o, mesh);
    const Hierarchy& h = store.hierarchy();
    ASSERT_GE(h.max_depth(), 2);
    size_t counted = 0, passed_behind = 0;
    for (size_t x = 0; x < store.box_count(); ++x) {
      const StoreBox& box = store.box(static_cast<int>(x));
      const SceneBox& sb = h.boxes[x];
      const size_t span = static_cast<size_t>(h.max_depth() - sb.depth + 1);
      std::vector<uint32_t> expected(sb.patches.size() * 2 * span, 0);
      linestore::DecodedChunk chunk;
      for (uint64_t c = 0; c < box.chunks.size(); ++c) {
        store.read(static_cast<int>(x), c, chunk);
        for (size_t l = 0; l < chunk.lines(); ++l) {
          const int n = static_cast<int>(chunk.first[l + 1] - chunk.first[l]);
          const linestore::Event* ev = chunk.events.data() + chunk.first[l];
          // The side of crossing k turned towards direction d, and whether it is an invisible back.
          const auto invisible = [&](int k, int d) {
            const size_t side = (d > 0) == ev[k].along ? 0 : 1;
            return mesh.patch_faces[static_cast<size_t>(sb.patches[ev[k].id])][side] == kInvisibleSide;
          };
          for (int i = 0; i < n; ++i)
            for (const int dir : {+1, -1}) {
              int j = i + dir;
              while (j >= 0 && j < n && invisible(j, -dir)) j += dir, ++passed_behind;
              const int a = h.patch_box[sb.patches[ev[i].id]];
              if ((j < 0 || j >= n) && x != 0) continue;  // a subscene's line leaving it carries no pair
              const int common = (j < 0 || j >= n) ? 0 : h.common_box(a, h.patch_box[sb.patches[ev[j].id]]);
              const size_t side = (dir > 0) == ev[i].along ? 0 : 1;
              ++expected[(ev[i].id * 2 + side) * span + static_cast<size_t>(h.boxes[a].depth - h.boxes[common].depth)];
              ++counted;
            }
        }
      }
      EXPECT_EQ(box.counts.class_crossings, expected) << "box " << x;
    }
    EXPECT_GT(counted, 1'000'000u);
    if (scene == mgf) {
      EXPECT_GT(passed_behind, 10'000u) << "the MGF furnace's lines pass invisible backs";
    }
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
// iterations (measured: 89 against 85 at 2M lines; none is held in walls),
// with at most 1.2x its error (measured 1.13-1.18x on seeds 1-3).
TEST(LineSets, HighReflectanceConvergesLikeMultipath) {
  TempDir dir;
  const auto scene = furnace(dir, 0.99, 1);
  const FurnaceRun h = solve_furnace(scene, 0.99, SolverMethod::hierarchical, 1'000'000, (dir / "h").string());
  const FurnaceRun m = solve_furnace(scene, 0.99, SolverMethod::multipath, 1'000'000, (dir / "m").string());
  EXPECT_TRUE(h.converged);
  EXPECT_LE(h.iterations, 1.5 * m.iterations) << "multipath " << m.iterations;
  EXPECT_NEAR(h.mean, 0.0, 0.01);
  EXPECT_LT(h.abs_error, 1.2 * m.abs_error) << "multipath " << m.abs_error;
  EXPECT_LT(h.worst_residual, 1e-10);
}

// Finely meshed (a few stored lines per face), later passes that take a
// part of the lines (solver.adaptive_lines, the default) must not stall:
// each shard sends a face's power only up to its part, so the faces few
// lines cross keep most of theirs a pass, and a subscene below the root's
// coverage takes no line, so the classes only its lines carry wait. Such
// passes are taken only where they send as much per line as a full one;
// the solve then needs at most 1.5x the iterations of full passes (before,
// it stalled with 0.35 % of the power waiting in the shade on every seed)
// and its reflected power is theirs.
TEST(LineSets, PartialPassesDoNotStallOnFineMeshes) {
  TempDir dir;
  for (const int seed : {1, 2, 3}) {
    // A furnished room of a random layout, lit by a lamp in its shade (a
    // subscene: the power the shade holds for its own classes moves only
    // along its own lines).
    const auto stem = dir / ("room" + std::to_string(seed));
    const test::RunResult made = test::run(std::string(MPATH_PYTHON) + " " + MPATH_SOURCE_DIR +
                                           "/scripts/make_room.py room " + stem.string() + " --seed " +
                                           std::to_string(seed));
    ASSERT_EQ(made.exit_code, 0) << made.output;
    const auto solve = [&](bool adaptive) {
      Options o = test::test_options(300'000, 100'000, 0.002);
      o.scene.file = stem.string() + ".obj";
      o.scene.two_sided = {"lampshade"};
      o.store.dir = dir / ("s" + std::to_string(seed) + (adaptive ? "a" : "f"));
      o.solver.method = SolverMethod::hierarchical;
      o.solver.adaptive_lines = adaptive;
      o.solver.iterations = 40;
      o.lines.sequence = "halton";
      return test::solve_stored(o);
    };
    const test::StoredSolve a = solve(true), f = solve(false);
    EXPECT_GE(a.boxes, 2u) << "seed " << seed;
    EXPECT_TRUE(f.log.converged) << "seed " << seed;
    EXPECT_TRUE(a.log.converged) << "seed " << seed << ": " << a.state.remaining_fraction() << " left after "
                                 << a.log.passes.size() << " iterations";
    EXPECT_LE(a.log.passes.size(), 1.5 * f.log.passes.size()) << "seed " << seed;
    EXPECT_LT(std::fabs(a.state.energy_residual()) / a.state.emitted_total(), 1e-10);
    // The same stored lines: the two answers differ by the passes' plans alone.
    ASSERT_EQ(a.mesh.face_count(), f.mesh.face_count());
    double diff = 0, total = 0;
    for (size_t k = 0; k < a.mesh.face_count(); ++k) {
      const double w = a.mesh.face_area(static_cast<int>(k));
      const double ra = a.state.radiosity(a.mesh, k)[0] - a.state.face_exitance(k)[0];
      const double rf = f.state.radiosity(f.mesh, k)[0] - f.state.face_exitance(k)[0];
      diff += w * (ra - rf);
      total += w * rf;
    }
    EXPECT_LT(std::fabs(diff / total), 5e-3) << "seed " << seed << ": reflected power, adaptive against full passes";
  }
}

// The choice between a partial and a full next pass, on logs shaped as
// OFFICE's at 2M lines (86,662 faces): a first pass of every line took the
// power left from 0.45 to 0.032 of the emitted with 10.9M crossings, then
// partial passes of 1.6M crossings took it down by 1.6x, 1.2x, ...
TEST(LineSets, AFullPassIsTakenWhereItReachesTheToleranceForLessWork) {
  const uint64_t lines = 2'000'000;
  const size_t faces = 86'662;
  const auto log_of = [&](std::vector<std::pair<uint64_t, double>> partial) {
    IterationLog log;
    log.first_unshot = 0.45 * 100.0;  // W, of 100 W emitted
    log.passes.push_back(PassStats{1, lines, 10'867'158, 0.3, 0.032});
    for (const auto& [hits, left] : partial)
      log.passes.push_back(PassStats{static_cast<int>(log.passes.size()) + 1, 246'858, hits, 0.08, left});
    return log;
  };
  // Too few passes to weigh, or the last one took every line: no judgement.
  EXPECT_FALSE(full_pass_pays(log_of({}), lines, 100.0, faces, 1e-3, 100));
  IterationLog full = log_of({{1'607'648, 0.0146}});
  full.passes.push_back(PassStats{3, lines, 10'867'158, 0.3, 0.0089});
  EXPECT_FALSE(full_pass_pays(full, lines, 100.0, faces, 1e-3, 100));
  // A thin pass that took the power down by 1.6x: five more of them (15M
  // crossings with the work around them) against one full pass (12.3M).
  EXPECT_TRUE(full_pass_pays(log_of({{1'607'648, 0.0146}, {1'605'393, 0.00887}}), lines, 100.0, faces, 1e-3, 100));
  // Close to the tolerance, one thin pass is enough.
  EXPECT_FALSE(full_pass_pays(log_of({{1'607'648, 0.0146}, {1'605'393, 0.00125}}), lines, 100.0, faces, 1e-3, 100));
  // Thin passes that take it down fast enough stay.
  EXPECT_FALSE(full_pass_pays(log_of({{1'607'648, 0.0146}, {1'605'393, 0.0020}}), lines, 100.0, faces, 1e-3, 100));
  // ... unless they would not get there within the iterations left.
  EXPECT_TRUE(full_pass_pays(log_of({{1'607'648, 0.0146}, {1'605'393, 0.0040}}), lines, 100.0, faces, 1e-3, 1));
  // A thin pass that moved nothing.
  EXPECT_TRUE(full_pass_pays(log_of({{1'607'648, 0.0146}, {1'605'393, 0.0146}}), lines, 100.0, faces, 1e-3, 100));
  // Below the tolerance already, or nothing emitted: nothing to choose.
  EXPECT_FALSE(full_pass_pays(log_of({{1'607'648, 0.0146}, {1'605'393, 0.0009}}), lines, 100.0, faces, 1e-3, 100));
  EXPECT_FALSE(full_pass_pays(log_of({{1'607'648, 0.0146}, {1'605'393, 0.00887}}), lines, 0.0, faces, 1e-3, 100));
}

// With no line in any subscene (lines.root_fraction = 1) every class is
// carried by the root's lines alone, each crossing sends 1/N of the face's
// power whatever its class, and power received in a pass goes on along the
// face's next crossing: the line sets must then be stored-line Multipath
// itself, face by face, up to rounding (every line in every pass, so that
// both take the same lines in the same order). Sending received power on
// class by class instead (each class along its own next crossing) is as
// unbiased but not the same sums, and measured 1.3x Multipath's error at
// rho 0.99.
TEST(LineSets, WithoutSubsceneLinesTheyAreStoredLineMultipath) {
  TempDir dir;
  const auto scene = furnace(dir, 0.9, 2);
  const auto solve = [&](SolverMethod method) {
    Options o = test::test_options(400'000, 100'000, 0.02);
    o.scene.file = scene;
    o.scene.two_sided = {"panel"};
    o.store.dir = dir / (method == SolverMethod::multipath ? "m" : "h");
    o.solver.method = method;
    o.solver.adaptive_lines = false;
    o.lines.box_budget = "quotient";
    o.lines.root_fraction = 1.0;
    return test::solve_stored(o);
  };
  const test::StoredSolve h = solve(SolverMethod::hierarchical), m = solve(SolverMethod::multipath);
  EXPECT_GE(h.boxes, 2u);
  ASSERT_EQ(h.mesh.face_count(), m.mesh.face_count());
  ASSERT_EQ(h.log.passes.size(), m.log.passes.size());
  double worst = 0;
  for (size_t f = 0; f < h.mesh.face_count(); ++f) {
    const double a = h.state.radiosity(h.mesh, f)[0], b = m.state.radiosity(m.mesh, f)[0];
    worst = std::max(worst, std::fabs(a - b) / b);
  }
  EXPECT_LT(worst, 1e-9);
}

// A furnace cannot show a bias of the form factors (any row-stochastic
// estimate gives the exact answer there), so the line sets are also held to
// stored-line Multipath on the shipped ROOM, whose lamp in its shade is a
// subscene: per object (those of 100 faces or more with 1 % of the
// reflected power or more), the mean reflected radiosity of either method at
// the same seed differs by noise alone. The noise of an object's mean is
// estimated from two Multipath seeds, face by face (sigma^2 = sum a^2 (m1 -
// m2)^2 / 2 / (sum a m)^2), and the difference of the two methods, averaged
// over both seeds, must be within 4 sigma (each method's error of the mean
// has about sigma; the two seeds halve the variance of the difference). A
// transport that moved power between classes of exchanges put the shade
// 5 % (7 sigma) too bright here.
TEST(LineSets, AgreeWithMultipathObjectByObjectOnTheShippedRoom) {
  TempDir dir;
  struct Run {
    PatchMesh mesh;
    std::vector<double> reflected;  // per face
  };
  const auto solve = [&](SolverMethod method, unsigned seed) {
    Options o = load_options(std::string(MPATH_SOURCE_DIR) + "/configs/room.toml", {});
    o.solver.method = method;
    o.lines.total = 500'000;
    o.first_shot.lines = 500'000;
    o.lines.seed = seed;
    o.solver.threads = 2;
    o.store.dir = dir / ("store" + std::to_string(seed) + (method == SolverMethod::multipath ? "m" : "h"));
    test::StoredSolve s = test::solve_stored(o);
    EXPECT_TRUE(s.log.converged);
    if (method == SolverMethod::hierarchical) {
      EXPECT_GE(s.boxes, 2u);
    }
    Run r;
    for (size_t f = 0; f < s.mesh.face_count(); ++f)
      r.reflected.push_back(s.state.radiosity(s.mesh, f)[0] - s.state.face_exitance(f)[0]);
    r.mesh = std::move(s.mesh);
    return r;
  };
  const Run m1 = solve(SolverMethod::multipath, 1), m2 = solve(SolverMethod::multipath, 2);
  const Run h1 = solve(SolverMethod::hierarchical, 1), h2 = solve(SolverMethod::hierarchical, 2);
  const PatchMesh& mesh = m1.mesh;
  ASSERT_EQ(mesh.face_count(), h1.mesh.face_count());
  int objects = 0;
  for (const Patch& p : mesh.patches) objects = std::max(objects, p.object + 1);
  std::vector<double> power(objects, 0.0), noise(objects, 0.0), difference(objects, 0.0), faces(objects, 0.0);
  double total = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const int o = mesh.patches[mesh.face_patch[f]].object;
    const double a = mesh.face_area(static_cast<int>(f));
    power[o] += a * m1.reflected[f];
    total += a * m1.reflected[f];
    noise[o] += a * a * (m1.reflected[f] - m2.reflected[f]) * (m1.reflected[f] - m2.reflected[f]) / 2;
    difference[o] += a * ((h1.reflected[f] - m1.reflected[f]) + (h2.reflected[f] - m2.reflected[f])) / 2;
    faces[o] += 1;
  }
  int checked = 0;
  for (int o = 0; o < objects; ++o) {
    if (faces[o] < 100 || power[o] < 0.01 * total) continue;
    const double sigma = std::sqrt(noise[o]) / power[o];
    const double relative = difference[o] / power[o];
    EXPECT_LT(std::fabs(relative), 4 * sigma) << "object " << o << " (" << faces[o] << " faces): hierarchical - "
                                              << "multipath = " << relative << " of its mean, sigma " << sigma;
    ++checked;
  }
  EXPECT_GE(checked, 5);
}

}  // namespace
}  // namespace mpath
