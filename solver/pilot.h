// Where a solve's error will lie, from a cheap pilot: a first shot of local
// lines from the emitters and as many global lines over the scene
// (docs/algorithm.md, "Pilot budget" and "First-shot share").
#pragma once

#include <cstdint>
#include <vector>

#include "hierarchy.h"
#include "luminaire.h"
#include "mesh.h"
#include "scene.h"
#include "tracer.h"

namespace mpath {

struct Pilot {
  // Per box of the hierarchy: the sum, over the faces whose patches the box
  // owns, of rho^2 times the mean square of the reflected radiosity the face
  // sees along global lines, which its estimate from the stored lines
  // averages (W2/m4, mean of the channels).
  std::vector<double> box_weights;
  // The area-weighted variance of the reflected radiosity (W2/m2 summed over
  // the faces, mean of the channels) times the lines that give it: of the
  // first shot's direct light (per local line), and of the first bounce that
  // the global lines carry from it (per global line of the scene's box).
  double first_shot_variance = 0;
  double global_variance = 0;
  // Whether first_shot_variance is that of stratified first shots
  // (first_shot.sequence = "halton"), measured over replicas, or of
  // independent lines.
  bool first_shot_stratified = false;
  // global_variance with each face's mean square of the radiosity it sees in
  // place of its variance: what the global lines' first bounce would add if
  // a face's crossing count varied as a Poisson count does. A pass's counts
  // vary less (the default lines are stratified, and a face sends no more
  // than its power however often it is crossed), so its first-bounce
  // variance lies between the two (test
  // PilotGlobal.APassVariesBetweenTheTwoFigures).
  double global_mean_square = 0;
  // Patch crossings per global line.
  double hits_per_line = 0;
  bool empty() const { return box_weights.empty(); }
};

// Runs about `lines` local and `lines` global lines of the scene's box
// (stream `seed`); `h` (null: the root alone) numbers the boxes of
// box_weights; `tracer`: the mesh's (null: one is built). The local lines
// leave the emitting faces and the point sources `lights`, each in
// proportion to its power: `stratified` (first_shot.sequence = "halton"),
// as the first shot does, in 8 replicas of an eighth of the lines each with
// Halton points shifted anew, whose spread is the first shot's variance
// (where every emitter has 4 lines a replica or more; else, and without
// `stratified`, independent lines and their Poisson variance). Empty when
// nothing in the scene emits. The same, bit for bit, on any number of
// threads and in every shard.
Pilot run_pilot(const Scene& scene, const PatchMesh& mesh, const Hierarchy* h, unsigned long long seed,
                uint64_t lines, bool stratified, const Tracer* tracer = nullptr,
                const std::vector<PointLight>& lights = {});

// Pilot::box_weights of run_pilot (stratified).
std::vector<double> pilot_weights(const Scene& scene, const PatchMesh& mesh, const Hierarchy& h,
                                  unsigned long long seed, uint64_t lines);

// First-shot lines per global line that give the least error for the time:
// with error^2 = V_s / s + V_g / g for s local and g global lines, and a
// global line costing as much as c local ones, s / g = sqrt(c V_s / V_g),
// c taken as the global line's crossings (at least 1). Between 1/8 and 4;
// 0 for an empty pilot. On eight scenes it lands where error^2 x CPU
// seconds is least (docs/performance.md, "First-shot budget").
double first_shot_share(const Pilot& pilot);

// Logs the choice: the share, the lines and the pilot's figures behind them.
void log_first_shot_choice(const Pilot& pilot, long long first_shot_lines, long long total_lines);

}  // namespace mpath
