#include "classic.h"

#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "progress.h"
#include "sampling.h"
#include "transport.h"

namespace mpath {
namespace {

constexpr unsigned kGlobalLineStream = 2;

// Adds a pass's shard accumulators to the state, in shard order.
void merge_pass(const PassInputs& in, const std::vector<ShardAccumulator>& acc, RadiosityState& state) {
  const int ch = state.channels;
  for (size_t f = 0; f < state.faces; ++f) {
    double unsent = 0;  // fraction of the quota no line took
    for (size_t s = 0; s < acc.size(); ++s) unsent += acc[s].allowance - acc[s].quota_used[f];
    for (int c = 0; c < ch; ++c) {
      const size_t i = state.at(f, c);
      double gathered = 0, gain = 0;
      for (const ShardAccumulator& a : acc) {
        gathered += a.gathered[i];
        gain += a.phi_gain[i];
      }
      state.unshot[i] = in.quota[i] * unsent + gathered;
      state.phi[i] += gain;
    }
  }
  for (const ShardAccumulator& a : acc)
    for (int c = 0; c < ch; ++c) {
      state.energy.absorbed[c] += a.absorbed[c];
      state.energy.escaped[c] += a.escaped[c];
    }
}

}  // namespace

uint64_t coverage_lines(const PatchMesh& mesh) {
  std::vector<double> areas;
  for (const Patch& p : mesh.patches) areas.push_back(p.area);
  if (areas.empty()) return 0;
  std::nth_element(areas.begin(), areas.begin() + areas.size() / 2, areas.end());
  const double median = areas[areas.size() / 2];
  // N lines cross a face N 2A/S times: 16 crossings need N = 8S/A.
  return std::max<uint64_t>(10000, static_cast<uint64_t>(std::ceil(8.0 * line_box(mesh.bounds).surface_area() / median)));
}

PassStats classic_pass(const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state, uint64_t lines,
                       unsigned long long seed, unsigned pass, int shards, const std::string& sequence) {
  const LineSequence points(sequence, seed, pass);
  const auto start = std::chrono::steady_clock::now();
  const BoxLineSampler sampler(line_box(mesh.bounds));
  PassInputs in;
  in.state = &state;
  in.mesh = &mesh;
  in.quota = state.unshot;
  std::fill(state.unshot.begin(), state.unshot.end(), 0.0);
  in.share.resize(state.faces);
  for (size_t f = 0; f < state.faces; ++f) {
    const double expected = static_cast<double>(lines) * 2.0 * mesh.face_area(static_cast<int>(f)) / sampler.surface_area();
    in.share[f] = 1.0 / expected;
  }

  std::vector<ShardAccumulator> acc(shards);
  const double tie_epsilon = 1e-7 * mesh.bounds.diagonal();
  Progress progress(fmt::format("pass {}", pass), lines, "lines", true);
  tbb::parallel_for(0, shards, [&](int s) {
    const uint64_t lo = lines * s / shards, hi = lines * (s + 1) / shards;
    ShardAccumulator& a = acc[s];
    a.reset(state.faces, state.channels);
    a.allowance = static_cast<double>(hi - lo) / static_cast<double>(lines);
    Rng rng = make_rng(seed, kGlobalLineStream, (static_cast<unsigned long long>(pass) << 20) + s);
    std::vector<LineHit> hits;
    uint64_t since_report = 0;
    for (uint64_t i = lo; i < hi; ++i) {
      double u[4];
      points.point(i, rng, u);
      const GlobalLine line = sampler.sample(u);
      tracer.all_hits(line.org, line.dir, line.length, hits);
      order_ties(mesh, tie_epsilon, hits);
      transport_line(in, hits, a);
      if (++since_report == 4096) {
        progress.advance(since_report);
        since_report = 0;
      }
    }
    progress.advance(since_report);
  });
  progress.finish();
  merge_pass(in, acc, state);

  PassStats stats;
  stats.pass = static_cast<int>(pass);
  for (const ShardAccumulator& a : acc) {
    stats.lines += a.lines;
    stats.hits += a.hits;
  }
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats.unshot_fraction = state.unshot_total() / state.emitted_total();
  return stats;
}

IterationLog solve_classic(const Options& options, const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state,
                           int shards) {
  IterationLog log;
  const double first_unshot = state.unshot_total();
  const double emitted = state.emitted_total();
  const auto floor_lines = std::min(static_cast<uint64_t>(options.lines.total), coverage_lines(mesh));
  for (int pass = 1; pass <= options.solver.iterations; ++pass) {
    const double unshot = state.unshot_total();
    if (unshot / emitted < options.solver.tolerance) {
      log.converged = true;
      break;
    }
    const double share = first_unshot > 0 ? unshot / first_unshot : 1.0;
    const auto lines = std::max(floor_lines, static_cast<uint64_t>(std::ceil(static_cast<double>(options.lines.total) * share)));
    const PassStats p = classic_pass(mesh, tracer, state, lines, options.lines.seed, static_cast<unsigned>(pass), shards,
                                     options.lines.sequence);
    spdlog::info("pass {}: {} lines, {} hits, {:.2f} s, unshot {:.3e} of emitted", p.pass, p.lines, p.hits, p.seconds,
                 p.unshot_fraction);
    log.passes.push_back(p);
    log.lines += p.lines;
    log.hits += p.hits;
  }
  if (!log.converged) log.converged = state.unshot_total() / emitted < options.solver.tolerance;
  return log;
}

}  // namespace mpath
