// Grids of illuminance sensors ([[grid]]): irradiance gathered from the
// solved radiosities, against analytic values, and the files a run writes.
#include "photometry.h"

#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "color.h"
#include "test_util.h"

namespace mpath {
namespace {

using test::TempDir;

// Every face of the state at radiosity B (W/m2), whatever was solved.
void set_radiosity(RadiosityState& state, const PatchMesh& mesh, double b) {
  for (size_t f = 0; f < mesh.face_count(); ++f)
    for (int c = 0; c < state.channels; ++c) state.phi[state.at(f, c)] = b * mesh.face_area(static_cast<int>(f));
}

// A grid of nu x nv points on the rectangle origin + s u + t v.
GridOptions grid(const Vec3& origin, const Vec3& u, const Vec3& v, int nu, int nv, int samples, const Vec3& normal = {}) {
  GridOptions g;
  g.origin = origin;
  g.u = u;
  g.v = v;
  g.nu = nu;
  g.nv = nv;
  g.samples = samples;
  g.normal = normal;
  return g;
}

// test::furnace_scene (rho 0.5, the given exitance) with every face at
// radiosity B, and its tracer.
struct UniformRoom {
  PatchMesh mesh;
  RadiosityState state;
  Tracer tracer;
  UniformRoom(double exitance, double b)
      : mesh(build_mesh(test::furnace_scene(0.5, exitance), 0.05)),
        state(make_state(test::furnace_scene(0.5, exitance), mesh)),
        tracer(mesh) {
    set_radiosity(state, mesh, b);
  }
};

// In a closed room whose every face has radiosity B, a sensor anywhere inside
// facing any way sees B in every direction: with no emission its irradiance
// is B exactly (every cosine ray, whatever the sample count), its illuminance
// 179 B. Points on a surface (the floor, facing up) read the same. (The grids
// avoid the furniture of test::furnace_scene.)
TEST(Photometry, ClosedFurnaceReadsItsRadiosityEverywhere) {
  const UniformRoom room(0.0, 2.5);
  const PatchMesh& mesh = room.mesh;
  const RadiosityState& state = room.state;
  const Tracer& tracer = room.tracer;
  for (const Vec3 normal : {Vec3{0, 0, 0}, Vec3{0, 0, 1}, Vec3{0, 0, -1}, Vec3{1, 0.3, 0}, Vec3{-0.2, 1, 0.5}}) {
    // On the floor facing up, else in the air.
    const GridOptions g = grid({0.35, 0.05, normal.z > 0 ? 0.0 : 0.2}, {0.8, 0, 0}, {0, 0.9, 0}, 7, 5, 256, normal);
    const GridResult r = measure_grid(g, mesh, tracer, state, {}, 1);
    ASSERT_EQ(r.points.size(), 35u);
    for (const GridPoint& p : r.points) {
      EXPECT_NEAR(p.irradiance[0], 2.5, 1e-12) << p.position.x << ", " << p.position.y;
      EXPECT_NEAR(p.illuminance, 179 * 2.5, 1e-9);
    }
  }
  // A point inside the floating cube sees only its black backs: covered, and
  // left out of the figures.
  const GridOptions g = grid({0.4, 0.6, 0.45}, {0.6, 0, 0}, {0, 0.01, 0}, 2, 1, 64);
  const GridResult r = measure_grid(g, mesh, tracer, state, {}, 1);
  EXPECT_TRUE(r.points[0].covered);
  EXPECT_EQ(r.points[0].illuminance, 0.0);
  EXPECT_FALSE(r.points[1].covered);
  EXPECT_EQ(r.covered, 1u);
  EXPECT_NEAR(r.min_lux, 179 * 2.5, 1e-9);
}

// The same room where every face emits (exitance 1 of B = 2.5): the
// emission is then gathered by both strategies, weighed by the balance
// heuristic, and the reading is B within its noise. The noise is measured
// from 8 seeds at each point (sigma of one reading); every reading within
// 5 sigma, their mean within 4 sigma / sqrt(readings).
TEST(Photometry, EmissionSeenByBothStrategiesIsUnbiased) {
  const UniformRoom room(1.0, 2.5);
  const PatchMesh& mesh = room.mesh;
  const RadiosityState& state = room.state;
  const Tracer& tracer = room.tracer;
  const GridOptions g = grid({0.35, 0.05, 0.2}, {0.8, 0, 0}, {0, 0.9, 0}, 4, 3, 1024, {0.3, -0.2, 1});
  std::vector<double> readings;
  for (unsigned seed = 1; seed <= 8; ++seed)
    for (const GridPoint& p : measure_grid(g, mesh, tracer, state, {}, seed).points) readings.push_back(p.irradiance[0]);
  const test::SampleStats stats = test::sample_stats(readings);
  const double sigma = std::sqrt(stats.variance);
  EXPECT_LT(sigma, 0.05 * 2.5) << "the two strategies together should be far less noisy than either";
  EXPECT_NEAR(stats.mean, 2.5, 4 * sigma / std::sqrt(readings.size()));
  for (double r : readings) EXPECT_NEAR(r, 2.5, 5 * sigma);
}

// A sensor under the centre of an emitting square (side 2a, radiosity M, at
// height h, nothing else in the scene) reads E = M F, F the form factor of a
// point to a parallel square centred above it: four times that of a corner
// rectangle a x a, (1 / 2 pi) (X / sqrt(1 + X^2) atan(X / sqrt(1 + X^2)) x 2)
// with X = a / h. The estimate of N cosine-distributed rays is binomial:
// within 4 sigma, sigma = M sqrt(F (1 - F) / N).
TEST(Photometry, SensorUnderAnEmittingSquareReadsItsFormFactor) {
  Scene scene;
  const int lamp = test::add_material(scene, "lamp", 0.0, 1.0);
  test::add_object(scene, "lamp");
  const double a = 0.5, h = 0.8;
  scene.polygons.push_back(Polygon{{{-a, -a, h}, {-a, a, h}, {a, a, h}, {a, -a, h}}, lamp, 0});  // facing down
  const PatchMesh mesh = build_mesh(scene, 0.01);
  RadiosityState state = make_state(scene, mesh);
  set_radiosity(state, mesh, 3.0);
  const Tracer tracer(mesh);
  const double x = a / h, s = std::sqrt(1 + x * x);
  const double f = 4 * (1 / (2 * std::numbers::pi)) * 2 * (x / s) * std::atan(x / s);
  for (const int samples : {1024, 16384}) {
    const GridOptions g = grid({-1e-3, -1e-3, 0}, {2e-3, 0, 0}, {0, 2e-3, 0}, 1, 1, samples);
    const GridResult r = measure_grid(g, mesh, tracer, state, {}, 7);
    const double sigma = 3.0 * std::sqrt(f * (1 - f) / samples);
    EXPECT_NEAR(r.points[0].irradiance[0], 3.0 * f, 4 * sigma) << samples << " samples, F = " << f;
  }
}

// A run with [[grid]]: NAME.csv (a row per point), NAME.png and the grid's
// figures in report.json; in a closed furnace (rho 0.5, exitance 1 on every
// face: B = 2 exactly) the sensors read 2 W/m2 (358 lx) within the solve's
// own noise, here about 1 % per face, averaged over the many faces a sensor
// sees.
TEST(Photometry, RunWritesTheGridsFilesAndFigures) {
  TempDir dir;
  std::string obj = "mtllib f.mtl\nusemtl grey\n";
  const double lo[3] = {0, 0, 0}, hi[3] = {4, 3, 2.5};
  int v = 0;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      double c[4][3];
      for (int k = 0; k < 4; ++k) {
        c[k][axis] = side ? hi[axis] : lo[axis];
        c[k][u] = (k == 1 || k == 2) ? hi[u] : lo[u];
        c[k][w] = (k >= 2) ? hi[w] : lo[w];
      }
      for (int k = 0; k < 4; ++k) obj += fmt::format("v {} {} {}\n", c[k][0], c[k][1], c[k][2]);
      // Counter-clockwise corners face +axis: reversed on the far side, so that every wall faces into the room.
      obj += side ? fmt::format("f {} {} {} {}\n", v + 4, v + 3, v + 2, v + 1)
                  : fmt::format("f {} {} {} {}\n", v + 1, v + 2, v + 3, v + 4);
      v += 4;
    }
  test::write_file(dir / "f.obj", obj);
  test::write_file(dir / "f.mtl", fmt::format("newmtl grey\nKd 0.5 0.5 0.5\nKe {} {} {}\n", 1 / std::numbers::pi,
                                              1 / std::numbers::pi, 1 / std::numbers::pi));
  test::write_file(dir / "run.toml", "[scene]\nfile = \"f.obj\"\n[lines]\ntotal = 400000\n[first_shot]\nlines = 400000\n"
                                     "[solver]\nmethod = \"classic\"\ntolerance = 1e-4\n[output]\ndir = \"out\"\n"
                                     "[[grid]]\nname = \"desk\"\norigin = [0.5, 0.5, 0.8]\nu = [3, 0, 0]\nv = [0, 2, 0]\n"
                                     "nu = 6\nnv = 4\nsamples = 2048\n");
  const test::RunResult r = test::run(test::solve_bin() + " " + (dir / "run.toml").string() + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string csv = test::read_file(dir / "out/desk.csv");
  std::istringstream lines(csv);
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line, "i,j,x,y,z,irradiance_W_m2,irradiance_r_W_m2,irradiance_g_W_m2,irradiance_b_W_m2,illuminance_lux,covered");
  int rows = 0;
  while (std::getline(lines, line)) {
    ++rows;
    std::vector<double> cells;
    std::istringstream in(line);
    for (std::string cell; std::getline(in, cell, ',');) cells.push_back(std::stod(cell));
    ASSERT_EQ(cells.size(), 11u) << line;
    EXPECT_EQ(cells[10], 0) << line;
    EXPECT_NEAR(cells[4], 0.8, 1e-12);
    EXPECT_NEAR(cells[5], 2.0, 0.02) << line;
    EXPECT_NEAR(cells[9], 179 * luminance({cells[6], cells[7], cells[8]}), 1e-6 * cells[9]);
  }
  EXPECT_EQ(rows, 24);
  EXPECT_TRUE(std::filesystem::file_size(dir / "out/desk.png") > 100);
  const auto report = nlohmann::json::parse(test::read_file(dir / "out/report.json"));
  ASSERT_EQ(report["grids"].size(), 1u);
  const auto& g = report["grids"][0];
  EXPECT_EQ(g["name"], "desk");
  EXPECT_EQ(g["points"], 24);
  EXPECT_NEAR(g["illuminance_lux"]["mean"].get<double>(), 358, 0.01 * 358);
  EXPECT_LE(g["illuminance_lux"]["min"].get<double>(), g["illuminance_lux"]["mean"].get<double>());
  EXPECT_NEAR(g["uniformity"].get<double>(),
              g["illuminance_lux"]["min"].get<double>() / g["illuminance_lux"]["mean"].get<double>(), 1e-12);
  EXPECT_GT(g["uniformity"].get<double>(), 0.97);
  // Per material: in a closed furnace the area mean of B is E / (1 - rho)
  // exactly once converged (what is absorbed, (1 - rho) B A summed, is what
  // is emitted), up to the unshot power left at solver.tolerance.
  ASSERT_EQ(report["materials"].size(), 1u);
  const auto& m = report["materials"][0];
  EXPECT_EQ(m["name"], "grey");
  EXPECT_NEAR(m["area_m2"].get<double>(), 2 * (4 * 3 + 4 * 2.5 + 3 * 2.5), 1e-9);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(m["exitance_W_m2"][c].get<double>(), 1.0, 1e-9);
    EXPECT_NEAR(m["radiosity_W_m2"][c].get<double>(), 2.0, 2.0 * 2e-4);
  }
  EXPECT_NEAR(m["luminance_cd_m2"].get<double>(), 179 * 2.0 / std::numbers::pi, 179 * 2.0 / std::numbers::pi * 2e-4);

  // output.grids = false: the same run without the grids' files and figures.
  const test::RunResult off = test::run(test::solve_bin() + " " + (dir / "run.toml").string() +
                                        " -q output.grids=false output.dir=\"" + (dir / "off").string() + "\"");
  ASSERT_EQ(off.exit_code, 0) << off.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "off/desk.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir / "off/desk.png"));
  EXPECT_TRUE(std::filesystem::exists(dir / "off/solution.ply"));
  EXPECT_EQ(nlohmann::json::parse(test::read_file(dir / "off/report.json"))["grids"].size(), 0u);
}

TEST(Photometry, GridConfigIsChecked) {
  TempDir dir;
  test::write_file(dir / "s.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const auto error_of = [&](const std::string& grid) {
    test::write_file(dir / "run.toml", "[scene]\nfile = \"s.obj\"\n[scene.emitters]\ndefault = 1\n" + grid);
    return test::run(test::solve_bin() + " " + (dir / "run.toml").string() + " --dry-run -q");
  };
  test::RunResult r = error_of("[[grid]]\nname = \"a\"\norigin = [0, 0, 0]\nu = [1, 0, 0]\n");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("grid 0 needs `origin`, `u` and `v`"), std::string::npos) << r.output;
  r = error_of("[[grid]]\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [2, 0, 0]\n");
  EXPECT_NE(r.output.find("u and v are parallel"), std::string::npos) << r.output;
  r = error_of("[[grid]]\nname = \"../x\"\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\n");
  EXPECT_NE(r.output.find("is not a plain file name"), std::string::npos) << r.output;
  r = error_of("[[grid]]\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\nnu = 0\n");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  r = error_of("[[grid]]\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\nwidth = 3\n");
  EXPECT_NE(r.output.find("unknown key"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace mpath
