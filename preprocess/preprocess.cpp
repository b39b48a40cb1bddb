#include "preprocess.h"

#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_pipeline.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <optional>
#include <nlohmann/json.hpp>

#include "atomic_file.h"
#include "box_file.h"
#include "directory_lock.h"
#include "error.h"
#include "on_threads.h"
#include "hash.h"
#include "hierarchy.h"
#include "json_text.h"
#include "line_budget.h"
#include "line_tracing.h"
#include "manifest.h"
#include "mpath_version.h"
#include "pilot.h"
#include "prepared_scene.h"
#include "process_memory.h"
#include "progress.h"
#include "store_identity.h"
#include "stored_shot.h"

namespace mpath {

namespace fs = std::filesystem;
using clock = std::chrono::steady_clock;

ShardSpec parse_shard(const std::string& text) {
  ShardSpec s;
  char slash = 0;
  std::istringstream in(text);
  if (!(in >> s.index >> slash >> s.count) || slash != '/' || !in.eof() || s.count < 1 || s.index < 1 ||
      s.index > s.count)
    throw InputError(fmt::format("--shard: expected i/n with 1 <= i <= n, got '{}'", text));
  return s;
}

namespace {

double seconds(clock::duration d) { return std::chrono::duration<double>(d).count(); }

std::string file_name(int box, const ShardSpec& shard) {
  if (shard.count == 1) return fmt::format("box{:04}.lines", box);
  return fmt::format("box{:04}.part{:04}of{:04}.lines", box, shard.index, shard.count);
}

fs::path part_manifest(const fs::path& dir, const ShardSpec& shard) {
  return dir / fmt::format("part{:04}of{:04}.json", shard.index, shard.count);
}

linestore::Manifest base_manifest(const Options& options, const PatchMesh& mesh, const Hierarchy& hierarchy,
                                  const std::vector<uint64_t>& budget,
                                  const std::map<std::string, std::string>& identity) {
  linestore::Manifest m;
  m.format_version = linestore::kFormatVersion;
  m.mpath_version = fmt::format("{} ({})", MPATH_VERSION, MPATH_GIT_COMMIT);
  m.identity = identity;
  m.patches = mesh.patches.size();
  m.faces = mesh.face_count();
  m.lines_total = 0;
  for (uint64_t n : budget) m.lines_total += n;
  m.chunk_lines = static_cast<uint64_t>(options.store.chunk_lines);
  // What first_shot.bin will hold, for the solves (with first_shot.accelerate they trace it).
  m.first_shot_lines = options.first_shot.accelerate ? 0 : static_cast<uint64_t>(first_shot_lines(options));
  for (size_t b = 0; b < hierarchy.boxes.size(); ++b) {
    const SceneBox& box = hierarchy.boxes[b];
    linestore::BoxEntry e;
    e.parent = box.parent;
    e.depth = box.depth;
    for (int i = 0; i < 3; ++i) {
      e.lo[i] = box.bounds.lo[i];
      e.hi[i] = box.bounds.hi[i];
    }
    e.lines = budget[b];
    e.patches = box.patches.size();
    e.ars = box.ar_count();
    e.objects = static_cast<uint64_t>(box.objects_total);
    e.quotient = box.quotient;
    e.direct_objects = box.objects;
    m.boxes.push_back(e);
  }
  return m;
}

// A shard's record, when it and its files exist, match this run and verify.
std::optional<linestore::Manifest> finished_and_verified(const fs::path& record, const fs::path& dir,
                                                         const std::map<std::string, std::string>& identity) {
  if (!fs::exists(record)) return std::nullopt;
  try {
    linestore::Manifest m = linestore::read_manifest(record);
    if (!linestore::identity_mismatch(identity, m.identity).empty() || m.files.empty()) return std::nullopt;
    for (const linestore::StoreFile& f : m.files) {
      const fs::path file = dir / f.name;
      if (!fs::exists(file) || fs::file_size(file) != f.bytes || hash_file(file) != f.hash) return std::nullopt;
    }
    return m;
  } catch (const InputError&) {
    return std::nullopt;
  }
}

// A store finished earlier keeps the boxes and lines it was made with (its
// solves use them). Where this run would make others (the pilot budget saw
// other materials or emitters, or an earlier mpath built the hierarchy
// differently), the log says which and how to get the new ones.
void note_other_hierarchy(const linestore::Manifest& record, const fs::path& dir, const linestore::Manifest& base) {
  const std::vector<linestore::BoxEntry>& kept = record.boxes;
  const std::vector<linestore::BoxEntry>& now = base.boxes;
  if (kept == now) return;
  auto lines = [](const std::vector<linestore::BoxEntry>& boxes) {
    std::vector<uint64_t> out;
    for (const linestore::BoxEntry& b : boxes) out.push_back(b.lines);
    return fmt::format("{}", fmt::join(out, ", "));
  };
  spdlog::warn("{}: the store was made with {} box(es) of {} lines; this run would make {} box(es) of {} lines (the pilot "
               "budget saw other materials or emitters, or an earlier mpath built the hierarchy). The store stays valid "
               "and its solves use its own boxes; remove it, or give another store.dir, to trace the new ones",
               dir.string(), kept.size(), lines(kept), now.size(), lines(now));
}

// When every part of a sharded store is there and matches, writes manifest.json.
bool merge_parts(const fs::path& dir, const ShardSpec& shard, linestore::Manifest merged) {
  for (int i = 1; i <= shard.count; ++i) {
    const fs::path record = part_manifest(dir, {i, shard.count});
    if (!fs::exists(record)) return false;
    const linestore::Manifest part = linestore::read_manifest(record);
    // Another shard of another config (an earlier run's, or one still to be
    // run again): the store is not complete, and the log says why. Not an
    // error: in a job array that shard may be running again right now.
    if (const std::string mismatch = linestore::identity_mismatch(merged.identity, part.identity); !mismatch.empty()) {
      spdlog::warn("{}: shard {} of {} was made with another scene or config ({}); the store is complete once that "
                   "shard has run again with this config", record.string(), i, shard.count, mismatch);
      return false;
    }
    merged.files.insert(merged.files.end(), part.files.begin(), part.files.end());
  }
  linestore::write_manifest(dir / "manifest.json", merged);
  return true;
}

}  // namespace

namespace {

// Traces the shard's part of one box's lines into one file; adds to `stats`,
// and to `crossings` how often the lines cross each face (as
// BoxStore::face_crossings and, for the root, root_crossings count them from
// the file).
linestore::StoreFile trace_box(const Options& options, const PatchMesh& mesh, const Hierarchy& hierarchy, int box,
                               uint64_t lines, const ShardSpec& shard, const fs::path& dir, int threads,
                               PreprocessStats& stats, StoreCrossings& crossings) {
  const ChunkTracer chunks(options, mesh, hierarchy, box, lines);
  const uint64_t lo = chunks.chunk_count() * (shard.index - 1) / shard.count;
  const uint64_t hi = chunks.chunk_count() * shard.index / shard.count;
  uint64_t shard_lines = 0;
  for (uint64_t c = lo; c < hi; ++c) shard_lines += chunks.lines_in(c);

  const fs::path path = dir / file_name(box, shard);
  linestore::BoxFileWriter writer(path, static_cast<uint32_t>(box));
  tbb::enumerable_thread_specific<BoxTally> tallies([&] { return chunks.empty_tally(); });
  std::atomic<uint64_t> trace_ns{0}, encode_ns{0}, compress_ns{0};
  auto ns = [](clock::duration d) { return static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(d).count()); };
  Progress progress(fmt::format("tracing {}", path.filename().string()), shard_lines, "lines", true);
  uint64_t next = lo, file_lines = 0, file_events = 0;
  double write_seconds = 0;
  tbb::parallel_pipeline(
      static_cast<size_t>(2 * threads),
      tbb::make_filter<void, uint64_t>(tbb::filter_mode::serial_in_order,
                                       [&](tbb::flow_control& fc) -> uint64_t {
                                         if (next >= hi) {
                                           fc.stop();
                                           return 0;
                                         }
                                         return next++;
                                       }) &
          tbb::make_filter<uint64_t, linestore::EncodedChunk>(
              tbb::filter_mode::parallel,
              [&](uint64_t c) {
                thread_local TracedChunk records;  // keeps its memory from chunk to chunk
                auto t0 = clock::now();
                chunks.trace(c, records, tallies.local());
                auto t1 = clock::now();
                uint64_t events = 0;
                const std::string raw = linestore::encode_lines(records.lines, records.order.data(), events);
                auto t2 = clock::now();
                linestore::EncodedChunk out =
                    linestore::compress_chunk(raw, chunks.first_line(c), records.order.size(), events, options.store.zstd_level);
                auto t3 = clock::now();
                trace_ns += ns(t1 - t0);
                encode_ns += ns(t2 - t1);
                compress_ns += ns(t3 - t2);
                return out;
              }) &
          tbb::make_filter<linestore::EncodedChunk, void>(tbb::filter_mode::serial_in_order,
                                                          [&](const linestore::EncodedChunk& chunk) {
                                                            auto t0 = clock::now();
                                                            writer.write(chunk);
                                                            write_seconds += seconds(clock::now() - t0);
                                                            file_lines += chunk.info.lines;
                                                            file_events += chunk.info.events;
                                                            stats.raw_bytes += chunk.info.raw_bytes;
                                                            progress.advance(chunk.info.lines);
                                                          }));
  progress.finish();
  BoxTally total = chunks.empty_tally();
  for (const BoxTally& t : tallies) t.merge_into(total);
  chunks.finish_tally(total);
  std::vector<std::pair<uint64_t, uint32_t>> first_met(total.first_met.begin(), total.first_met.end());
  std::sort(first_met.begin(), first_met.end());
  linestore::select_associated(first_met, total.counts);
  const std::vector<uint32_t>& patches = hierarchy.boxes[box].patches;
  for (size_t k = 0; k < patches.size(); ++k)
    for (int face : mesh.patch_faces[patches[k]])
      if (face >= 0) {
        crossings.all[face] += total.counts.patch_crossings[k];
        if (box == 0) crossings.root[face] += total.counts.patch_crossings[k];
      }
  auto t0 = clock::now();
  writer.finish(total.counts);
  write_seconds += seconds(clock::now() - t0);
  const uint64_t bytes = fs::file_size(path);
  stats.lines += file_lines;
  stats.events += file_events;
  stats.bytes += bytes;
  stats.trace_seconds += trace_ns * 1e-9;
  stats.encode_seconds += encode_ns * 1e-9;
  stats.compress_seconds += compress_ns * 1e-9;
  stats.write_seconds += write_seconds;
  return {path.filename().string(), static_cast<uint32_t>(box), chunks.first_line(lo), file_lines, file_events,
          hi - lo, bytes, hash_file(path)};
}

// Once the store is complete, the first and second shots a solve of it
// would trace (stored_shot.h); not with first_shot.accelerate, whose solves
// trace them.
// `crossings`: counted by this run over every line of the store (null: the
// store is opened to count them).
void add_shots(const Options& options, const PreparedScene& prepared, PreprocessStats& stats,
               const StoreCrossings* crossings) {
  if (options.first_shot.accelerate) return;
  const StoredShots shots = store_shots(options, prepared, crossings);
  stats.first_shot_lines = shots.first.lines;
  stats.first_shot_bytes = shots.first.bytes;
  stats.first_shot_seconds = shots.first.seconds;
  stats.second_shot_lines = shots.second.lines;
  stats.second_shot_bytes = shots.second.bytes;
  stats.second_shot_seconds = shots.second.seconds;
  stats.lights_shot_lines = shots.lights.lines;
  stats.lights_shot_bytes = shots.lights.bytes;
  stats.lights_shot_seconds = shots.lights.seconds;
}

}  // namespace

namespace {

PreprocessStats preprocess_on_threads(const Options& options, const ShardSpec& shard, bool dry_run,
                                      bool print_hierarchy, int threads) {
  const auto start = clock::now();
  spdlog::info("mpath-preprocess {} ({}), shard {}/{}, {} thread(s)", MPATH_VERSION, MPATH_GIT_COMMIT, shard.index,
               shard.count, threads);
  PreparedScene prepared = prepare_scene(options);
  const PatchMesh& mesh = prepared.mesh;
  PreprocessStats stats;
  auto t = clock::now();
  const Hierarchy hierarchy = store_hierarchy(options, mesh, nullptr, &prepared.scene);
  stats.hierarchy_seconds = seconds(clock::now() - t);
  // The pilot sets the boxes' lines (the pilot budget) and the first shot's
  // (first_shot.lines = 0), which this run stores for the solves.
  std::vector<double> pilot;
  const bool boxes_need_pilot = options.lines.box_budget == "pilot" && hierarchy.boxes.size() > 1;
  const bool shot_needs_pilot = options.first_shot.lines == 0 && !options.first_shot.accelerate && !print_hierarchy &&
                                !dry_run;
  Options run = options;
  if (boxes_need_pilot || shot_needs_pilot) {
    t = clock::now();
    const long long lines = options.lines.pilot_lines();
    // The lights are shot by every solve, but what they light is in the boxes.
    const Pilot p = run_pilot(prepared.scene, mesh, &hierarchy, options.lines.seed, static_cast<uint64_t>(lines),
                              options.first_shot.halton(), nullptr, make_lights(options.scene.lights));
    if (boxes_need_pilot) pilot = p.box_weights;
    stats.pilot_seconds = seconds(clock::now() - t);
    stats.pilot_lines = static_cast<uint64_t>(lines);
    spdlog::info("pilot: {} local and {} global lines ({:.2f} s){}", lines, lines, stats.pilot_seconds,
                 p.empty() ? ": nothing emits" + std::string(boxes_need_pilot ? ", the subscenes share by quotient" : "")
                           : "");
    if (shot_needs_pilot) {
      stats.first_shot_share = first_shot_share(p);
      run.first_shot.chosen = first_shot_lines_for_share(options, stats.first_shot_share);
      log_first_shot_choice(p, run.first_shot.chosen, options.lines.total);
    }
  }
  const std::vector<uint64_t> budget = box_line_budget(hierarchy, options.lines, pilot);
  if (!pilot.empty())
    spdlog::info("pilot budget: {:.1f} % of the lines in the root, the subscenes {}", 100.0 * budget[0] /
                 static_cast<double>(options.lines.total), fmt::join(budget.begin() + 1, budget.end(), ", "));
  spdlog::info("hierarchy: {} box(es), depth {} ({:.2f} s)", hierarchy.boxes.size(), hierarchy.max_depth(),
               stats.hierarchy_seconds);
  if (print_hierarchy) {
    fmt::print("{}", describe_hierarchy(hierarchy, budget));
    return stats;
  }
  if (dry_run) return stats;

  const fs::path dir = options.store.dir;
  create_folder(dir, "store.dir");
  // One run writes the store at a time; shards of one store run together,
  // each part once.
  const char* busy = "another mpath-preprocess is writing it, or mpath-solve is reading it; wait for that run, or "
                     "give this one another store.dir";
  const DirectoryLock store_lock(dir, kLockFile, shard.count == 1 ? DirectoryLock::Role::writer : DirectoryLock::Role::shard,
                                 "store.dir", busy);
  std::optional<DirectoryLock> shard_lock;
  if (shard.count > 1)
    shard_lock.emplace(dir, fmt::format("{}.part{:04}of{:04}", kLockFile, shard.index, shard.count),
                       DirectoryLock::Role::writer, fmt::format("shard {}/{} of store.dir", shard.index, shard.count),
                       "that shard is being traced by another mpath-preprocess; run each shard once");
  const auto identity = store_identity(options, mesh);
  const linestore::Manifest base = base_manifest(run, mesh, hierarchy, budget, identity);
  const fs::path record = shard.count == 1 ? dir / "manifest.json" : part_manifest(dir, shard);
  if (const auto finished = finished_and_verified(record, dir, identity)) {
    spdlog::info("{}: shard {}/{} finished and verified earlier, not traced again", dir.string(), shard.index, shard.count);
    note_other_hierarchy(*finished, dir, base);
    stats.skipped = true;
    if (shard.count > 1) stats.manifest_written = merge_parts(dir, shard, base);
    if (shard.count == 1 || stats.manifest_written) add_shots(run, prepared, stats, nullptr);
    return stats;
  }
  // The store is incomplete from now until this run's manifest is written.
  std::error_code ec;
  fs::remove(dir / "manifest.json", ec);
  fs::remove(record, ec);

  linestore::Manifest m = base;
  nlohmann::json per_box = nlohmann::json::array();
  StoreCrossings crossings{std::vector<double>(mesh.face_count(), 0.0), std::vector<double>(mesh.face_count(), 0.0)};
  for (int b : hierarchy.depth_order) {
    const auto t0 = clock::now();
    m.files.push_back(trace_box(options, mesh, hierarchy, b, budget[b], shard, dir, threads, stats, crossings));
    per_box.push_back({{"box", b}, {"lines", m.files.back().lines}, {"events", m.files.back().events},
                       {"bytes", m.files.back().bytes}, {"seconds", seconds(clock::now() - t0)}});
  }
  linestore::write_manifest(record, m);
  stats.manifest_written = shard.count == 1 || merge_parts(dir, shard, base);
  // A shard's lines are part of the store's: the last shard opens the store to count them all.
  if (stats.manifest_written) add_shots(run, prepared, stats, shard.count == 1 ? &crossings : nullptr);
  stats.wall_seconds = seconds(clock::now() - start);
  const nlohmann::json timings = {{"shard", fmt::format("{}/{}", shard.index, shard.count)}, {"lines", stats.lines},
                                 {"events", stats.events}, {"bytes", stats.bytes}, {"raw_bytes", stats.raw_bytes},
                                 {"hierarchy_seconds", stats.hierarchy_seconds}, {"pilot_seconds", stats.pilot_seconds},
                                 {"pilot_lines", stats.pilot_lines}, {"first_shot_share", stats.first_shot_share},
                                 {"first_shot_seconds", stats.first_shot_seconds},
                                 {"first_shot_lines", stats.first_shot_lines},
                                 {"first_shot_bytes", stats.first_shot_bytes},
                                 {"second_shot_seconds", stats.second_shot_seconds},
                                 {"second_shot_lines", stats.second_shot_lines},
                                 {"second_shot_bytes", stats.second_shot_bytes},
                                 {"lights_shot_seconds", stats.lights_shot_seconds},
                                 {"lights_shot_lines", stats.lights_shot_lines},
                                 {"lights_shot_bytes", stats.lights_shot_bytes},
                                 {"trace_seconds", stats.trace_seconds}, {"encode_seconds", stats.encode_seconds},
                                 {"compress_seconds", stats.compress_seconds}, {"write_seconds", stats.write_seconds},
                                 {"wall_seconds", stats.wall_seconds}, {"threads", threads},
                                 {"peak_rss_bytes", peak_rss_bytes()},
                                 {"transparent_huge_pages", transparent_huge_pages()},
                                 {"malloc_huge_pages", malloc_asks_for_huge_pages()}, {"boxes", per_box}};
  write_text_file(dir / (shard.count == 1 ? std::string("preprocess.json")
                                          : fmt::format("preprocess.part{:04}of{:04}.json", shard.index, shard.count)),
                  json_text(timings));
  spdlog::info("{}: {} box file(s), {} lines, {} events, {:.3f} bytes/event on disk ({:.2f} before compression), {:.1f} MB",
               dir.string(), m.files.size(), stats.lines, stats.events,
               stats.events ? double(stats.bytes) / stats.events : 0.0,
               stats.events ? double(stats.raw_bytes) / stats.events : 0.0, stats.bytes / 1e6);
  if (shard.count > 1 && !stats.manifest_written)
    spdlog::info("store not complete yet: manifest.json is written when every shard of {} has finished", shard.count);
  return stats;
}

}  // namespace

PreprocessStats run_preprocess(const Options& options, const ShardSpec& shard, bool dry_run, bool print_hierarchy) {
  const int threads = effective_threads(options);
  return run_on_threads(threads, [&] { return preprocess_on_threads(options, shard, dry_run, print_hierarchy, threads); });
}

}  // namespace mpath
