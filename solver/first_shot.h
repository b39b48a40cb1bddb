// The first shot: local lines from every emitting face, cosine distributed,
// in number proportional to its emitted power; the nearest face hit keeps rho
// of the power as accumulated and unshot power (design.md section 7).
#pragma once

#include <cstdint>

#include "radiosity_state.h"
#include "tracer.h"

namespace mpath {

struct FirstShotStats {
  uint64_t lines = 0;
  uint64_t emitter_faces = 0;
  double seconds = 0;
};

FirstShotStats first_shot(const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state, long long lines,
                          unsigned long long seed, int shards);

}  // namespace mpath
