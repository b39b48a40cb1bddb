#include "first_shot.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "accelerated_shot.h"
#include "box_store.h"
#include "classic.h"
#include "ranks.h"
#include "progress.h"
#include "sampling.h"
#include "transport.h"

namespace mpath {
namespace {

constexpr unsigned kFirstShotStream = 1;
constexpr unsigned kLightStream = 6;
constexpr unsigned long long kLightShiftIndex = 1ULL << 32;  // above any shard's index
constexpr unsigned kEmitterShiftStream = 1000;

double face_power(const RadiosityState& s, int f) {
  double p = 0;
  for (int c = 0; c < s.channels; ++c) p += s.emitted_power[s.at(f, c)];
  return p;
}

std::vector<uint64_t> allocate_lines(const RadiosityState& s, long long budget, const std::vector<int>& emitters) {
  std::vector<double> power;
  for (int f : emitters) power.push_back(face_power(s, f));
  return lines_by_power(power, budget);
}

}  // namespace

std::vector<double> emitter_crossings(const Options& options, std::vector<double> crossings) {
  if (options.first_shot.mode != "auto") return {};
  return crossings;
}

std::vector<uint64_t> lines_by_power(const std::vector<double>& power, long long budget) {
  double total = 0;
  for (double p : power) total += p;
  std::vector<uint64_t> counts(power.size());
  double cumulative = 0;
  uint64_t assigned = 0;
  for (size_t i = 0; i < power.size(); ++i) {
    cumulative += power[i];
    const auto upto = static_cast<uint64_t>(std::llround(static_cast<double>(budget) * cumulative / total));
    counts[i] = std::max<uint64_t>(1, upto > assigned ? upto - assigned : 0);
    assigned = std::max(assigned, upto);
  }
  return counts;
}

Rng first_shot_rng(unsigned long long seed, uint64_t block) { return make_rng(seed, kFirstShotStream, block); }

EmitterPoints::EmitterPoints(unsigned long long seed, size_t emitter)
    : emitter_(emitter), points_(make_rng(seed, kEmitterShiftStream, emitter)) {}

FirstShotPlan plan_first_shot(const PatchMesh& mesh, const RadiosityState& state, long long budget,
                              const std::vector<double>& global_crossings) {
  FirstShotPlan plan;
  std::vector<int> emitters;
  for (size_t f = 0; f < state.faces; ++f)
    if (face_power(state, static_cast<int>(f)) > 0) emitters.push_back(static_cast<int>(f));
  std::vector<uint64_t> counts = allocate_lines(state, budget, emitters);
  if (!global_crossings.empty()) {
    std::vector<int> local;
    for (size_t e = 0; e < emitters.size(); ++e) {
      const int f = emitters[e];
      // A face that may touch another shoots locally: what it emits where
      // it touches stays there (receive_in_contact), which a global line
      // cannot tell apart.
      if (!mesh.may_touch(mesh.face_patch[f]) && global_crossings[f] >= static_cast<double>(counts[e]))
        plan.global_faces.push_back(f);
      else
        local.push_back(f);
    }
    if (local.size() != emitters.size()) {
      emitters = std::move(local);
      counts = allocate_lines(state, budget, emitters);
    }
  }
  plan.emitters = std::move(emitters);
  for (uint64_t n : counts) plan.first.push_back(plan.first.back() + n);
  return plan;
}

RunFirstShot plan_run_first_shot(const Options& options, const PatchMesh& mesh, const RadiosityState& state,
                                 const BoxStore* store, const std::vector<PointLight>& lights) {
  return plan_run_first_shot(options, mesh, state,
                             store ? store->face_crossings(mesh.face_count())
                                   : forecast_crossings(mesh, static_cast<double>(options.lines.total)),
                             lights);
}

RunFirstShot plan_run_first_shot(const Options& options, const PatchMesh& mesh, const RadiosityState& state,
                                 std::vector<double> crossings, const std::vector<PointLight>& lights) {
  // first_shot.lines shared by power between the emitting faces and the lights.
  const double faces_power = state.emitted_total();
  double lights_power = 0;
  for (const PointLight& l : lights) lights_power += l.power() * state.channels;
  const double total_power = faces_power + lights_power;
  const auto share = [&](double power) {  // nothing emits at all (lights at multiplier 0): no lines
    return total_power > 0
               ? static_cast<long long>(std::llround(static_cast<double>(first_shot_lines(options)) * power / total_power))
               : 0LL;
  };
  RunFirstShot run;
  run.plan = plan_first_shot(mesh, state, lights.empty() ? first_shot_lines(options) : share(faces_power),
                             emitter_crossings(options, std::move(crossings)));
  run.plan.halton = options.first_shot.halton();
  for (const PointLight& l : lights) run.light_lines.push_back(std::max<long long>(10'000, share(l.power() * state.channels)));
  return run;
}

void receive_emitter_lines(const RadiosityState& state, const FirstShotPlan& plan, size_t e, uint32_t code, uint64_t lines,
                           ShardAccumulator& acc) {
  const int face = plan.emitters[e];
  const double share = static_cast<double>(lines) / static_cast<double>(plan.count(e));
  double power[3];
  for (int c = 0; c < state.channels; ++c) power[c] = state.emitted_power[state.at(face, c)] * share;
  receive_outcome(state, face, code, power, acc);
}

void leave_to_global_lines(const FirstShotPlan& plan, RadiosityState& state) {
  for (int f : plan.global_faces)
    for (int c = 0; c < state.channels; ++c) state.unshot[state.at(f, c)] += state.emitted_power[state.at(f, c)];
}

FirstShotStats first_shot(const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state, const FirstShotPlan& plan,
                          unsigned long long seed, int shards, const SubsceneNearest* accelerated) {
  const auto start = std::chrono::steady_clock::now();
  FirstShotStats stats;
  leave_to_global_lines(plan, state);
  const uint64_t total = plan.lines();
  const double tfar = 4.0 * mesh.bounds.diagonal() + 1.0;
  const auto nearest = [&](int from, const Vec3& org, const Vec3& dir) {
    return accelerated ? accelerated->nearest_from(from, org, dir) : tracer.nearest_from(from, org, dir, tfar);
  };
  const std::vector<ShardAccumulator> acc =
      shoot_plan(mesh, state, plan, seed, shards, "first shot", nearest,
                 [&](size_t e, uint32_t code, ShardAccumulator& a) { receive_emitter_lines(state, plan, e, code, 1, a); });

  // Merge in shard order: the result does not depend on scheduling.
  merge_received(acc, state);
  stats.lines = total;
  stats.halton = plan.halton;
  stats.emitter_faces = plan.emitters.size();
  stats.global_emitter_faces = plan.global_faces.size();
  if (accelerated) {
    uint64_t shortcuts = accelerated->shortcuts();
    Ranks::sum(&shortcuts, 1);
    stats.associated_hits = shortcuts;
  }
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

FirstShotStats first_shot(const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state, long long budget,
                          unsigned long long seed, int shards, const std::vector<double>& global_crossings,
                          const SubsceneNearest* accelerated) {
  return first_shot(mesh, tracer, state, plan_first_shot(mesh, state, budget, global_crossings), seed, shards,
                    accelerated);
}

unsigned long long light_seed(unsigned long long seed, size_t light) { return seed + 7919 * (light + 1); }

uint64_t light_line_count(const PointLight& light, long long lines) {
  return light.power() > 0 ? static_cast<uint64_t>(std::max<long long>(lines, 1)) : 0;
}

std::vector<uint64_t> light_line_counts(const std::vector<PointLight>& lights, const std::vector<long long>& lines) {
  std::vector<uint64_t> counts;
  for (size_t l = 0; l < lights.size(); ++l) counts.push_back(light_line_count(lights[l], lines[l]));
  return counts;
}

// The Halton points' shift: the light's stream, past the shards' indices.
ShiftedHalton light_points(unsigned long long light_seed) {
  return ShiftedHalton(make_rng(light_seed, kLightStream, kLightShiftIndex));
}

uint32_t light_line_outcome(const PatchMesh& mesh, const Tracer& tracer, const PointLight& light, const double u[3]) {
  const Vec3 dir = light.sample(u[0], u[1], u[2]);
  const NearestHit hit = tracer.nearest(light.options.position, dir, 0.0, 4.0 * mesh.bounds.diagonal() + 1.0);
  return hit.patch < 0 ? kEscaped : met_code(mesh.face_met(hit.patch, dir), false);
}

void receive_light_lines(const RadiosityState& state, const PointLight& light, uint64_t count, uint32_t code,
                         uint64_t lines, ShardAccumulator& acc) {
  // White: the same radiant power in every channel.
  const double part = light.power() / static_cast<double>(count) * static_cast<double>(lines);
  const double power[3] = {part, part, part};
  receive_outcome(state, -1, code, power, acc);
}

uint64_t shoot_light(const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state, const PointLight& light,
                     long long lines, unsigned long long seed, int shards, bool halton) {
  const double power = light.power();
  for (int c = 0; c < state.channels; ++c) state.energy.emitted[c] += power;
  const uint64_t n = light_line_count(light, lines);
  if (n == 0) return 0;
  const ShiftedHalton points = light_points(seed);
  std::vector<ShardAccumulator> acc(shards);
  run_shards(acc, [&](int s) { acc[s].reset(state.faces); }, [&](int s) {
    ShardAccumulator& a = acc[s];
    Rng rng = make_rng(seed, kLightStream, static_cast<unsigned long long>(s));
    for (uint64_t k = n * s / shards; k < n * (s + 1) / shards; ++k) {
      double u[4];
      if (halton) points.point(k, u);
      else
        for (int i = 0; i < 3; ++i) u[i] = uniform(rng);
      receive_light_lines(state, light, n, light_line_outcome(mesh, tracer, light, u), 1, a);
      ++a.lines;
    }
  });
  merge_received(acc, state);
  return n;
}

std::vector<uint64_t> shoot_lights(const Options& options, const PatchMesh& mesh, const Tracer& tracer,
                                   RadiosityState& state, const std::vector<PointLight>& lights,
                                   const std::vector<long long>& light_lines) {
  std::vector<uint64_t> shot(lights.size());
  for (size_t l = 0; l < lights.size(); ++l)
    shot[l] = shoot_light(mesh, tracer, state, lights[l], light_lines[l], light_seed(options.lines.seed, l),
                          options.solver.shards, options.first_shot.halton());
  return shot;
}

uint64_t shoot_unshot(const PatchMesh& mesh, const Tracer& tracer, std::vector<int> faces,
                      RadiosityState& state, unsigned pass, unsigned long long seed, int shards_wanted) {
  const int ch = state.channels;
  if (faces.empty()) return 0;
  std::sort(faces.begin(), faces.end());
  // A shard per kFacesPerShard faces, at most shards_wanted, from the faces
  // alone, so that threads and ranks do not change the answer.
  constexpr size_t kFacesPerShard = 1024;
  const int shards = static_cast<int>(
      std::clamp<size_t>((faces.size() + kFacesPerShard - 1) / kFacesPerShard, 1, static_cast<size_t>(shards_wanted)));
  const size_t n = faces.size();
  const auto first_face = [&](int s) { return n * static_cast<size_t>(s) / static_cast<size_t>(shards); };
  // What each line meets (its outcome code), traced shard by shard on the
  // threads; with several ranks each shard's lines by one rank, 0 elsewhere.
  std::vector<uint64_t> met(n * kUncarriedLines, 0);
  const double tfar = 4.0 * mesh.bounds.diagonal() + 1.0;
  for_each_shard(shards, [&](int s) {
    if (!Ranks::owns(s, shards)) return;
    for (size_t i = first_face(s); i < first_face(s + 1); ++i) {
      const int face = faces[i];
      Rng rng = make_rng(seed, kUncarriedStream, (static_cast<unsigned long long>(pass) << 32) + face);
      for (int k = 0; k < kUncarriedLines; ++k)
        met[i * kUncarriedLines + k] = local_line_outcome(mesh, face, rng, [&](int from, const Vec3& org, const Vec3& dir) {
          return tracer.nearest_from(from, org, dir, tfar);
        });
    }
  });
  Ranks::sum(met.data(), met.size());
  // The shot power leaves its faces' unshot.
  std::vector<double> power(n * static_cast<size_t>(ch));
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < ch; ++c) {
      double& unshot = state.unshot[state.at(static_cast<size_t>(faces[i]), c)];
      power[i * ch + c] = unshot / kUncarriedLines;
      unshot = 0;
    }
  // Then each shard's hits are received into one accumulator and added to
  // the state in shard order, only the faces they reached, which are then
  // cleared for the next shard: each face's sums are the additions a
  // shard's own accumulator would make, in the same order, with one
  // accumulator alive instead of one per shard (at most 8, each of all the
  // scene's faces: on OFFICE meshed to 667k faces 43 MB each, every pass).
  ShardAccumulator acc;
  acc.reset(state.faces);
  std::vector<int> reached;
  for (int s = 0; s < shards; ++s) {
    reached.clear();
    for (size_t i = first_face(s); i < first_face(s + 1); ++i)
      for (int k = 0; k < kUncarriedLines; ++k) {
        const uint32_t code = static_cast<uint32_t>(met[i * kUncarriedLines + k]);
        receive_outcome(state, faces[i], code, &power[i * ch], acc);
        if (code == kEscaped) continue;
        reached.push_back(code_face(code));
        if (code_contact(code)) reached.push_back(faces[i]);
      }
    std::sort(reached.begin(), reached.end());
    reached.erase(std::unique(reached.begin(), reached.end()), reached.end());
    for (int f : reached) {
      if (f < 0) continue;
      FaceAccumulator& a = acc.faces[static_cast<size_t>(f)];
      add_face_gains(a, static_cast<size_t>(f), state);
      a = FaceAccumulator{};
    }
    for (int c = 0; c < ch; ++c) {
      state.energy.absorbed[c] += acc.absorbed[c];
      state.energy.escaped[c] += acc.escaped[c];
    }
    acc.absorbed = {};
    acc.escaped = {};
  }
  return faces.size() * kUncarriedLines;
}

}  // namespace mpath
