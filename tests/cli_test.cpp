// mpath-solve as a user runs it: outputs, flags and every error message a
// user can meet from bad input, each with exit status 1.
#include <gtest/gtest.h>

#include <gnu/libc-version.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>

#include "mpath_version.h"
#include "test_util.h"

namespace mpath {
namespace {

using test::RunResult;
using test::TempDir;
using test::write_file;

const std::string kCornell = std::string(MPATH_SOURCE_DIR) + "/configs/cornell_box.toml";

RunResult solve(const std::string& args) { return test::run(test::solve_bin() + " " + args); }

bool has_temp_files(const std::filesystem::path& dir) {
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().filename().string().find(".tmp.") != std::string::npos) return true;
  return false;
}

TEST(Cli, SolvesTheDefaultSceneAndWritesEveryOutput) {
  TempDir dir;
  const RunResult r = solve(kCornell + " lines.total=200000 first_shot.lines=100000 camera.0.width=64 output.dir=" +
                            dir.path().string() + " -q");
  // camera.0.width is not a config key: arrays of tables are set in the file.
  EXPECT_NE(r.exit_code, 0);
  const RunResult ok = solve(kCornell + " lines.total=200000 first_shot.lines=100000 output.dir=" + dir.path().string() + " -q");
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  for (const char* name : {"solution.ply", "report.json", "cornell.exr", "cornell.png"})
    EXPECT_TRUE(std::filesystem::exists(dir / name)) << name;
  EXPECT_FALSE(has_temp_files(dir.path()));

  const std::string ply = test::read_file(dir / "solution.ply");
  EXPECT_EQ(ply.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  for (const char* p : {"area", "rho_r", "rho_g", "rho_b", "emit_r", "emit_g", "emit_b", "B_r", "B_g", "B_b"})
    EXPECT_NE(ply.find(std::string("property float ") + p + "\n"), std::string::npos) << p;

  const auto report = nlohmann::json::parse(test::read_file(dir / "report.json"));
  const auto& e = report["energy"];
  const double emitted = e["emitted"];
  EXPECT_GT(emitted, 0);
  EXPECT_NEAR(emitted, e["absorbed"].get<double>() + e["escaped"].get<double>() + e["unshot"].get<double>(), 1e-9 * emitted);
  EXPECT_EQ(report["config"]["solver"]["method"], "classic");
  EXPECT_EQ(report["lines"]["local"], 100000);
  for (const char* phase : {"load", "mesh", "first_shot", "iterations", "outputs", "total"})
    EXPECT_TRUE(report["timings"].contains(phase)) << phase;
  EXPECT_GT(report["memory"]["peak_rss_bytes"].get<double>(), 0);

  const std::string exr = test::read_file(dir / "cornell.exr");
  EXPECT_EQ(exr.substr(0, 4), std::string("\x76\x2f\x31\x01", 4));
  EXPECT_NE(exr.find("mpathVersion"), std::string::npos);
  EXPECT_NE(exr.find("exposure"), std::string::npos);
}

// A run stopped by the iteration cap says so in report.json, with what to do.
TEST(Cli, AnUnconvergedRunWarnsInItsReport) {
  TempDir dir;
  const RunResult r = solve(kCornell + " -q lines.total=20000 first_shot.lines=10000 solver.method=classic "
                            "solver.iterations=1 solver.tolerance=1e-9 output.exr=false output.png=false output.dir=" +
                            dir.path().string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("not converged"), std::string::npos) << r.output;
  const auto report = nlohmann::json::parse(test::read_file(dir / "report.json"));
  EXPECT_FALSE(report["iterations"]["converged"].get<bool>());
  bool warned = false;
  for (const auto& w : report["warnings"])
    warned |= w.get<std::string>().find("not converged: stopped at solver.iterations = 1") != std::string::npos &&
              w.get<std::string>().find("--resume") != std::string::npos;
  EXPECT_TRUE(warned) << report["warnings"].dump();
}

// Where the kernel gives transparent huge pages to memory that asks
// ("madvise") and glibc can ask (2.35 and later), mpath-solve runs itself
// again with GLIBC_TUNABLES=glibc.malloc.hugetlb=1 and its report says so;
// MPATH_HUGE_PAGES=0 or a hugetlb tunable of the user's own leaves it as it
// is, another tunable of the user's does not stop it. The answer is the same
// byte for byte.
TEST(Cli, AsksForHugePagesWhereTheKernelGivesThemOnRequest) {
  std::string mode;
  {
    std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
    std::string line;
    std::getline(in, line);
    if (line.find('[') != std::string::npos)
      mode = line.substr(line.find('[') + 1, line.find(']') - line.find('[') - 1);
  }
  int major = 0, minor = 0;
  std::sscanf(gnu_get_libc_version(), "%d.%d", &major, &minor);
  const bool can = mode == "madvise" && (major > 2 || (major == 2 && minor >= 35));
  std::string first_ply;
  for (const auto& [env, asks] : std::vector<std::pair<std::string, bool>>{
           {"env -u GLIBC_TUNABLES -u MPATH_HUGE_PAGES", can},
           {"env -u GLIBC_TUNABLES MPATH_HUGE_PAGES=0", false},
           {"env -u MPATH_HUGE_PAGES GLIBC_TUNABLES=glibc.malloc.hugetlb=0", false},
           {"env -u MPATH_HUGE_PAGES GLIBC_TUNABLES=glibc.malloc.trim_threshold=1073741824", can}}) {
    TempDir dir;
    const RunResult r = test::run(env + " " + test::solve_bin() + " " + kCornell +
                                  " -q lines.total=20000 first_shot.lines=10000 output.exr=false output.png=false "
                                  "output.dir=" + dir.path().string());
    ASSERT_EQ(r.exit_code, 0) << env << "\n" << r.output;
    const auto report = nlohmann::json::parse(test::read_file(dir / "report.json"));
    EXPECT_EQ(report["mpath"]["transparent_huge_pages"], mode);
    EXPECT_EQ(report["mpath"]["malloc_huge_pages"].get<bool>(), asks) << env;
    const std::string ply = test::read_file(dir / "solution.ply");
    if (first_ply.empty()) first_ply = ply;
    EXPECT_TRUE(ply == first_ply) << env << ": another answer";
  }
}

TEST(Cli, PrintsTheEffectiveConfigWithOverrides) {
  const RunResult r = solve(kCornell + " --print-config solver.iterations=3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("iterations = 3"), std::string::npos);
  EXPECT_NE(r.output.find("method = 'classic'"), std::string::npos) << r.output;
}

TEST(Cli, DryRunChecksConfigAndSceneWithoutWriting) {
  TempDir dir;
  const RunResult r = solve(kCornell + " --dry-run output.dir=" + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}

// Writes a config around a scene file and expects a failing run whose one-line
// error contains `expected`; no result may appear.
void expect_failure(const std::string& scene_name, const std::string& scene_text, const std::string& config_extra,
                    const std::string& overrides, const std::string& expected) {
  TempDir dir;
  if (!scene_name.empty()) write_file(dir / scene_name, scene_text);
  write_file(dir / "s.mtl", "newmtl lamp\nKd 0.5\nKe 1 1 1\n");
  write_file(dir / "run.toml", "scene.file = \"" + (scene_name.empty() ? "missing.obj" : scene_name) +
                                   "\"\nsolver.method = \"classic\"\noutput.dir = \"out\"\n" + config_extra);
  const RunResult r = solve((dir / "run.toml").string() + " -q " + overrides);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("mpath-solve: error: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(expected), std::string::npos) << "wanted: " << expected << "\ngot: " << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out/solution.ply"));
}

const std::string kTriangle = "mtllib s.mtl\nusemtl lamp\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

TEST(Cli, BadInputGivesAClearErrorAndNoResult) {
  expect_failure("", "", "", "", "missing.obj: file not found");
  expect_failure("s.obj", "mtllib s.mtl\nv 0 0 0\nv 1 0\n", "", "", "s.obj:3: malformed 'v'");
  expect_failure("s.obj", "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl wood\nf 1 2 3\n", "", "",
                 "the scene has no emitting polygon");
  expect_failure("s.obj", kTriangle, "[scene.emitters]\nwood = [1, 1, 1]\n", "", "unknown material 'wood'");
  expect_failure("s.obj", kTriangle, "", "scene.emitters.lamp=1e300",
                 "material 'lamp': emission 1e+300 W/sr/m2 is above 1e+12");
  expect_failure("s.obj", kTriangle, "[[camera]]\nname = \"../x\"\nposition = [0, 0, 5]\n", "",
                 "'camera[0].name': '../x' is not a plain file name");
  expect_failure("s.obj", "v 0 0 NaN\n", "", "", "s.obj:1: expected a finite number for z, got 'NaN'");
  expect_failure("s.obj", kTriangle, "solver.threds = 2\n", "", "run.toml:4: unknown config key 'solver.threds'");
  expect_failure("s.obj", kTriangle, "lines.total = \"many\"\n", "",
                 "config key 'lines.total': expected an integer, got a string");
  expect_failure("s.obj", kTriangle, "", "lines.total=-5", "command line: config key 'lines.total': expected a positive integer");
  expect_failure("s.obj", kTriangle, "", "solver.method=fancy", "solver.method");
  expect_failure("s.mgf", "v a =\np 0 0 0\nsph a 1 2\n", "", "", "s.mgf:3: malformed 'sph'");
  expect_failure("s.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n", "", "",
                 "unexpected end of file in element 'vertex'");
}

TEST(Cli, MissingConfigAndUnwritableOutputAreErrors) {
  RunResult r = solve("/nonexistent/run.toml");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("mpath-solve: error: /nonexistent/run.toml: config file not found"), std::string::npos)
      << r.output;
  TempDir dir;
  write_file(dir / "blocker", "a file where the output folder should go");
  r = solve(kCornell + " -q lines.total=1000 first_shot.lines=1000 output.dir=" + (dir / "blocker").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("mpath-solve: error: output.dir " + (dir / "blocker").string() + ": cannot create the folder"),
            std::string::npos)
      << r.output;
}

// Every program: --version prints its name and version; a usage error (an
// unknown flag, no config, a flag without its value) exits 1 with
// "PROGRAM: error: ..." like any other error.
TEST(Cli, EveryProgramHasVersionAndUsageErrorsExitOne) {
  for (const std::string name : {"mpath-solve", "mpath-preprocess", "mpath-compare"}) {
    const std::string bin = test::program_bin(name);
    RunResult r = test::run(bin + " --version");
    EXPECT_EQ(r.exit_code, 0) << name << ": " << r.output;
    EXPECT_EQ(r.output.rfind(name + " " + MPATH_VERSION, 0), 0u) << r.output;
    const std::string needs = name == "mpath-compare" ? "--result a --reference b " + kCornell : kCornell;
    for (const std::string& args : {needs + " --no-such-flag", std::string(), needs + " --log-level"}) {
      r = test::run(bin + " " + args);
      EXPECT_EQ(r.exit_code, 1) << name << " " << args << ": " << r.output;
      EXPECT_EQ(r.output.rfind(name + ": error: ", 0), 0u) << name << " " << args << ": " << r.output;
    }
  }
}

}  // namespace
}  // namespace mpath
