#include "classic.h"

#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <utility>

#include "first_shot.h"
#include "progress.h"
#include "sampling.h"
#include "transport.h"

namespace mpath {
namespace {

constexpr unsigned kGlobalLineStream = 2;

// The `keep` faces of `faces` holding the most unshot power (summed over the
// channels; ties to the lower face), in face order.
std::vector<int> most_unshot(std::vector<int> faces, const RadiosityState& state, size_t keep) {
  if (faces.size() <= keep) return faces;
  const auto power = [&](int f) {
    double p = 0;
    for (int c = 0; c < state.channels; ++c) p += state.unshot[state.at(static_cast<size_t>(f), c)];
    return p;
  };
  std::nth_element(faces.begin(), faces.begin() + static_cast<std::ptrdiff_t>(keep), faces.end(), [&](int a, int b) {
    const double pa = power(a), pb = power(b);
    return pa != pb ? pa > pb : a < b;
  });
  faces.resize(keep);
  std::sort(faces.begin(), faces.end());
  return faces;
}

}  // namespace

Rng pass_order_rng(unsigned long long seed, unsigned pass, int shard) {
  // The global lines' stream, with a bit above every (pass, shard) key of theirs.
  return make_rng(seed, kGlobalLineStream, (1ull << 39) | ((static_cast<unsigned long long>(pass) << 20) + shard));
}

std::vector<double> forecast_crossings(const PatchMesh& mesh, double lines) {
  const double box_area = line_box(mesh.bounds).surface_area();
  std::vector<double> c(mesh.face_count());
  for (size_t f = 0; f < c.size(); ++f) c[f] = lines * 2.0 * mesh.face_area(static_cast<int>(f)) / box_area;
  return c;
}

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
                       unsigned long long seed, unsigned pass, int shards, const std::string& sequence,
                       uint64_t* local_lines) {
  const LineSequence points(sequence, seed, pass);
  const auto start = std::chrono::steady_clock::now();
  const BoxLineSampler sampler(line_box(mesh.bounds));
  const PassInputs in = PassInputs::start(state, mesh, forecast_crossings(mesh, static_cast<double>(lines)));

  std::vector<ShardAccumulator> acc(shards);
  Progress progress(fmt::format("pass {}", pass), lines, "lines", true);
  const auto part = [&](int s) { return std::pair{lines * s / shards, lines * (s + 1) / shards}; };
  run_shards(acc, [&](int s) {
    const auto [lo, hi] = part(s);
    acc[s].reset(state.faces);
    acc[s].allowance = static_cast<double>(hi - lo) / static_cast<double>(lines);
  }, [&](int s) {
    const auto [lo, hi] = part(s);
    ShardAccumulator& a = acc[s];
    Rng rng = make_rng(seed, kGlobalLineStream, (static_cast<unsigned long long>(pass) << 20) + s);
    Rng order = pass_order_rng(seed, pass, s);
    std::vector<LineHit> hits;
    uint64_t since_report = 0;
    for_each_pass_line(lo, hi, order, [&](uint64_t i) {
      double u[4];
      points.point(i, rng, u);
      const GlobalLine line = sampler.sample(u);
      tracer.all_hits(line.org, line.dir, line.length, hits);
      order_ties(mesh, tracer.tie_epsilon(), hits, tracer.live_faces());
      transport_line(in, hits, a);
      if (++since_report == 4096) {
        progress.advance(since_report);
        since_report = 0;
      }
    });
    progress.advance(since_report);
  });
  progress.finish();
  PassStats stats = finish_pass(in, acc, state, pass, start);
  // Power on faces no line of the pass crossed, shot with local lines:
  // otherwise it waits for a pass whose lines cross its face, and on a
  // polygon that a coplanar one hides from every global line it waits for
  // ever (docs/algorithm.md, "Power no line moves"). At most as many local
  // lines as the pass had global ones, for the faces holding the most (with
  // far fewer lines than patches most faces are missed; the others wait).
  std::vector<int> missed =
      most_unshot(faces_no_line_crossed(in, acc), state, std::max<uint64_t>(1, lines / kUncarriedLines));
  if (!missed.empty()) {
    const uint64_t shot = shoot_unshot(mesh, tracer, std::move(missed), state, pass, seed, shards);
    if (local_lines) *local_lines += shot;
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    stats.unshot_fraction = state.remaining_fraction();
  }
  return stats;
}

uint64_t classic_pass_lines(const Options& options, const PatchMesh& mesh, const IterationLog& log,
                            const RadiosityState& state) {
  const auto floor_lines = std::min(static_cast<uint64_t>(options.lines.total), coverage_lines(mesh));
  const double share = log.first_unshot > 0 ? state.unshot_total() / log.first_unshot : 1.0;
  return std::max(floor_lines, static_cast<uint64_t>(std::ceil(static_cast<double>(options.lines.total) * share)));
}

IterationLog solve_classic(const Options& options, const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state,
                           int shards) {
  IterationLog log;
  iterate(options, state, log, [&](unsigned pass) {
    return classic_pass(mesh, tracer, state, classic_pass_lines(options, mesh, log, state), options.lines.seed, pass,
                        shards, options.lines.sequence);
  });
  return log;
}

}  // namespace mpath
