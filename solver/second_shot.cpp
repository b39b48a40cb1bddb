#include "second_shot.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "box_store.h"
#include "classic.h"
#include "transport.h"

namespace mpath {
namespace {

double unshot_power(const RadiosityState& state, size_t f) {
  double p = 0;
  for (int c = 0; c < state.channels; ++c) p += state.unshot[state.at(f, c)];
  return p;
}

}  // namespace

unsigned long long second_shot_stream(unsigned long long seed) {
  unsigned long long z = seed + 0x5EC0D5407A11F00DULL;  // splitmix64 of the salted seed
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

FirstShotPlan plan_second_shot(const RadiosityState& state, long long budget, const std::vector<double>& crossings,
                               bool halton) {
  FirstShotPlan plan;
  plan.halton = halton;
  if (budget <= 0) return plan;
  // Face f belongs when its share of the budget, budget P_f / P_S (P_S the
  // power of the faces taken), exceeds its crossings c_f, that is when
  // P_f / c_f > P_S / budget. Taken in decreasing P_f / c_f, the left side
  // falls and the right side grows, so the faces that belong are the
  // longest run from the top where it holds: the largest consistent set.
  struct Candidate {
    int face;
    double power, crossings;
  };
  std::vector<Candidate> order;
  for (size_t f = 0; f < state.faces; ++f)
    if (const double p = unshot_power(state, f); p > 0)
      order.push_back({static_cast<int>(f), p, f < crossings.size() ? std::max(0.0, crossings[f]) : 0.0});
  // P_a / c_a > P_b / c_b without dividing (a face no line crosses first).
  std::sort(order.begin(), order.end(), [](const Candidate& a, const Candidate& b) {
    const double l = a.power * b.crossings, r = b.power * a.crossings;
    return l != r ? l > r : a.face < b.face;
  });
  double taken = 0;
  size_t count = 0;
  for (const Candidate& c : order) {
    if (!(static_cast<double>(budget) * c.power > c.crossings * (taken + c.power))) break;
    taken += c.power;
    ++count;
  }
  std::vector<int> faces;
  for (size_t k = 0; k < count; ++k) faces.push_back(order[k].face);
  std::sort(faces.begin(), faces.end());
  std::vector<double> power;
  for (int f : faces) power.push_back(unshot_power(state, static_cast<size_t>(f)));
  const std::vector<uint64_t> counts = faces.empty() ? std::vector<uint64_t>{} : lines_by_power(power, budget);
  plan.emitters = std::move(faces);
  for (uint64_t n : counts) plan.first.push_back(plan.first.back() + n);
  return plan;
}

FirstShotPlan plan_run_second_shot(const Options& options, const PatchMesh& mesh, const RadiosityState& state,
                                   const BoxStore* store) {
  if (!(options.second_shot.share > 0)) return plan_second_shot(state, 0, {}, options.first_shot.halton());
  const auto total = static_cast<double>(options.lines.total);
  return plan_run_second_shot(options, state,
                              store ? store->root_crossings(mesh.face_count()) : forecast_crossings(mesh, total));
}

FirstShotPlan plan_run_second_shot(const Options& options, const RadiosityState& state,
                                   const std::vector<double>& crossings) {
  const long long budget =
      options.second_shot.share > 0 ? std::llround(options.second_shot.share * static_cast<double>(options.lines.total)) : 0;
  return plan_second_shot(state, budget, crossings, options.first_shot.halton());
}

std::vector<double> second_shot_line_power(const RadiosityState& state, const FirstShotPlan& plan) {
  const int ch = state.channels;
  std::vector<double> per_line(plan.emitters.size() * static_cast<size_t>(ch));
  for (size_t e = 0; e < plan.emitters.size(); ++e)
    for (int c = 0; c < ch; ++c)
      per_line[e * ch + c] = state.unshot[state.at(static_cast<size_t>(plan.emitters[e]), c)] /
                             static_cast<double>(plan.count(e));
  return per_line;
}

void receive_second_shot_lines(const RadiosityState& state, const FirstShotPlan& plan,
                               const std::vector<double>& per_line, size_t e, uint32_t code, uint64_t lines,
                               ShardAccumulator& acc) {
  const int ch = state.channels;
  const int face = plan.emitters[e];
  double power[3];
  for (int c = 0; c < ch; ++c) power[c] = per_line[e * ch + c] * static_cast<double>(lines);
  if (code_contact(code)) {
    // From where the face is pressed against another surface: its
    // reflected power does not leave there (a pass's crossing that touches
    // keeps its share at the face too); it stays unshot.
    for (int c = 0; c < ch; ++c) acc.faces[static_cast<size_t>(face)].gathered[c] += power[c];
  } else {
    receive_outcome(state, face, code, power, acc);
  }
}

SecondShotStats finish_second_shot(const FirstShotPlan& plan, const std::vector<ShardAccumulator>& acc,
                                   RadiosityState& state) {
  SecondShotStats stats;
  stats.halton = plan.halton;
  double all = 0, taken = 0;
  for (size_t f = 0; f < state.faces; ++f) all += unshot_power(state, f);
  for (int f : plan.emitters) {
    taken += unshot_power(state, static_cast<size_t>(f));
    for (int c = 0; c < state.channels; ++c) state.unshot[state.at(static_cast<size_t>(f), c)] = 0;
  }
  merge_received(acc, state);  // in shard order
  stats.lines = plan.lines();
  stats.faces = plan.emitters.size();
  stats.power_share = all > 0 ? taken / all : 0.0;
  return stats;
}

SecondShotStats second_shot(const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state,
                            const FirstShotPlan& plan, unsigned long long seed, int shards) {
  const auto start = std::chrono::steady_clock::now();
  if (plan.emitters.empty()) {
    SecondShotStats none;
    none.halton = plan.halton;
    return none;
  }
  const std::vector<double> per_line = second_shot_line_power(state, plan);
  const double tfar = 4.0 * mesh.bounds.diagonal() + 1.0;
  const auto nearest = [&](int from, const Vec3& org, const Vec3& dir) {
    return tracer.nearest_from(from, org, dir, tfar);
  };
  const std::vector<ShardAccumulator> acc =
      shoot_plan(mesh, state, plan, second_shot_stream(seed), shards, "second shot", nearest,
                 [&](size_t e, uint32_t code, ShardAccumulator& a) {
                   receive_second_shot_lines(state, plan, per_line, e, code, 1, a);
                 });
  SecondShotStats stats = finish_second_shot(plan, acc, state);
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

}  // namespace mpath
