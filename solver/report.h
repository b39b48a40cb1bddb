// report.json of mpath-solve: what a run did, assembled from what each step
// measured (docs/user-guide.md, "Outputs").
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "box_store.h"
#include "config.h"
#include "first_shot.h"
#include "second_shot.h"
#include "hierarchical.h"
#include "iteration.h"
#include "prepared_scene.h"
#include "radiosity_state.h"

namespace mpath {

// Seconds per phase of a solve.
struct SolveTimings {
  double store = 0, bvh = 0, iterations = 0, outputs = 0, total = 0;
};

// What a solve measured, for its report.
struct SolveRecord {
  std::string command_line;
  int threads = 1;
  int ranks = 1;  // MPI ranks that shared the passes
  SolveTimings timings;
  FirstShotStats shot;
  SecondShotStats second_shot;
  LightsShotStats lights_shot;
  // How the first shot's lines were set when first_shot.lines is 0: "pilot"
  // (this run's), "store" (the store's first shot), else "config".
  std::string shot_lines_from = "config";
  double shot_share = 0;      // the pilot's share of lines.total (0: no pilot ran)
  double pilot_seconds = 0;
  bool resumed = false;
  IterationLog iterations;
  uint64_t hits_before = 0;      // hits of passes restored from a checkpoint (not timed by this run)
  uint64_t uncarried_lines = 0;  // local lines for power no stored line can carry
  std::vector<BoxPassStats> box_stats;
  std::vector<std::string> outputs;
  nlohmann::json grids = nlohmann::json::array();  // photometric grids' figures
  struct Light {
    std::string name;
    double flux_lm = 0, power_W = 0;
    uint64_t first_shot_lines = 0;  // 0 when resumed from a checkpoint
  };
  std::vector<Light> lights;
  std::vector<std::string> warnings;  // of the solve itself, after the scene's
};

// `store` is null for the classic method.
nlohmann::json solve_report(const Options& options, const PreparedScene& prepared, const RadiosityState& state,
                            const BoxStore* store, const SolveRecord& record);

}  // namespace mpath
