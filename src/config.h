// The one options struct of mpath, loaded from a TOML config file with
// command-line key=value overrides, validated key by key.
#pragma once

#include <array>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "vec3.h"

namespace mpath {

using Rgb = std::array<double, 3>;

struct CameraOptions {
  std::string name = "camera";
  Vec3 position{0, 0, 1};
  Vec3 look_at{0, 0, 0};
  Vec3 up{0, 1, 0};
  double fov_deg = 40.0;      // vertical field of view
  int width = 512;
  int height = 512;
  int samples = 4;            // jittered primary rays per pixel
  double exposure = 0.0;      // pixel = radiance * 2^exposure
};

struct Options {
  std::filesystem::path config_file;

  struct Scene {
    std::filesystem::path file;
    std::map<std::string, Rgb> emitters;  // material -> emitted radiance, W/sr/m2
    std::vector<std::string> two_sided;
    int mgf_default_sides = 1;  // sides of MGF materials without a `sides` entity
  } scene;

  struct Mesh {
    double max_patch_area = 0.0;  // 0: automatic, scene box area / 2000
    int curve_segments = 16;      // MGF curved primitives: segments around a circle
  } mesh;

  struct Hierarchy {
    double group_threshold = 0.4;  // docs/algorithm.md: a table and its legs group at about 0.4
    double vp_area_ratio = 16.0;
    int vp_grid = 0;  // 0: derived from vp_area_ratio
    // Largest subscene box, as a share of the scene box's surface area.
    double max_share = 0.5;
    int max_depth = 1;  // docs/algorithm.md: one level measured best
  } hierarchy;

  struct Lines {
    long long total = 1'000'000;
    double root_fraction = 2.0 / 3.0;
    // How the subscenes share the rest: "quotient" (their grouping quotient)
    // or "objects" (their object count), paper 3.3.1.
    std::string box_budget = "quotient";
    // No subscene gets fewer lines per unit of box surface than this times
    // the root's (docs/algorithm.md).
    double min_density = 1.0;
    unsigned long long seed = 1;
    std::string sequence = "halton";  // "random" or "halton" (docs/algorithm.md)
  } lines;

  struct FirstShot {
    long long lines = 1'000'000;
    bool accelerate = false;
    // "auto": an emitter face that the first pass of global lines crosses more
    // often than it would get local lines is shot by the global lines;
    // "local": every emitter face is shot with local lines.
    std::string mode = "auto";
  } first_shot;

  struct Solver {
    std::string method = "hierarchical";
    int iterations = 10;
    double tolerance = 1e-3;
    // Stored-line methods: later iterations stream a share of each box's
    // lines in proportion to the power left (docs/algorithm.md).
    bool adaptive_lines = true;
    // Order of the box passes in an iteration: "v-cycle" (subscenes deepest
    // first, the root, then top-down) or "top-down" (MP(root) of paper figure 5).
    std::string schedule = "v-cycle";
    int threads = 0;  // 0: all hardware threads
  } solver;

  struct Store {
    std::filesystem::path dir = "store";
    int chunk_lines = 65536;  // lines per compressed chunk
    int zstd_level = 6;       // zstd compression level of chunks
  } store;

  struct Output {
    std::filesystem::path dir = "results";
    bool exr = true;  // an EXR per camera
    bool png = true;  // and a tone-mapped PNG preview beside it
  } output;

  std::vector<CameraOptions> cameras;
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

// Number of worker threads the options ask for.
int effective_threads(const Options& options);

}  // namespace mpath
