// The one options struct of mpath, loaded from a TOML config file with
// command-line key=value overrides, validated key by key.
#pragma once

#include <array>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "hierarchy_options.h"
#include "scene_readers.h"
#include "vec3.h"

namespace mpath {

struct CameraOptions {
  std::string name = "camera";
  Vec3 position{0, 0, 1};
  Vec3 look_at{0, 0, 0};
  Vec3 up{0, 1, 0};
  double fov_deg = 40.0;      // vertical field of view
  int width = 512;
  int height = 512;
  int samples = 4;            // jittered primary rays per pixel
  double exposure = 0.0;      // PNG pixel = radiance * 2^exposure (an attribute of the EXR)
};

// A grid of illuminance sensors (a work plane): nu x nv points at the centres
// of equal cells of the rectangle origin + s u + t v, s and t in [0, 1],
// each facing `normal` (zero: u x v normalised).
struct GridOptions {
  std::string name = "grid";
  Vec3 origin{0, 0, 0};
  Vec3 u{1, 0, 0};
  Vec3 v{0, 1, 0};
  int nu = 10;
  int nv = 10;
  Vec3 normal{0, 0, 0};
  int samples = 4096;  // gathering rays per point
};

// How mpath-solve solves (solver.method).
enum class SolverMethod {
  hierarchical,  // stored lines of the hierarchy of subscenes
  multipath,     // stored lines of the root box alone
  classic,       // fresh global lines traced on the fly, no store
};
const char* to_string(SolverMethod method);

struct Options {
  std::filesystem::path config_file;

  using Scene = SceneOptions;
  Scene scene;

  struct Mesh {
    double max_patch_area = 0.0;  // 0: automatic, scene box area / 2000
    int curve_segments = 16;      // MGF curved primitives: segments around a circle
    bool split_contacts = false;  // polygons pressed against another split at the contact (contact.h)
    double contact_min_area = 0;  // contacts of at most this area are left whole; 0: max_patch_area
  } mesh;

  using Hierarchy = HierarchyOptions;
  Hierarchy hierarchy;

  using Lines = LineOptions;
  Lines lines;

  struct FirstShot {
    long long lines = 0;  // 0: set by a pilot (first_shot_lines)
    // Not a config key: the lines the programs chose from the pilot (or a
    // store records) when `lines` is 0; 0 until then.
    long long chosen = 0;
    bool accelerate = false;
    // "auto": an emitter face that the first pass of global lines crosses more
    // often than it would get local lines is shot by the global lines;
    // "local": every emitter face is shot with local lines.
    std::string mode = "auto";
    // "halton": an emitter's lines take the points of a randomised Halton
    // sequence of its own (stratified); "random": independent points.
    std::string sequence = "halton";
    bool halton() const { return sequence == "halton"; }
  } first_shot;

  struct SecondShot {
    // Local lines of the second shot, as a share of lines.total: after the
    // first shot the faces holding the most unshot power for their size
    // shoot it with local lines (second_shot.h); 0: no second shot.
    double share = 0.25;
  } second_shot;

  struct Solver {
    SolverMethod method = SolverMethod::hierarchical;
    int iterations = 100;  // a cap: runs stop at solver.tolerance (high reflectance needs tens)
    double tolerance = 1e-3;
    // Stored-line methods: later iterations stream a share of each box's
    // lines in proportion to the power left (docs/algorithm.md).
    bool adaptive_lines = true;
    // Order of the box passes in an iteration: "v-cycle" (subscenes deepest
    // first, the root, then top-down) or "top-down" (MP(root) of paper figure 5).
    std::string schedule = "v-cycle";
    int threads = 0;  // 0: all hardware threads
    // Every pass splits its work into this many shards (fewer when a box has
    // fewer chunks), merged in shard order: the answer does not depend on
    // the threads or MPI ranks that run them (docs/algorithm.md).
    int shards = 8;
    // A checkpoint after the first shot, then after a pass only where the
    // last was written at least this long ago (wall seconds; 0: after every
    // pass), and after the last pass (docs/user-guide.md, on checkpoint.bin).
    double checkpoint_seconds = 30;
  } solver;

  struct Store {
    std::filesystem::path dir = "store";
    int chunk_lines = 65536;  // lines per compressed chunk
    int zstd_level = 3;       // zstd compression level of chunks (docs/performance.md, "The store")
  } store;

  struct Output {
    std::filesystem::path dir = "results";
    bool exr = true;  // an EXR per camera
    bool png = true;  // and a tone-mapped PNG preview beside it
    bool grids = true;  // the [[grid]] illuminance measurements
  } output;

  std::vector<CameraOptions> cameras;
  std::vector<GridOptions> grids;
};

// Loads `config_path` and applies `overrides` ("dotted.key=value"). Paths in the
// file are relative to the file; paths given on the command line are relative
// to the working directory. Throws InputError naming the key on any problem.
Options load_options(const std::filesystem::path& config_path,
                     const std::vector<std::string>& overrides);

// The effective configuration as TOML text (for --print-config and logs).
std::string options_to_toml(const Options& options);

// The effective configuration as JSON text (for report.json).
std::string options_to_json(const Options& options);

// Local lines of the first shot: first_shot.lines; where it is 0,
// first_shot.chosen (the pilot's or the store's count), else half of
// lines.total (at least 10,000), so that the first shot's noise falls with
// the line budget (docs/algorithm.md, "First shot", "First-shot share").
long long first_shot_lines(const Options& options);
// The first-shot lines for a share of lines.total the pilot chose (at least
// 10,000); where it had none (nothing emits), first_shot_lines of `options`,
// whose first_shot.chosen is not yet set: half of lines.total.
long long first_shot_lines_for_share(const Options& options, double share);

// Number of worker threads the options ask for.
int effective_threads(const Options& options);

}  // namespace mpath
