#include "solve.h"

#include <spdlog/spdlog.h>
#include <tbb/task_group.h>

#include <chrono>
#include <optional>

#include "atomic_file.h"
#include "checkpoint.h"
#include "on_threads.h"
#include "classic.h"
#include "directory_lock.h"
#include "error.h"
#include "first_shot.h"
#include "pilot.h"
#include "second_shot.h"
#include "stored_shot.h"
#include "store_identity.h"
#include "json_text.h"
#include "mpath_version.h"
#include "prepared_scene.h"
#include "photometry.h"
#include "render.h"
#include "sampling.h"
#include "solution_ply.h"
#include "accelerated_shot.h"
#include "box_store.h"
#include "hierarchical.h"
#include "line_sets.h"
#include "ranks.h"
#include "report.h"

namespace mpath {
namespace {

using clock = std::chrono::steady_clock;

double seconds_since(clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); }

// The store's files checked against its manifest on another thread while
// this one loads and meshes the scene (prepare_scene): their hashes read the
// whole store, which needs no scene. With solver.threads = 1 the check runs
// in wait(), after the scene, as before. An error of the scene comes first
// (the check is cancelled or waited for); one of the store is thrown by
// open_store, in the order BoxStore gives.
class StoreCheck {
 public:
  // `reads_store`: a stored-line method whose store.dir is a folder (nothing to check otherwise).
  StoreCheck(const Options& options, bool reads_store) {
    if (!reads_store) return;
    tasks_.run([this, dir = options.store.dir] {
      try {
        checked_ = check_store_files(dir);
      } catch (...) {
        unread_ = std::current_exception();
      }
    });
  }
  ~StoreCheck() {
    tasks_.cancel();
    tasks_.wait();
  }
  // The checked files, or nullopt where no check ran (BoxStore then reads the manifest and names what is missing).
  std::optional<CheckedFiles> take() {
    tasks_.wait();
    if (unread_) std::rethrow_exception(unread_);
    return std::move(checked_);
  }

 private:
  tbb::task_group tasks_;
  std::optional<CheckedFiles> checked_;
  std::exception_ptr unread_;
};

// The store of a stored-line method, checked before any work (null for classic).
std::unique_ptr<BoxStore> open_store(const Options& options, const PatchMesh& mesh, StoreCheck& check,
                                     SolveTimings& timings) {
  if (options.solver.method == SolverMethod::classic) return nullptr;
  const auto start = clock::now();
  auto store = std::make_unique<BoxStore>(options, mesh, check.take());
  timings.store = seconds_since(start);
  spdlog::info("store {}: {} box(es), depth {}, {} lines, {} events, {:.1f} MB", options.store.dir.string(),
               store->box_count(), store->hierarchy().max_depth(), store->lines(), store->events(), store->bytes() / 1e6);
  return store;
}

// The first shot's lines where first_shot.lines is 0: a kept store's (its
// first_shot.bin, read instead of traced), else the pilot's choice
// (pilot.h); a store made before stores recorded them, half of lines.total
// as then.
long long chosen_first_shot_lines(const Options& options, const Scene& scene, const PatchMesh& mesh,
                                  const TracerOnDemand& tracer, const BoxStore* store,
                                  const std::vector<PointLight>& lights, SolveRecord& record) {
  if (store) {
    record.shot_lines_from = "store";
    return static_cast<long long>(store->manifest().first_shot_lines);
  }
  const auto start = clock::now();
  const Pilot pilot = run_pilot(scene, mesh, nullptr, options.lines.seed,
                                static_cast<uint64_t>(options.lines.pilot_lines()),
                                options.first_shot.halton(), &tracer.get(), lights);
  record.shot_lines_from = "pilot";
  record.shot_share = first_shot_share(pilot);
  record.pilot_seconds = seconds_since(start);
  const long long lines = first_shot_lines_for_share(options, record.shot_share);
  log_first_shot_choice(pilot, lines, options.lines.total);
  return lines;
}

// A shot of a kept store is read, not traced, when this run would trace the
// same lines (stored_shot.h): `read` reads it or returns why not, `trace`
// traces it. Returns why it was traced ("" when read, and without a store).
template <typename Read, typename Trace>
std::string read_or_trace(const BoxStore* store, bool accelerated, const char* shot, const Read& read,
                          const Trace& trace) {
  std::string why;
  if (store && accelerated) why = "first_shot.accelerate traces through the associated patches";
  else if (store) why = read();
  if (!store || !why.empty()) {
    if (store) spdlog::info("{} traced: {}", shot, why);
    trace();
  }
  return why;
}

// Restores the state from the checkpoint (--resume) or runs the first shot.
void start_state(const Options& run_options, const SolveFlags& flags, const Scene& scene, const PatchMesh& mesh,
                 const TracerOnDemand& tracer, const BoxStore* store, const Checkpoint& checkpoint,
                 const std::vector<PointLight>& lights, RadiosityState& state, SolveRecord& record) {
  if (flags.resume && std::filesystem::exists(checkpoint.path)) {
    read_checkpoint(checkpoint.path, checkpoint.key, state, record.iterations);
    record.resumed = true;
    spdlog::info("resuming from {} after {} finished pass(es)", checkpoint.path.string(), record.iterations.passes.size());
    return;
  }
  if (flags.resume) spdlog::warn("--resume: no checkpoint at {}; starting from the beginning", checkpoint.path.string());
  Options options = run_options;
  if (options.first_shot.lines == 0)
    options.first_shot.chosen = chosen_first_shot_lines(options, scene, mesh, tracer, store, lights, record);
  const RunFirstShot shot = plan_run_first_shot(options, mesh, state, store, lights);
  std::unique_ptr<SubsceneNearest> accelerated;
  if (options.first_shot.accelerate && store && store->box_count() > 1 && !store->line_sets())
    accelerated = std::make_unique<SubsceneNearest>(mesh, *store);
  record.shot.traced_because = read_or_trace(
      store, accelerated != nullptr, "first shot",
      [&] {
        return replay_stored_shot(options.store.dir / kStoredShotFile, mesh, shot.plan, options.lines.seed, state,
                                  record.shot);
      },
      [&] {
        record.shot = first_shot(mesh, tracer.get(), state, shot.plan, options.lines.seed, options.solver.shards,
                                 accelerated.get());
      });
  if (record.shot.stored)
    spdlog::info("first shot: {} local lines read from the store ({:.2f} s)", record.shot.lines, record.shot.seconds);
  // The lights' shot: read like the first shot where the store holds it.
  std::vector<uint64_t> shot_lines = light_line_counts(lights, shot.light_lines);
  if (!lights.empty())
    record.lights_shot.traced_because = read_or_trace(
        store, false, "lights' shot",
        [&] {
          return replay_stored_lights(options.store.dir / kStoredLightsFile, mesh, lights, shot_lines,
                                      options.lines.seed, state, record.lights_shot);
        },
        [&] {
          const auto start = clock::now();
          shot_lines = shoot_lights(options, mesh, tracer.get(), state, lights, shot.light_lines);
          record.lights_shot.seconds = seconds_since(start);
        });
  record.lights_shot.lines = 0;
  for (size_t l = 0; l < lights.size(); ++l) {
    record.shot.lines += shot_lines[l];
    record.lights_shot.lines += shot_lines[l];
    record.lights[l].first_shot_lines = shot_lines[l];
  }
  if (!lights.empty())
    spdlog::info("lights' shot: {} local lines from {} light(s) ({}, {:.2f} s)", record.lights_shot.lines,
                 lights.size(), record.lights_shot.stored ? "read from the store" : "traced", record.lights_shot.seconds);
  // The faces the first shot left brightest shoot their power with local
  // lines of their own (second_shot.h); read like the first shot.
  if (const FirstShotPlan second = plan_run_second_shot(options, mesh, state, store); !second.emitters.empty()) {
    record.second_shot.traced_because = read_or_trace(
        store, accelerated != nullptr, "second shot",
        [&] {
          return replay_stored_second_shot(options.store.dir / kStoredSecondShotFile, mesh, second, options.lines.seed,
                                           state, record.second_shot);
        },
        [&] {
          record.second_shot =
              second_shot(mesh, tracer.get(), state, second, options.lines.seed, options.solver.shards);
        });
    spdlog::info("second shot: {} local lines from {} face(s) holding {:.1f} % of the unshot power ({}, {:.2f} s)",
                 record.second_shot.lines, record.second_shot.faces, 100.0 * record.second_shot.power_share,
                 record.second_shot.stored ? "read from the store" : "traced", record.second_shot.seconds);
  }
}

// Iterations of the stored-line methods or classic passes. A checkpoint
// follows the first shot or a pass that ends solver.checkpoint_seconds or
// more after the solve began (`began`: before the first shot) or the last
// checkpoint was written, and the last pass, so that an interrupted run
// loses at most that long of finished work. Writing OFFICE's 8 MB state
// after each of 20 short passes took 0.13-0.17 s of a 2 s solve, all of it
// serial, and a short solve's first shot read from its store in 0.01 s was
// followed by a write of the whole state (docs/performance.md, "Checkpoints").
void run_iterations(const Options& options, const PatchMesh& mesh, const TracerOnDemand& tracer, const BoxStore* store,
                    const Checkpoint& checkpoint, clock::time_point began, RadiosityState& state,
                    SolveRecord& record) {
  const auto start = clock::now();
  record.hits_before = record.iterations.hits;
  IterationLog& log = record.iterations;
  auto written = began;
  bool saved = record.resumed;  // whether checkpoint.bin holds the state as it is now
  const auto write = [&] {
    checkpoint.save(state, log);
    written = clock::now();
    saved = true;
  };
  const auto save = [&] {
    saved = false;
    if (seconds_since(written) >= options.solver.checkpoint_seconds) write();
  };
  if (!record.resumed) save();  // the first shot
  if (store) {
    iterate(options, state, log,
            [&](unsigned pass) {
              return stored_iteration(options, mesh, tracer, *store, state, log, pass, options.solver.shards,
                                      &record.box_stats, &record.uncarried_lines);
            }, save);
  } else {
    iterate(options, state, log, [&](unsigned pass) {
      return classic_pass(mesh, tracer.get(), state, classic_pass_lines(options, mesh, log, state), options.lines.seed,
                          pass, options.solver.shards, options.lines.sequence, &record.uncarried_lines);
    }, save);
  }
  if (!saved) write();
  record.timings.iterations = seconds_since(start);
}

// The energy balance and what is left to distribute, in the log; a run
// stopped by the iteration cap is a warning, in the report too.
void log_remaining(const Options& options, const PatchMesh& mesh, const BoxStore* store, const RadiosityState& state,
                   const IterationLog& log, std::vector<std::string>& warnings) {
  const double e = state.emitted_total();
  spdlog::info("energy: unshot {:.3e} and held in ARs {:.3e} of emitted, balance residual {:.2e} (relative)",
               state.unshot_total() / e, state.held_total() / e, state.energy_residual() / e);
  if (store && !store->line_sets()) {  // what waits in walls, with the paper's transport
    const Remaining r = remaining_power(*store, state);
    spdlog::info("left to distribute: unshot {:.2e}, entering boxes {:.2e}, leaving boxes {:.2e} of emitted; most in box {} "
                 "({:.2e}); no stored line can carry {:.2e} (faces {:.2e}, ARs {:.2e})",
                 r.unshot / e, r.in / e, r.out / e, r.deepest_box, r.deepest_power / e,
                 (r.stuck_faces + r.stuck_in + r.stuck_out) / e, r.stuck_faces / e, (r.stuck_in + r.stuck_out) / e);
  }
  // Faces no stored line crosses never receive power from the stored lines
  // (only the first shot's): their reflected radiosity is missing.
  if (store) {
    const std::vector<bool> crossed = store->faces_crossed(mesh.face_count());
    size_t missed = 0;
    double area = 0, total = 0;
    for (size_t f = 0; f < crossed.size(); ++f) {
      total += mesh.face_area(static_cast<int>(f));
      if (crossed[f]) continue;
      ++missed;
      area += mesh.face_area(static_cast<int>(f));
    }
    if (missed > 0) {
      warnings.push_back(fmt::format(
          "{} face(s) ({:.3g} % of the area) are crossed by no stored line: they receive only the first shot's light, "
          "so their reflected radiosity is too low; use more lines.total or a larger mesh.max_patch_area",
          missed, 100.0 * area / total));
      spdlog::warn("{}", warnings.back());
    }
  }
  if (!log.converged) {
    warnings.push_back(fmt::format(
        "not converged: stopped at solver.iterations = {} with {:.3e} of the emitted power still to distribute "
        "(solver.tolerance = {}); run again with a larger solver.iterations and --resume to continue",
        options.solver.iterations, state.remaining_fraction(), options.solver.tolerance));
    spdlog::warn("{}", warnings.back());
  }
}

// solution.ply and, per camera, the EXR and PNG images; their names in `record`.
void write_outputs(const Options& options, const PatchMesh& mesh, const TracerOnDemand& tracer,
                   const std::vector<PointLight>& lights, const RadiosityState& state,
                   SolveRecord& record) {
  const auto start = clock::now();
  write_solution_ply(options.output.dir / "solution.ply", mesh, state.solution_faces(mesh));
  record.outputs.push_back("solution.ply");
  if (!options.cameras.empty() && (options.output.exr || options.output.png)) {
    const VertexRadiosity vertex_radiosity(mesh, state);
    for (const CameraOptions& cam : options.cameras) {
      const Image image = render_camera(cam, mesh, tracer.get(), vertex_radiosity, options.lines.seed);
      if (options.output.exr) {
        std::map<std::string, std::string> meta{{"mpathVersion", MPATH_VERSION},
                                                {"mpathCommit", MPATH_GIT_COMMIT},
                                                {"mpathMethod", to_string(options.solver.method)},
                                                {"mpathScene", options.scene.file.string()},
                                                {"mpathConfig", options_to_json(options)}};
        meta["mpathUnits"] = "radiance W/sr/m2, scene-referred (the exposure attribute is for viewers)";
        write_exr(options.output.dir / (cam.name + ".exr"), image, cam.exposure, meta);
        meta["mpathUnits"] = "luminance cd/m2 (179 lm/W times the luminance Y of the radiance)";
        write_scalar_exr(options.output.dir / (cam.name + ".luminance.exr"), image.width, image.height,
                         luminance_cd_m2(image), meta);
        record.outputs.push_back(cam.name + ".exr");
        record.outputs.push_back(cam.name + ".luminance.exr");
      }
      if (options.output.png) {
        write_png(options.output.dir / (cam.name + ".png"), image, cam.exposure);
        record.outputs.push_back(cam.name + ".png");
      }
    }
  }
  const std::vector<GridOptions> none;  // output.grids = false
  for (const GridOptions& grid : options.output.grids ? options.grids : none) {
    const GridResult result = measure_grid(grid, mesh, tracer.get(), state, lights, options.lines.seed);
    write_grid_csv(options.output.dir / (grid.name + ".csv"), result);
    write_grid_png(options.output.dir / (grid.name + ".png"), result);
    record.outputs.push_back(grid.name + ".csv");
    record.outputs.push_back(grid.name + ".png");
    record.grids.push_back(grid_json(result));
    spdlog::info("grid {}: illuminance min {:.4g}, mean {:.4g}, max {:.4g} lx, uniformity {:.3f}", grid.name,
                 result.min_lux, result.mean_lux, result.max_lux, result.uniformity());
  }
  record.timings.outputs = seconds_since(start);
}

}  // namespace

namespace {

void solve_on_threads(const Options& options, const SolveFlags& flags, int threads) {
  const auto start = clock::now();
  SolveRecord record;
  record.command_line = flags.command_line;
  record.threads = threads;
  record.ranks = Ranks::size();
  if (!Ranks::root()) spdlog::set_level(spdlog::level::err);  // rank 0 logs and warns for all
  spdlog::info("mpath-solve {} ({}), method {}, {} thread(s){}", MPATH_VERSION, MPATH_GIT_COMMIT,
               to_string(options.solver.method), record.threads,
               record.ranks > 1 ? fmt::format(" on each of {} MPI ranks", record.ranks) : "");

  // A store being rewritten by mpath-preprocess is not read (the lock is
  // shared: runs that only read it go on together).
  const bool reads_store =
      options.solver.method != SolverMethod::classic && std::filesystem::is_directory(options.store.dir);
  std::optional<DirectoryLock> store_lock;
  if (reads_store)
    store_lock.emplace(options.store.dir, kLockFile, DirectoryLock::Role::reader, "store.dir",
                       "mpath-preprocess is writing this store; solve when it has finished");
  StoreCheck check(options, reads_store);
  const PreparedScene prepared = prepare_scene(options);
  const PatchMesh& mesh = prepared.mesh;
  const std::unique_ptr<BoxStore> store = open_store(options, mesh, check, record.timings);
  if (flags.dry_run) {
    spdlog::info("dry run: config, scene{} are valid; nothing solved", store ? " and store" : "");
    return;
  }
  // Rank 0 writes the results (ranks.h); the others hold the same state.
  std::optional<DirectoryLock> output_lock;
  if (Ranks::root()) {
    create_folder(options.output.dir, "output.dir");
    output_lock.emplace(options.output.dir, kLockFile, DirectoryLock::Role::writer, "output.dir",
                        "two solves would overwrite each other's results and checkpoint; give this run "
                        "another output.dir, or wait");
  }

  // Embree's BVH is built when something is first traced (the first shot, a
  // classic pass, a camera); a kept store's solve may trace nothing.
  const TracerOnDemand tracer(mesh);

  RadiosityState state = make_state(prepared.scene, mesh);
  const std::vector<PointLight> lights = make_lights(options.scene.lights);
  for (const PointLight& l : lights) {
    spdlog::info("light {}: {:.4g} lm, {:.4g} W (at 179 lm/W)", l.options.name, l.flux(), l.power());
    record.lights.push_back({l.options.name, l.flux(), l.power(), 0});
  }
  if (store) add_ar_state(*store, state);
  spdlog::info("solving in {} channel(s); emitted power {:.6g} W", state.channels, state.emitted_total());
  const std::string geometry = store ? store->manifest().identity.at(kMeshHashKey) : mesh_hash(mesh);
  const Checkpoint checkpoint{options.output.dir / "checkpoint.bin", checkpoint_key(options, geometry)};
  const auto began = clock::now();
  start_state(options, flags, prepared.scene, mesh, tracer, store.get(), checkpoint, lights, state, record);
  run_iterations(options, mesh, tracer, store.get(), checkpoint, began, state, record);
  if (store && store->line_sets()) release_pass_memory(*store->line_sets());
  log_remaining(options, mesh, store.get(), state, record.iterations, record.warnings);
  if (!Ranks::root()) return;
  write_outputs(options, mesh, tracer, lights, state, record);
  record.timings.bvh = tracer.build_seconds();

  record.timings.total = seconds_since(start);
  const nlohmann::json report = solve_report(options, prepared, state, store.get(), record);
  write_text_file(options.output.dir / "report.json", json_text(report));
  spdlog::info("results in {} ({:.2f} s in all)", options.output.dir.string(), seconds_since(start));
}

}  // namespace

void run_solve(const Options& options, const SolveFlags& flags) {
  const int threads = effective_threads(options);
  run_on_threads(threads, [&] { solve_on_threads(options, flags, threads); });
}

}  // namespace mpath
