#include "solve.h"

#include <spdlog/spdlog.h>
#include <tbb/global_control.h>

#include <chrono>
#include <nlohmann/json.hpp>

#include "atomic_file.h"
#include "checkpoint.h"
#include "classic.h"
#include "error.h"
#include "first_shot.h"
#include "mpath_version.h"
#include "prepared_scene.h"
#include "render.h"
#include "sampling.h"
#include "solution_ply.h"
#include "accelerated_shot.h"
#include "box_store.h"
#include "hierarchical.h"

namespace mpath {
namespace {

using clock = std::chrono::steady_clock;
using json = nlohmann::json;

double seconds_since(clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); }

// Bytes the solver holds per AR of a box: In and Out per channel, the
// transmittance, two redirect targets, n_R, n_R^d and the associated patches.
size_t ar_bytes(const RadiosityState& s) {
  return 2 * s.channels * sizeof(double) + sizeof(double) + 4 * sizeof(uint32_t) +
         2 * linestore::BoxCounts::kAssociated * sizeof(uint32_t);
}

json hierarchy_json(const BoxStore& store, const RadiosityState& state, const std::vector<BoxPassStats>& last) {
  json boxes = json::array();
  size_t ar_memory = 0;
  for (size_t b = 0; b < store.box_count(); ++b) {
    const SceneBox& sb = store.hierarchy().boxes[b];
    const StoreBox& box = store.box(b);
    const size_t memory = sb.ar_count() * ar_bytes(state) + box.counts.child_crossings.size() * sizeof(uint32_t);
    ar_memory += memory;
    boxes.push_back({{"box", b}, {"parent", sb.parent}, {"depth", sb.depth}, {"children", sb.children},
                     {"objects", sb.objects_total}, {"polygons", sb.polygons_total}, {"patches_direct", sb.patches.size()},
                     {"quotient", sb.quotient}, {"vp_grid", sb.grid}, {"ars", sb.ar_count()},
                     {"lo", {sb.bounds.lo.x, sb.bounds.lo.y, sb.bounds.lo.z}},
                     {"hi", {sb.bounds.hi.x, sb.bounds.hi.y, sb.bounds.hi.z}},
                     {"lines", box.lines}, {"events", box.events}, {"store_bytes", box.bytes}, {"ar_memory_bytes", memory},
                     {"last_pass_seconds", b < last.size() ? last[b].seconds : 0.0}});
  }
  return {{"boxes", boxes}, {"count", store.box_count()}, {"depth", store.hierarchy().max_depth()},
          {"ars", store.ar_total()}, {"ar_memory_bytes", ar_memory}, {"store_bytes", store.bytes()}};
}

json energy_json(const RadiosityState& s) {
  const auto absorbed = s.rgb(s.energy.absorbed), escaped = s.rgb(s.energy.escaped), emitted = s.rgb(s.energy.emitted);
  std::array<double, 3> unshot{};
  for (size_t f = 0; f < s.faces; ++f)
    for (int c = 0; c < s.channels; ++c) unshot[c] += s.unshot[s.at(f, c)];
  const auto unshot_rgb = s.rgb(unshot);
  std::array<double, 3> held{};
  for (size_t i = 0; i < s.ar_in.size(); ++i) held[i % s.channels] += s.ar_in[i] + s.ar_out[i];
  const auto held_rgb = s.rgb(held);
  auto sum = [](const std::array<double, 3>& v) { return v[0] + v[1] + v[2]; };
  const double residual = sum(emitted) - sum(absorbed) - sum(escaped) - sum(unshot_rgb) - sum(held_rgb);
  return {{"emitted", sum(emitted)},
          {"absorbed", sum(absorbed)},
          {"escaped", sum(escaped)},
          {"unshot", sum(unshot_rgb)},
          {"in_transit", sum(held_rgb)},
          {"residual", residual},
          {"relative_residual", sum(emitted) > 0 ? residual / sum(emitted) : 0.0},
          {"per_channel", {{"emitted", emitted}, {"absorbed", absorbed}, {"escaped", escaped}, {"unshot", unshot_rgb},
                            {"in_transit", held_rgb}}}};
}

}  // namespace

void run_solve(const Options& options, const SolveFlags& flags) {
  const auto start = clock::now();
  const int threads = effective_threads(options);
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  spdlog::info("mpath-solve {} ({}), method {}, {} thread(s)", MPATH_VERSION, MPATH_GIT_COMMIT, to_string(options.solver.method), threads);

  PreparedScene prepared = prepare_scene(options);
  const PatchMesh& mesh = prepared.mesh;
  // A stored-line solve checks its store before any work.
  std::unique_ptr<BoxStore> store;
  double store_seconds = 0;
  if (options.solver.method != SolverMethod::classic) {
    const auto store_start = clock::now();
    store = std::make_unique<BoxStore>(options, mesh);
    store_seconds = seconds_since(store_start);
    spdlog::info("store {}: {} box(es), depth {}, {} lines, {} events, {:.1f} MB", options.store.dir.string(),
                 store->box_count(), store->hierarchy().max_depth(), store->lines(), store->events(), store->bytes() / 1e6);
  }
  if (flags.dry_run) {
    spdlog::info("dry run: config, scene{} are valid; nothing solved", store ? " and store" : "");
    return;
  }
  std::filesystem::create_directories(options.output.dir);

  auto t = clock::now();
  const Tracer tracer(mesh);
  const double bvh_seconds = seconds_since(t);

  RadiosityState state = make_state(prepared.scene, mesh);
  if (store) add_ar_state(*store, state);
  spdlog::info("solving in {} channel(s); emitted power {:.6g} W", state.channels, state.emitted_total());
  const std::string key = checkpoint_key(options, mesh, threads);
  const auto checkpoint = options.output.dir / "checkpoint.bin";
  IterationLog iterations;
  FirstShotStats shot;
  bool resumed = false;
  if (flags.resume && std::filesystem::exists(checkpoint)) {
    read_checkpoint(checkpoint, key, state, iterations);
    resumed = true;
    spdlog::info("resuming from {} after {} finished pass(es)", checkpoint.string(), iterations.passes.size());
  } else {
    if (flags.resume) spdlog::warn("--resume: no checkpoint at {}; starting from the beginning", checkpoint.string());
    std::vector<double> crossings;
    if (store) crossings = store->face_crossings(mesh.face_count());
    else crossings = forecast_crossings(mesh, static_cast<double>(options.lines.total));
    std::unique_ptr<SubsceneNearest> accelerated;
    if (options.first_shot.accelerate && store && store->box_count() > 1)
      accelerated = std::make_unique<SubsceneNearest>(mesh, *store);
    shot = first_shot(mesh, tracer, state, options.first_shot.lines, options.lines.seed, threads,
                      emitter_crossings(options, std::move(crossings)), accelerated.get());
    write_checkpoint(checkpoint, key, state, iterations);
  }
  t = clock::now();
  const uint64_t hits_before = iterations.hits;  // passes restored from a checkpoint are not timed here
  const auto save = [&] { write_checkpoint(checkpoint, key, state, iterations); };
  std::vector<BoxPassStats> box_stats;
  uint64_t uncarried_lines = 0;  // local lines for power no stored line can carry
  if (store) {
    iterate(options, state, iterations,
            [&](unsigned pass) {
              return stored_iteration(options, mesh, tracer, *store, state, iterations, pass, threads, &box_stats,
                                      &uncarried_lines);
            }, save);
  } else {
    iterate(options, state, iterations, [&](unsigned pass) {
      return classic_pass(mesh, tracer, state, classic_pass_lines(options, mesh, iterations, state), options.lines.seed,
                          pass, threads, options.lines.sequence);
    }, save);
  }
  const double iteration_seconds = seconds_since(t);
  const double relative_residual = state.energy_residual() / state.emitted_total();
  spdlog::info("energy: unshot {:.3e} and held in ARs {:.3e} of emitted, balance residual {:.2e} (relative)",
               state.unshot_total() / state.emitted_total(), state.held_total() / state.emitted_total(), relative_residual);
  if (store) {
    const Remaining r = remaining_power(*store, state);
    const double e = state.emitted_total();
    spdlog::info("left to distribute: unshot {:.2e}, entering boxes {:.2e}, leaving boxes {:.2e} of emitted; most in box {} "
                 "({:.2e}); no stored line can carry {:.2e} (faces {:.2e}, ARs {:.2e})",
                 r.unshot / e, r.in / e, r.out / e, r.deepest_box, r.deepest_power / e,
                 (r.stuck_faces + r.stuck_in + r.stuck_out) / e, r.stuck_faces / e, (r.stuck_in + r.stuck_out) / e);
  }
  if (!iterations.converged)
    spdlog::warn("stopped at solver.iterations = {} with unshot + held {:.3e} of emitted above solver.tolerance {}",
                 options.solver.iterations, state.remaining_fraction(), options.solver.tolerance);

  t = clock::now();
  json outputs = json::array();
  write_solution_ply(options.output.dir / "solution.ply", mesh, state.solution_faces(mesh));
  outputs.push_back("solution.ply");
  if (!options.cameras.empty() && (options.output.exr || options.output.png)) {
    const VertexRadiosity vertex_radiosity(mesh, state);
    for (const CameraOptions& cam : options.cameras) {
      const Image image = render_camera(cam, mesh, tracer, vertex_radiosity, options.lines.seed);
      if (options.output.exr) {
        write_exr(options.output.dir / (cam.name + ".exr"), image, cam.exposure,
                  {{"mpathVersion", MPATH_VERSION},
                   {"mpathCommit", MPATH_GIT_COMMIT},
                   {"mpathMethod", to_string(options.solver.method)},
                   {"mpathScene", options.scene.file.string()},
                   {"mpathUnits", "radiance W/sr/m2 times 2^exposure"},
                   {"mpathConfig", options_to_json(options)}});
        outputs.push_back(cam.name + ".exr");
      }
      if (options.output.png) {
        write_png(options.output.dir / (cam.name + ".png"), image, cam.exposure);
        outputs.push_back(cam.name + ".png");
      }
    }
  }
  const double output_seconds = seconds_since(t);

  json passes = json::array();
  for (const PassStats& p : iterations.passes)
    passes.push_back({{"pass", p.pass}, {"lines", p.lines}, {"hits", p.hits}, {"seconds", p.seconds},
                      {"unshot_fraction", p.unshot_fraction}});
  const PatchMesh& m = mesh;
  json report = {
      {"mpath", {{"version", MPATH_VERSION}, {"commit", MPATH_GIT_COMMIT}, {"embree", Tracer::embree_version()},
                 {"command", flags.command_line}, {"threads", threads}}},
      {"config", json::parse(options_to_json(options))},
      {"scene", {{"file", options.scene.file.string()}, {"polygons", prepared.scene.polygons.size()},
                 {"objects", prepared.scene.objects.size()}, {"materials", prepared.scene.materials.size()},
                 {"dropped_polygons", m.dropped_polygons}, {"patches", m.patches.size()}, {"faces", m.face_count()},
                 {"max_patch_area", m.max_patch_area}, {"channels", state.channels}}},
      {"timings", {{"load", prepared.load_seconds}, {"mesh", prepared.mesh_seconds}, {"store", store_seconds},
                   {"bvh", bvh_seconds},
                   {"first_shot", shot.seconds}, {"iterations", iteration_seconds}, {"outputs", output_seconds},
                   {"total", seconds_since(start)}}},
      {"first_shot", {{"lines", shot.lines}, {"emitter_faces", shot.emitter_faces},
                      {"associated_hits", shot.associated_hits},
                      {"global_emitter_faces", shot.global_emitter_faces}, {"from_checkpoint", resumed}}},
      {"lines", {{"global", iterations.lines}, {"hits", iterations.hits}, {"local", shot.lines},
                 {"local_uncarried", uncarried_lines}}},
      {"iterations", {{"count", iterations.passes.size()}, {"converged", iterations.converged},
                      {"tolerance", options.solver.tolerance}, {"cap", options.solver.iterations},
                      {"unshot_fraction", state.unshot_total() / state.emitted_total()},
                      {"remaining_fraction", state.remaining_fraction()}, {"passes", passes}}},
      {"memory", {{"peak_rss_bytes", peak_rss_bytes()}}},
      {"store", store ? json{{"dir", options.store.dir.string()}, {"lines", store->lines()}, {"events", store->events()},
                             {"bytes", store->bytes()}, {"bytes_per_event", double(store->bytes()) / std::max<uint64_t>(1, store->events())},
                             {"events_per_second_per_thread", iteration_seconds > 0 && !iterations.passes.empty()
                                  ? double(iterations.hits - hits_before) / iteration_seconds / threads : 0.0}}
                      : json(nullptr)},
      {"hierarchy", store ? hierarchy_json(*store, state, box_stats) : json(nullptr)},
      {"energy", energy_json(state)},
      {"outputs", outputs},
      {"warnings", prepared.warnings},
  };
  write_text_file(options.output.dir / "report.json", report.dump(2) + "\n");
  spdlog::info("results in {} ({:.2f} s in all)", options.output.dir.string(), seconds_since(start));
}

}  // namespace mpath
