// The first shot: local lines from every emitting face, cosine distributed,
// in number proportional to its emitted power; the nearest face hit keeps rho
// of the power as accumulated and unshot power (docs/method.md, 7).
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "config.h"
#include "luminaire.h"
#include "progress.h"
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
  bool stored = false;         // read from the store's first_shot.bin instead of traced
  bool halton = true;          // the points' sequence (first_shot.sequence, or the store's)
  std::string traced_because;  // with a store: why its first shot was not used
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
class BoxStore;

// What became of one local line, as a code: kEscaped, or the face met (-1:
// the back of a one-sided surface, which absorbs) and whether the line's face
// touches it. Codes are small integers: the stored first shot keeps them.
inline constexpr uint32_t kEscaped = 0;
inline uint32_t met_code(int met, bool contact) { return 2 * static_cast<uint32_t>(met + 1) + (contact ? 2 : 1); }
inline int code_face(uint32_t code) { return static_cast<int>((code - 1) / 2) - 1; }
inline bool code_contact(uint32_t code) { return code != kEscaped && (code - 1) % 2 == 1; }
// One past the largest code of a mesh of `faces` faces.
inline uint32_t code_limit(size_t faces) { return met_code(static_cast<int>(faces) - 1, true) + 1; }

// One local line from `face`: the point of its patch that u[0], u[1] give,
// the cosine-distributed direction of u[2], u[3] (all in [0, 1)); returns
// what it meets first (`nearest(patch, org, dir)`).
// `sampler`: the face's patch and normal (PatchSampler), made once for its lines.
template <typename Nearest>
uint32_t local_line_outcome(const PatchMesh& mesh, int face, const PatchSampler& sampler, const double u[4],
                            const Nearest& nearest) {
  const int patch = mesh.face_patch[face];
  const Vec3& n = sampler.normal();
  const Vec3 org = sampler.point(u[0], u[1]);
  if (mesh.may_touch(patch)) {
    // Where the face touches another, a line along the normal meets it at
    // distance 0, whatever the direction the cosine draws next (grazing
    // lines may slip past a surface at distance 0).
    const NearestHit probe = nearest(patch, org, n);
    if (probe.patch >= 0 && mesh.touching(patch, probe.patch)) return met_code(mesh.face_met(probe.patch, n), true);
  }
  const Vec3 dir = sampler.direction(u[2], u[3]);
  const NearestHit hit = nearest(patch, org, dir);
  if (hit.patch < 0) return kEscaped;
  return met_code(mesh.face_met(hit.patch, dir), mesh.touching(patch, hit.patch));
}

template <typename Nearest>
uint32_t local_line_outcome(const PatchMesh& mesh, int face, const double u[4], const Nearest& nearest) {
  const PatchSampler sampler(mesh, mesh.patches[mesh.face_patch[face]], mesh.face_normal(face));
  return local_line_outcome(mesh, face, sampler, u, nearest);
}

// The same with four independent numbers of `rng`.
template <typename Nearest>
uint32_t local_line_outcome(const PatchMesh& mesh, int face, Rng& rng, const Nearest& nearest) {
  double u[4];
  for (double& x : u) x = uniform(rng);
  return local_line_outcome(mesh, face, u, nearest);
}

// `power` from `face` to where a line of outcome `code` took it.
inline void receive_outcome(const RadiosityState& state, int face, uint32_t code, const double* power,
                            ShardAccumulator& acc) {
  if (code == kEscaped) {
    for (int c = 0; c < state.channels; ++c) acc.escaped[c] += power[c];
  } else if (code_contact(code)) {
    receive_in_contact(state, face, code_face(code), power, acc);
  } else {
    receive(state, code_face(code), power, acc);
  }
}

// One local line from `face` carrying `power` to the face it meets first,
// escaping when it meets none.
template <typename Nearest>
void shoot_local_line(const PatchMesh& mesh, const RadiosityState& state, int face, const double* power, Rng& rng,
                      const Nearest& nearest, ShardAccumulator& acc) {
  receive_outcome(state, face, local_line_outcome(mesh, face, rng, nearest), power, acc);
}

// Unshot power the global lines cannot move (on faces no stored line
// crosses, or that no line of a classic pass crossed: a polygon hidden under
// a coplanar one, a patch too small for the pass) is shot with
// kUncarriedLines local lines per face, like the first shot; their points
// and directions come from stream kUncarriedStream, keyed by the pass and
// the face, so that threads and ranks do not change the answer. Returns the
// local lines cast.
inline constexpr int kUncarriedLines = 16;
inline constexpr unsigned kUncarriedStream = 7;
uint64_t shoot_unshot(const PatchMesh& mesh, const Tracer& tracer, std::vector<int> faces, RadiosityState& state,
                      unsigned pass, unsigned long long seed, int shards_wanted);
// The same with the tracer built only when some face needs the shot: a
// kept-store solve whose faces every stored line carries builds no BVH.
inline uint64_t shoot_unshot(const PatchMesh& mesh, const TracerOnDemand& tracer, std::vector<int> faces,
                             RadiosityState& state, unsigned pass, unsigned long long seed, int shards_wanted) {
  return faces.empty() ? 0 : shoot_unshot(mesh, tracer.get(), std::move(faces), state, pass, seed, shards_wanted);
}

// Which faces the first shot shoots with local lines and how many lines each.
struct FirstShotPlan {
  std::vector<int> emitters;          // in face order
  std::vector<uint64_t> first{0};     // first line of each emitter; first.back() = lines in all
  std::vector<int> global_faces;      // emitting faces whose emission the global lines shoot
  // first_shot.sequence: each emitter's lines take the points of a
  // randomised Halton sequence of its own (true) or independent ones.
  bool halton = true;
  uint64_t lines() const { return first.back(); }
  uint64_t count(size_t e) const { return first[e + 1] - first[e]; }
  uint64_t blocks() const;  // of kFirstShotBlock lines, the last one partly filled
  bool operator==(const FirstShotPlan&) const = default;
};

// `budget` lines shared by power among the emitting faces, at least one each;
// with `global_crossings` (first_shot.mode = "auto"), an emitting face that
// the global lines cross at least as often is left to them.
FirstShotPlan plan_first_shot(const PatchMesh& mesh, const RadiosityState& state, long long budget,
                              const std::vector<double>& global_crossings);

// The first shot of a run: the plan for its emitting faces (first_shot.lines
// shared by power between the faces and the lights; with `store`, the
// crossings of its lines decide first_shot.mode = "auto", without it a
// forecast of a classic pass), and the lines of each light.
struct RunFirstShot {
  FirstShotPlan plan;
  std::vector<long long> light_lines;
};
RunFirstShot plan_run_first_shot(const Options& options, const PatchMesh& mesh, const RadiosityState& state,
                                 const BoxStore* store, const std::vector<PointLight>& lights);
// The same with the store's crossing counts per face given (what
// BoxStore::face_crossings returns), for a store not opened.
RunFirstShot plan_run_first_shot(const Options& options, const PatchMesh& mesh, const RadiosityState& state,
                                 std::vector<double> store_crossings, const std::vector<PointLight>& lights);

// Local lines are drawn in blocks of this many, each block with a random
// stream of its own: a line's fate does not depend on threads, shards or ranks.
inline constexpr uint64_t kFirstShotBlock = 4096;
inline uint64_t FirstShotPlan::blocks() const { return (lines() + kFirstShotBlock - 1) / kFirstShotBlock; }
Rng first_shot_rng(unsigned long long seed, uint64_t block);

// Lines per emitter, proportional to its power `power[e]`, at least one
// each: cumulative roundings, so that they add up to `budget` (plus the
// minimums).
std::vector<uint64_t> lines_by_power(const std::vector<double>& power, long long budget);

// The points of emitter e's lines with first_shot.sequence = "halton": its
// j-th line takes the j-th point of the Halton sequence in bases 2, 3, 5 and
// 7, shifted modulo 1 by a random vector of e's own (a Cranley-Patterson
// rotation: every point is uniform, so the shot stays unbiased, and an
// emitter's lines are spread evenly over its patch and its hemisphere). The
// same whatever block or thread a line falls in.
class EmitterPoints {
 public:
  EmitterPoints(unsigned long long seed, size_t emitter);
  size_t emitter() const { return emitter_; }
  void point(uint64_t index, double u[4]) const { points_.point(index, u); }

 private:
  size_t emitter_;
  ShiftedHalton points_;
};

// Calls line(e, code) for lines [block * kFirstShotBlock, ...) of block
// `block` of `plan` in order (e: the emitter's index in the plan).
template <typename Nearest, typename Line>
void trace_first_shot_block(const PatchMesh& mesh, const FirstShotPlan& plan, unsigned long long seed, uint64_t block,
                            const Nearest& nearest, const Line& line) {
  Rng rng = first_shot_rng(seed, block);
  const uint64_t lo = block * kFirstShotBlock, hi = std::min(plan.lines(), lo + kFirstShotBlock);
  size_t e = std::upper_bound(plan.first.begin(), plan.first.end(), lo) - plan.first.begin() - 1;
  std::optional<EmitterPoints> points;
  std::optional<PatchSampler> sampler;
  for (uint64_t l = lo; l < hi; ++l) {
    while (l >= plan.first[e + 1]) ++e;
    const int face = plan.emitters[e];
    if (!plan.halton) {
      line(e, local_line_outcome(mesh, face, rng, nearest));
      continue;
    }
    if (!points || points->emitter() != e) {
      points.emplace(seed, e);
      sampler.emplace(mesh, mesh.patches[mesh.face_patch[face]], mesh.face_normal(face));
    }
    double u[4];
    points->point(l - plan.first[e], u);
    line(e, local_line_outcome(mesh, face, *sampler, u, nearest));
  }
}

// Traces `plan`'s lines shard by shard on the threads (`seed` gives their
// streams, `label` names the progress) and calls receive(e, code, acc) for
// each line, in order within a shard; returns the shards' accumulators, for
// the caller to merge in shard order. The first and second shots' loop.
template <typename Nearest, typename Receive>
std::vector<ShardAccumulator> shoot_plan(const PatchMesh& mesh, const RadiosityState& state, const FirstShotPlan& plan,
                                         unsigned long long seed, int shards, const char* label,
                                         const Nearest& nearest, const Receive& receive) {
  const uint64_t blocks = plan.blocks();
  std::vector<ShardAccumulator> acc(static_cast<size_t>(shards));
  Progress progress(label, plan.lines(), "lines", true);
  run_shards(acc, [&](int s) { acc[s].reset(state.faces); }, [&](int s) {
    ShardAccumulator& a = acc[s];
    const uint64_t lo = blocks * s / shards, hi = blocks * (s + 1) / shards;
    for (uint64_t b = lo; b < hi; ++b) {
      const uint64_t before = a.lines;
      trace_first_shot_block(mesh, plan, seed, b, nearest, [&](size_t e, uint32_t code) {
        receive(e, code, a);
        ++a.lines;
      });
      progress.advance(a.lines - before);
    }
  });
  progress.finish();
  return acc;
}

// Adds `code` received from plan.emitters[e]: `lines` of its lines' power
// (its emitted power over its line count) at once.
void receive_emitter_lines(const RadiosityState& state, const FirstShotPlan& plan, size_t e, uint32_t code, uint64_t lines,
                           ShardAccumulator& acc);

// Moves the emission of plan.global_faces to their unshot power.
void leave_to_global_lines(const FirstShotPlan& plan, RadiosityState& state);

// A point source ([[light]]): its radiant power is added to the emitted
// energy and shot along `lines` lines from its position, drawn in
// proportion to its intensity, each carrying an equal share of its power to
// the face it meets first. `halton`: line k's three numbers are point k of
// the Halton sequence shifted by a random vector of the light's own (as an
// emitting face's, EmitterPoints), so the lines spread over the candela
// table evenly; else independent numbers. Returns the lines shot.
uint64_t shoot_light(const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state, const PointLight& light,
                     long long lines, unsigned long long seed, int shards, bool halton);
// A run's lights, light l along light_lines[l] lines (RunFirstShot) from
// streams of its own; returns the lines each shot.
std::vector<uint64_t> shoot_lights(const Options& options, const PatchMesh& mesh, const Tracer& tracer,
                                   RadiosityState& state, const std::vector<PointLight>& lights,
                                   const std::vector<long long>& light_lines);

// A run's lights' shot, as its report gives it.
struct LightsShotStats {
  uint64_t lines = 0;
  double seconds = 0;
  bool stored = false;         // read from the store's lights_shot.bin instead of traced
  std::string traced_because;  // with a store: why its lights' shot was not used
};

// The parts of shoot_light that a stored lights' shot (stored_shot.h)
// shares: the seed of light l's streams (lines.seed = `seed`); the lines
// shoot_light shoots for `lines` asked (none for a light of no power); the
// Halton points of the light's lines; what line k met (kEscaped, or
// met_code of the face, never a contact: a point touches nothing); and
// adding `lines` of the light's `count` lines that met `code`.
unsigned long long light_seed(unsigned long long seed, size_t light);
uint64_t light_line_count(const PointLight& light, long long lines);
// light_line_count of each light for the lines RunFirstShot asks of it.
std::vector<uint64_t> light_line_counts(const std::vector<PointLight>& lights, const std::vector<long long>& lines);
ShiftedHalton light_points(unsigned long long light_seed);
uint32_t light_line_outcome(const PatchMesh& mesh, const Tracer& tracer, const PointLight& light, const double u[3]);
void receive_light_lines(const RadiosityState& state, const PointLight& light, uint64_t count, uint32_t code,
                         uint64_t lines, ShardAccumulator& acc);

// Traces `plan` (its global faces left to the global lines). `accelerated`:
// find nearest hits through the subscenes' associated patches
// (first_shot.accelerate) instead of the whole scene's tracer.
FirstShotStats first_shot(const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state, const FirstShotPlan& plan,
                          unsigned long long seed, int shards, const SubsceneNearest* accelerated = nullptr);
// The same with the plan of `lines` lines.
FirstShotStats first_shot(const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state, long long lines,
                          unsigned long long seed, int shards, const std::vector<double>& global_crossings = {},
                          const SubsceneNearest* accelerated = nullptr);

}  // namespace mpath
