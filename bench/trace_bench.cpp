// Benchmark: global-line rate of the classic solver (trace every hit, sort,
// de-duplicate, order ties, Multipath transport) against Embree's raw
// all-hit rate (rtcIntersect1 with a filter that only collects hits) for the
// same lines on the same scene and threads. Writes one JSON record.
#include <CLI/CLI.hpp>
#include <tbb/global_control.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <thread>

#include "classic.h"
#include "mpath_version.h"
#include "prepared_scene.h"
#include "progress.h"
#include "sampling.h"
#include "transport.h"

namespace {

using namespace mpath;

struct RawContext {
  RTCIntersectContext context;
  std::vector<std::pair<float, unsigned>>* hits;
};

void raw_filter(const RTCFilterFunctionNArguments* args) {
  auto* ctx = reinterpret_cast<RawContext*>(args->context);
  ctx->hits->push_back({RTCRayN_tfar(args->ray, args->N, 0), RTCHitN_primID(args->hit, args->N, 0)});
  args->valid[0] = 0;
}

// The lines classic_pass draws, split into the same shards; `trace(shard,
// line)` returns the hits of a line. Returns the hits in all.
template <typename Trace>
uint64_t over_lines(const PatchMesh& mesh, uint64_t lines, unsigned long long seed, unsigned pass, int shards,
                    const std::string& sequence, Trace trace) {
  const LineSequence points(sequence, seed, pass);
  const BoxLineSampler sampler(line_box(mesh.bounds));
  std::vector<uint64_t> hits(shards, 0);
  tbb::parallel_for(0, shards, [&](int s) {
    Rng rng = make_rng(seed, 2, (static_cast<unsigned long long>(pass) << 20) + s);
    Rng order = pass_order_rng(seed, pass, s);
    auto shard_trace = trace();  // per-shard state
    for_each_pass_line(lines * s / shards, lines * (s + 1) / shards, order, [&](uint64_t i) {
      double u[4];
      points.point(i, rng, u);
      hits[s] += shard_trace(sampler.sample(u));
    });
  });
  uint64_t total = 0;
  for (uint64_t h : hits) total += h;
  return total;
}

// Embree alone: every hit collected, nothing else.
uint64_t raw_pass(const Tracer& tracer, const PatchMesh& mesh, uint64_t lines, unsigned long long seed, unsigned pass,
                  int shards, const std::string& sequence) {
  return over_lines(mesh, lines, seed, pass, shards, sequence, [&] {
    return [&tracer, found = std::vector<std::pair<float, unsigned>>()](const GlobalLine& line) mutable -> uint64_t {
      RawContext ctx;
      rtcInitIntersectContext(&ctx.context);
      ctx.context.filter = raw_filter;
      ctx.hits = &found;
      RTCRayHit rh{};
      rh.ray.org_x = static_cast<float>(line.org.x);
      rh.ray.org_y = static_cast<float>(line.org.y);
      rh.ray.org_z = static_cast<float>(line.org.z);
      rh.ray.dir_x = static_cast<float>(line.dir.x);
      rh.ray.dir_y = static_cast<float>(line.dir.y);
      rh.ray.dir_z = static_cast<float>(line.dir.z);
      rh.ray.tfar = static_cast<float>(line.length);
      rh.ray.mask = 0xFFFFFFFFu;
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      found.clear();
      rtcIntersect1(tracer.embree_scene(), &ctx.context, &rh);
      return found.size();
    };
  });
}

// mpath's tracer without transport: all hits, sorted, de-duplicated, ties ordered.
uint64_t tracer_pass(const Tracer& tracer, const PatchMesh& mesh, uint64_t lines, unsigned long long seed, unsigned pass,
                     int shards, const std::string& sequence) {
  return over_lines(mesh, lines, seed, pass, shards, sequence, [&] {
    return [&tracer, &mesh, found = std::vector<LineHit>()](const GlobalLine& line) mutable -> uint64_t {
      tracer.all_hits(line.org, line.dir, line.length, found);
      order_ties(mesh, tracer.tie_epsilon(), found, tracer.live_faces());
      return found.size();
    };
  });
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"mpath trace benchmark"};
  std::string config, out;
  uint64_t lines = 2'000'000;
  int repeats = 3;
  bool raw_only = false;
  std::vector<std::string> overrides;
  app.add_option("config", config)->required();
  app.add_option("--lines", lines);
  app.add_option("--repeats", repeats);
  app.add_option("--out", out, "JSON file to write")->required();
  app.add_flag("--raw-only", raw_only,
               "Embree's raw loop alone (no tracer or classic pass): what a paired preprocess run is divided by");
  app.add_option("overrides", overrides);
  CLI11_PARSE(app, argc, argv);

  Progress::set_enabled_default(false);
  spdlog::set_level(spdlog::level::warn);
  const Options options = load_options(config, overrides);
  const int threads = effective_threads(options);
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  PreparedScene prepared = prepare_scene(options);
  const Tracer tracer(prepared.mesh);
  RadiosityState state = make_state(prepared.scene, prepared.mesh);
  const std::vector<double> initial = state.emitted_power;

  using clock = std::chrono::steady_clock;
  std::vector<double> raw_rate, tracer_rate, solver_rate;
  uint64_t raw_hits = 0, solver_hits = 0;
  // Alternate the two so that both see the same machine load.
  for (int r = 0; r < repeats; ++r) {
    auto t = clock::now();
    raw_hits = raw_pass(tracer, prepared.mesh, lines, options.lines.seed, 1, threads, options.lines.sequence);
    raw_rate.push_back(lines / std::chrono::duration<double>(clock::now() - t).count());
    if (raw_only) continue;
    t = clock::now();
    tracer_pass(tracer, prepared.mesh, lines, options.lines.seed, 1, threads, options.lines.sequence);
    tracer_rate.push_back(lines / std::chrono::duration<double>(clock::now() - t).count());
    state.unshot = initial;  // every face has power to send
    t = clock::now();
    const PassStats p = classic_pass(prepared.mesh, tracer, state, lines, options.lines.seed, 1, threads, options.lines.sequence);
    solver_rate.push_back(lines / std::chrono::duration<double>(clock::now() - t).count());
    solver_hits = p.hits;
  }
  // The raw loop's record; the tracer's and the classic pass's beside it
  // unless --raw-only.
  nlohmann::json j = {{"scene", options.scene.file.filename().string()},
                      {"patches", prepared.mesh.patches.size()},
                      {"lines", lines},
                      {"threads", threads},
                      {"sequence", options.lines.sequence},
                      {"raw_lines_per_s", median(raw_rate)},
                      {"raw_hits_per_line", static_cast<double>(raw_hits) / lines},
                      {"raw_runs", raw_rate},
                      {"commit", MPATH_GIT_COMMIT},
                      {"embree", Tracer::embree_version()},
                      {"hardware_threads", std::thread::hardware_concurrency()}};
  if (!raw_only) {
    const double raw = median(raw_rate), solver = median(solver_rate);
    // Each repeat measures both back to back: the median of those ratios is
    // steadier than the ratio of medians when the machine's load drifts.
    std::vector<double> pair_ratio;
    for (size_t r = 0; r < raw_rate.size(); ++r) pair_ratio.push_back(solver_rate[r] / raw_rate[r]);
    j["tracer_lines_per_s"] = median(tracer_rate);
    j["solver_lines_per_s"] = solver;
    j["ratio"] = median(pair_ratio);
    j["ratio_of_medians"] = solver / raw;
    j["ratio_min"] = *std::min_element(pair_ratio.begin(), pair_ratio.end());
    j["ratio_max"] = *std::max_element(pair_ratio.begin(), pair_ratio.end());
    j["solver_hits_per_line"] = static_cast<double>(solver_hits) / lines;
    j["tracer_runs"] = tracer_rate;
    j["solver_runs"] = solver_rate;
  }
  std::ofstream(out) << j.dump(2) << "\n";
  std::cout << j.dump() << "\n";
  return 0;
}
