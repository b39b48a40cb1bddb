// The store's first and second shots (docs/store-format.md, "first_shot.bin"
// and "second_shot.bin"): the fate of every local line of each, written by
// mpath-preprocess when the store is complete, so that a solve on a kept
// store reads them instead of tracing them. What each line met does not
// depend on reflectances or on how much power its face shoots: a solve
// reweights the lines by the power it has, and traces a shot only where its
// plan differs (for the first shot other emitting faces, first_shot.lines,
// first_shot.mode; for the second, whose faces and line counts follow the
// unshot power after the first shot, also other materials or lights).
#pragma once

#include <filesystem>
#include <string>

#include "first_shot.h"
#include "prepared_scene.h"
#include "second_shot.h"

namespace mpath {

inline constexpr const char* kStoredShotFile = "first_shot.bin";
inline constexpr const char* kStoredSecondShotFile = "second_shot.bin";
inline constexpr const char* kStoredLightsFile = "lights_shot.bin";

// Which shot a file holds: the files differ in their magic and in the
// random streams their lines come from (second_shot_stream for the second,
// each light's light_seed for the lights').
enum class ShotKind { first, second, lights };

struct StoredShotStats {
  uint64_t lines = 0;
  uint64_t bytes = 0;
  double seconds = 0;
  bool written = false;  // false: the file there already held this plan
};

// Traces `plan` with lines.seed = `seed` on the threads and writes the
// lines' fates to `path` (under a temporary name until complete).
uint64_t write_stored_shot(const std::filesystem::path& path, const PatchMesh& mesh, const Tracer& tracer,
                           const FirstShotPlan& plan, unsigned long long seed, int zstd_level,
                           ShotKind kind = ShotKind::first);

// The plan and seed recorded in `path`; InputError naming the file when it
// is damaged or not a file of that shot.
FirstShotPlan read_stored_plan(const std::filesystem::path& path, size_t faces, unsigned long long& seed,
                               ShotKind kind = ShotKind::first);

// Adds the stored first shot at `path` to `state` when it was made with
// `plan` and `seed`, and returns ""; otherwise returns why not (the file is
// missing, or another plan), leaving `state` as it was. InputError when the
// file is damaged.
std::string replay_stored_shot(const std::filesystem::path& path, const PatchMesh& mesh, const FirstShotPlan& plan,
                               unsigned long long seed, RadiosityState& state, FirstShotStats& stats);

// The same for the second shot (second_shot.h): `plan` from the state after
// the first shot and the lights, the lines' power from it too.
std::string replay_stored_second_shot(const std::filesystem::path& path, const PatchMesh& mesh,
                                      const FirstShotPlan& plan, unsigned long long seed, RadiosityState& state,
                                      SecondShotStats& stats);

// The lights' shot (first_shot.h, shoot_lights) with first_shot.sequence =
// "halton": light l's lines[l] lines (light_line_count) from lines.seed =
// `seed`, traced on the threads, their fates written to `path` (under a
// temporary name until complete). With "random" a light's points are drawn
// per shard, so its lines depend on solver.shards: not stored.
uint64_t write_stored_lights(const std::filesystem::path& path, const PatchMesh& mesh, const Tracer& tracer,
                             const std::vector<PointLight>& lights, const std::vector<uint64_t>& lines,
                             unsigned long long seed, int zstd_level);

// Adds the stored lights' shot at `path` to `state` (their power to the
// emitted energy, as shoot_lights) when it was made for these lights (each
// light's position, frame and distribution: PointLight::lines_hash), `lines`
// and `seed`, and returns ""; otherwise returns why not, leaving `state` as
// it was. The lines carry the lights' power of this run. InputError when
// the file is damaged.
std::string replay_stored_lights(const std::filesystem::path& path, const PatchMesh& mesh,
                                 const std::vector<PointLight>& lights, const std::vector<uint64_t>& lines,
                                 unsigned long long seed, RadiosityState& state, LightsShotStats& stats);

// The store's crossing counts per face: by every box's lines
// (BoxStore::face_crossings) and by the root's (BoxStore::root_crossings).
struct StoreCrossings {
  std::vector<double> all, root;
};

// What mpath-preprocess runs once the store in options.store.dir is
// complete: the first shot a solve with these options would trace, its
// lights' shot, then the second shot it would trace after them (from the
// state the stored first shot and lights give), each written beside the box
// files unless the file there holds it already. `crossings`: the store's crossing counts, when
// the caller counted them; otherwise the store is opened to read them.
struct StoredShots {
  StoredShotStats first, second;  // second: lines 0 where the plan has none (the file removed)
  StoredShotStats lights;         // lines 0 without lights or with first_shot.sequence = "random" (no file)
};
StoredShots store_shots(const Options& options, const PreparedScene& prepared,
                        const StoreCrossings* crossings = nullptr);

}  // namespace mpath
