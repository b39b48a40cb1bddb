// The first shot: local lines from every emitting face, cosine distributed,
// in number proportional to its emitted power; the nearest face hit keeps rho
// of the power as accumulated and unshot power (docs/method.md, 7).
#pragma once

#include <cstdint>
#include <vector>

#include "config.h"
#include "luminaire.h"
#include "radiosity_state.h"
#include "sampling.h"
#include "tracer.h"
#include "transport.h"

namespace mpath {

struct FirstShotStats {
  uint64_t lines = 0;
  uint64_t emitter_faces = 0;      // faces shot with local lines
  uint64_t global_emitter_faces = 0; // faces whose emission was left to the global lines
  uint64_t associated_hits = 0;      // accelerated: lines ended on an associated patch
  double seconds = 0;
};

// `global_crossings`: per face, how many global lines of the first pass cross
// it (empty: every emitter is shot with local lines). An emitting face that
// global lines cross more often than it would get local lines keeps its
// emission as unshot power for the global passes, which sample it better at
// no extra tracing cost (docs/algorithm.md).
// The `global_crossings` that first_shot.mode asks for, from per-face
// crossing counts of the first pass (forecast or counted).
std::vector<double> emitter_crossings(const Options& options, std::vector<double> crossings);

class SubsceneNearest;

// One local line from `face`: a uniform point of its patch, a cosine-
// distributed direction; `power` goes to the face the line meets first
// (`nearest(patch, org, dir)`), escaping when it meets none.
template <typename Nearest>
void shoot_local_line(const PatchMesh& mesh, const RadiosityState& state, int face, const double* power, Rng& rng,
                      const Nearest& nearest, ShardAccumulator& acc) {
  const int patch = mesh.face_patch[face];
  const Vec3 n = mesh.face_normal(face);
  const Vec3 org = uniform_point(mesh, mesh.patches[patch], rng);
  if (mesh.may_touch(patch)) {
    // Where the face touches another, a line along the normal meets it at
    // distance 0, whatever the direction the cosine draws next (grazing
    // lines may slip past a surface at distance 0).
    const NearestHit probe = nearest(patch, org, n);
    if (probe.patch >= 0 && mesh.touching(patch, probe.patch)) {
      receive_in_contact(state, face, mesh.face_met(probe.patch, n), power, acc);
      return;
    }
  }
  const Vec3 dir = cosine_direction(n, rng);
  const NearestHit hit = nearest(patch, org, dir);
  if (hit.patch < 0) {
    for (int c = 0; c < state.channels; ++c) acc.escaped[c] += power[c];
    return;
  }
  const int met = mesh.face_met(hit.patch, dir);
  if (mesh.touching(patch, hit.patch)) receive_in_contact(state, face, met, power, acc);
  else receive(state, met, power, acc);
}

// A point source ([[light]]): its radiant power is added to the emitted
// energy and shot along `lines` lines from its position, drawn in
// proportion to its intensity, each carrying an equal share of its power to
// the face it meets first. Returns the lines shot.
uint64_t shoot_light(const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state, const PointLight& light,
                     long long lines, unsigned long long seed, int shards);

// `accelerated`: find nearest hits through the subscenes' associated patches
// (first_shot.accelerate) instead of the whole scene's tracer.
FirstShotStats first_shot(const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state, long long lines,
                          unsigned long long seed, int shards, const std::vector<double>& global_crossings = {},
                          const SubsceneNearest* accelerated = nullptr);

}  // namespace mpath
