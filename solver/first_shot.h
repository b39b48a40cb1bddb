// The first shot: local lines from every emitting face, cosine distributed,
// in number proportional to its emitted power; the nearest face hit keeps rho
// of the power as accumulated and unshot power (design.md section 7).
#pragma once

#include <cstdint>

#include "config.h"
#include "radiosity_state.h"
#include "tracer.h"

namespace mpath {

struct FirstShotStats {
  uint64_t lines = 0;
  uint64_t emitter_faces = 0;      // faces shot with local lines
  uint64_t global_emitter_faces = 0; // faces whose emission was left to the global lines
  double seconds = 0;
};

// `global_crossings_per_area`: expected crossings of a unit-area face by the
// first pass of global lines (0: every emitter is shot with local lines). With
// it, an emitting face that global lines will cross more often than it would
// get local lines keeps its emission as unshot power for the global passes,
// which sample it better at no extra tracing cost (docs/algorithm.md).
// The `global_crossings_per_area` that first_shot.mode asks for with classic
// passes of lines.total lines over the scene box.
double classic_crossings_per_area(const Options& options, const PatchMesh& mesh);

FirstShotStats first_shot(const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state, long long lines,
                          unsigned long long seed, int shards, double global_crossings_per_area = 0);

}  // namespace mpath
