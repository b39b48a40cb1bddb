// Benchmark: the hierarchy build (grouping) of a scene, wall and CPU seconds,
// with the spatial grid mpath uses and, when asked, by comparing every pair
// (the quadratic reference), checking that both give the same boxes. The
// emitters are marked as mpath-preprocess marks them (with the default pilot
// budget: bright subscenes), and the build is timed once more without them.
// Writes one JSON record.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <ctime>
#include <fstream>
#include <nlohmann/json.hpp>

#include "config.h"
#include "hierarchy.h"
#include "mpath_version.h"
#include "prepared_scene.h"
#include "store_identity.h"

namespace {

using namespace mpath;

struct Timed {
  Hierarchy h;
  double wall = 0, cpu = 0;
};

Timed timed_build(const PatchMesh& mesh, const HierarchyOptions& options, bool all_pairs,
                  const std::vector<uint8_t>& emitting) {
  const auto w0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();  // the process's CPU time, every thread
  Timed t;
  t.h = build_hierarchy(mesh, options, false, all_pairs, emitting);
  t.cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
  t.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"mpath hierarchy-build benchmark"};
  std::string config, out;
  std::vector<std::string> overrides;
  bool all_pairs = false;
  app.add_option("config", config)->required();
  app.add_option("overrides", overrides);
  app.add_flag("--all-pairs", all_pairs, "also build by comparing every pair, and compare the hierarchies");
  app.add_option("--out", out, "JSON file to write")->required();
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::warn);
  const Options options = load_options(config, overrides);
  const PreparedScene prepared = prepare_scene(options);
  const std::vector<uint8_t> emitting = grouping_emitters(options, prepared.mesh, prepared.scene);
  const Timed grid = timed_build(prepared.mesh, options.hierarchy, false, emitting);
  const Timed unlit = timed_build(prepared.mesh, options.hierarchy, false, {});
  nlohmann::json j = {{"mpath", std::string(MPATH_VERSION) + " (" + MPATH_GIT_COMMIT + ")"},
                      {"scene", options.scene.file.string()},
                      {"polygons", prepared.scene.polygons.size()},
                      {"objects", prepared.scene.objects.size()},
                      {"patches", prepared.mesh.patches.size()},
                      {"boxes", grid.h.boxes.size()},
                      {"grid_wall_s", grid.wall},
                      {"grid_cpu_s", grid.cpu},
                      {"emitters_marked", !emitting.empty()},
                      {"unmarked_boxes", unlit.h.boxes.size()},
                      {"unmarked_wall_s", unlit.wall},
                      {"unmarked_cpu_s", unlit.cpu}};
  if (all_pairs) {
    const Timed all = timed_build(prepared.mesh, options.hierarchy, true, emitting);
    j["all_pairs_wall_s"] = all.wall;
    j["all_pairs_cpu_s"] = all.cpu;
    j["same"] = describe_hierarchy(all.h, {}) == describe_hierarchy(grid.h, {}) && all.h.patch_box == grid.h.patch_box;
  }
  std::ofstream(out) << j.dump(2) << "\n";
  return 0;
}
