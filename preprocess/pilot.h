// Where the hierarchical solve's error will lie, from a cheap pilot: a first
// shot of local lines from the emitters (docs/algorithm.md, "Pilot budget").
#pragma once

#include <cstdint>
#include <vector>

#include "hierarchy.h"
#include "mesh.h"
#include "scene.h"

namespace mpath {

// Per box of `h`: the sum, over the faces whose patches the box owns, of
// rho^2 times the mean square of the reflected radiosity the face sees along
// global lines, which its estimate from the stored lines averages (W2/m4,
// mean of the channels). The radiosity is what the emitters' direct light
// gives, from `lines` local lines; the mean square is taken over `lines`
// global lines of the root box (stream `seed`). Empty when nothing in the
// scene emits. The same on any number of threads and in every shard.
std::vector<double> pilot_weights(const Scene& scene, const PatchMesh& mesh, const Hierarchy& h,
                                  unsigned long long seed, uint64_t lines);

}  // namespace mpath
