// The second shot: after the first shot, the faces that hold the most unshot
// power for their size (a lamp's shade lit by its bulb at close range, a
// ceiling patch above an uplight) shoot it with local lines, as the first
// shot shoots the emitters, instead of leaving it to the global lines, which
// cross such small faces seldom and so carry their power to the room in few,
// heavy portions (docs/algorithm.md, "Second shot").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "config.h"
#include "first_shot.h"
#include "radiosity_state.h"
#include "tracer.h"

namespace mpath {

struct SecondShotStats {
  uint64_t lines = 0;
  uint64_t faces = 0;        // faces shot
  double power_share = 0;    // of the unshot power after the first shot, the share these faces held
  double seconds = 0;
  bool halton = true;
  bool stored = false;          // read from the store's second_shot.bin instead of traced
  std::string traced_because;   // why a solve on a store traced it
};

// Which faces shoot and how many lines each: `budget` local lines shared by
// unshot power among the largest set of faces in which each face's share of
// them exceeds its crossings `crossings[f]` by the first pass's global lines
// (a face the global lines cross more often than it would get local lines
// is left to them, as first_shot.mode = "auto" leaves emitters). Empty when
// nothing is unshot or no face qualifies.
FirstShotPlan plan_second_shot(const RadiosityState& state, long long budget, const std::vector<double>& crossings,
                               bool halton);

class BoxStore;

// The plan of a run's second shot: second_shot.share of lines.total, against
// the crossings of the root's lines of `store` (those that carry power
// across the scene) or, without one, a forecast of a classic first pass.
FirstShotPlan plan_run_second_shot(const Options& options, const PatchMesh& mesh, const RadiosityState& state,
                                   const BoxStore* store);
// The same with the crossings given: the root's (BoxStore::root_crossings),
// for a store not opened.
FirstShotPlan plan_run_second_shot(const Options& options, const RadiosityState& state,
                                   const std::vector<double>& crossings);

// The second shot of `plan`: each face's unshot power leaves it along its
// lines in equal parts, and the faces met keep rho of it as radiosity and
// unshot power (the first shot's transport); a line that starts where the
// face touches another surface leaves its part unshot, as a pass's touching
// crossing does (what a face reflects does not enter a contact). Its own
// random streams (second_shot_stream(seed)); the same result on any number
// of threads, shards or ranks.
SecondShotStats second_shot(const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state,
                            const FirstShotPlan& plan, unsigned long long seed, int shards);

// The parts of second_shot that a stored second shot (stored_shot.h) shares:
// the seed of its lines' streams; the power each line carries (per emitter
// and channel, its face's unshot power over its line count, from the state
// before the shot); adding `lines` lines of plan.emitters[e] that met
// `code`; and, once every line is in `acc`, taking the faces' unshot power
// and merging `acc` in shard order (the stats but the seconds).
unsigned long long second_shot_stream(unsigned long long seed);
std::vector<double> second_shot_line_power(const RadiosityState& state, const FirstShotPlan& plan);
void receive_second_shot_lines(const RadiosityState& state, const FirstShotPlan& plan,
                               const std::vector<double>& per_line, size_t e, uint32_t code, uint64_t lines,
                               ShardAccumulator& acc);
SecondShotStats finish_second_shot(const FirstShotPlan& plan, const std::vector<ShardAccumulator>& acc,
                                   RadiosityState& state);

}  // namespace mpath
