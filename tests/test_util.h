// Helpers shared by the tests: scenes built in code, temporary folders,
// running the programs, and an in-memory solve.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "classic.h"
#include "config.h"
#include "first_shot.h"
#include "mesh.h"
#include "radiosity_state.h"
#include "scene.h"
#include "tracer.h"

namespace mpath::test {

// A fresh directory under the system temp dir, removed at destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

void write_file(const std::filesystem::path& path, const std::string& text);
std::string read_file(const std::filesystem::path& path);

struct RunResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};
RunResult run(const std::string& command);
std::string solve_bin();
// Path of one of mpath's programs ("mpath-preprocess", "mpath-compare", ...).
std::string program_bin(const std::string& name);
std::filesystem::path shared_scenes();
// A scene under ../shared/scenes (the public scenes the project is cloned
// beside); when it is absent the test fails with what is missing and how to
// get it, and the path is empty.
std::filesystem::path shared_scene(const std::string& relative);

// The mean of independent samples and their unbiased variance (n - 1 in the
// denominator; at least two samples): a test's standard error is
// sqrt(variance / n).
struct SampleStats {
  double mean = 0, variance = 0;
};
SampleStats sample_stats(const std::vector<double>& x);

int add_material(Scene& scene, const std::string& name, double rho, double radiance, bool two_sided = false);
int add_object(Scene& scene, const std::string& name);
void add_quad(Scene& scene, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, int material, int object);
// Axis-aligned box; faces point out of it, or into it when `inward`.
void add_box(Scene& scene, const Vec3& lo, const Vec3& hi, bool inward, int material, int object);

// A closed room 2 x 1.5 x 1 with a floating cube, a block resting on the
// floor and a column standing in a corner from floor to ceiling; every
// surface has reflectance rho and emits exitance `exitance`.
Scene furnace_scene(double rho, double exitance);

// An in-memory classic solve, the same steps as mpath-solve.
struct Solved {
  PatchMesh mesh;
  RadiosityState state;
  IterationLog log;
};
// `contacts` false: the mesh forgets which surfaces touch (what mpath did
// before it knew them), for tests that show a check can fail.
Solved solve_classic_in_memory(const Scene& scene, const Options& options, bool contacts = true);

// A table of separate objects (top and four legs) standing on the floor z = 0
// with its top's corner at (x, y); its legs are well inside the top's
// outline, so the five group into one subscene.
void add_table(Scene& scene, double x, double y, int material, const std::string& name);

// Writes the scene as OBJ + MTL (`stem`.obj and `stem`.mtl); returns the OBJ path.
std::filesystem::path write_obj(const Scene& scene, const std::filesystem::path& stem);

// Preprocesses `options` (its scene file and store.dir set) into a store and
// solves it with the stored-line solver as mpath-solve does; the state after
// each iteration is checked by `after_each` when given.
struct StoredSolve {
  PatchMesh mesh;
  RadiosityState state;
  IterationLog log;
  size_t boxes = 0;
  int depth = 0;  // of the hierarchy
};
StoredSolve solve_stored(const Options& options,
                         const std::function<void(const RadiosityState&)>& after_each = {});

// Options for in-memory solves: given lines, seed 1, 2 threads.
Options test_options(long long global_lines, long long local_lines, double max_patch_area);

}  // namespace mpath::test
