// The store's first shot (docs/store-format.md, "first_shot.bin"): the fate
// of every local line of the first shot, written by mpath-preprocess when
// the store is complete, so that a solve on a kept store reads it instead of
// tracing it. What each line met does not depend on reflectances or on how
// bright its emitter is: a solve reweights the lines by the emission it
// has, and traces the first shot only where the plan differs (other
// emitting faces, first_shot.lines, first_shot.mode).
#pragma once

#include <filesystem>
#include <string>

#include "first_shot.h"
#include "prepared_scene.h"

namespace mpath {

inline constexpr const char* kStoredShotFile = "first_shot.bin";

struct StoredShotStats {
  uint64_t lines = 0;
  uint64_t bytes = 0;
  double seconds = 0;
  bool written = false;  // false: the file there already held this plan
};

// Traces `plan` with `seed` on the threads and writes the lines' fates to
// `path` (under a temporary name until complete).
uint64_t write_stored_shot(const std::filesystem::path& path, const PatchMesh& mesh, const Tracer& tracer,
                           const FirstShotPlan& plan, unsigned long long seed, int zstd_level);

// The plan and seed recorded in `path`; InputError naming the file when it
// is damaged or not a first-shot file.
FirstShotPlan read_stored_plan(const std::filesystem::path& path, size_t faces, unsigned long long& seed);

// Adds the stored first shot at `path` to `state` when it was made with
// `plan` and `seed`, and returns ""; otherwise returns why not (the file is
// missing, or another plan), leaving `state` as it was. InputError when the
// file is damaged.
std::string replay_stored_shot(const std::filesystem::path& path, const PatchMesh& mesh, const FirstShotPlan& plan,
                               unsigned long long seed, RadiosityState& state, FirstShotStats& stats);

// What mpath-preprocess runs once the store in options.store.dir is
// complete: the first shot a solve with these options would trace, written
// beside the box files, unless the file there holds it already. `crossings`:
// the store's crossing counts per face (BoxStore::face_crossings), when the
// caller counted them; otherwise the store is opened to read them.
StoredShotStats store_first_shot(const Options& options, const PreparedScene& prepared,
                                 const std::vector<double>* crossings = nullptr);

}  // namespace mpath
