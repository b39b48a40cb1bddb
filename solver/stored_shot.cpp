#include "stored_shot.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_pipeline.h>
#include <zstd.h>

#include <chrono>
#include <cstring>
#include <fstream>

#include "atomic_file.h"
#include "box_store.h"
#include "error.h"
#include "hierarchical.h"
#include "progress.h"
#include "varint.h"
#include "zstd_frame.h"

namespace mpath {

namespace fs = std::filesystem;
using linestore::get_varint;
using linestore::put_varint;

namespace {

// File layout (docs/store-format.md): the magic, then frames, each as its
// raw and compressed sizes (two little-endian 64-bit words) and a zstd frame
// with its checksum: first the plan, then the lines' fates, kBlocksPerFrame
// blocks of kFirstShotBlock lines a frame; then the end magic.
constexpr char kMagic[8] = {'M', 'P', 'F', 'S', 'H', 'O', 'T', '1'};
constexpr char kEndMagic[8] = {'M', 'P', 'F', 'S', 'E', 'N', 'D', '1'};
// 1: independent points; 2: the plan ends with its sequence (1: Halton).
constexpr uint64_t kVersion = 2;
constexpr uint64_t kBlocksPerFrame = 64;

uint64_t frame_count(const FirstShotPlan& plan) {
  return (plan.blocks() + kBlocksPerFrame - 1) / kBlocksPerFrame;
}

std::string encode_plan(const FirstShotPlan& plan, unsigned long long seed, size_t faces) {
  std::string raw;
  for (uint64_t v : {kVersion, static_cast<uint64_t>(seed), kFirstShotBlock, kBlocksPerFrame, uint64_t{faces},
                     uint64_t{plan.emitters.size()}})
    put_varint(raw, v);
  int previous = -1;
  for (size_t e = 0; e < plan.emitters.size(); ++e) {
    put_varint(raw, static_cast<uint64_t>(plan.emitters[e] - previous));
    put_varint(raw, plan.count(e));
    previous = plan.emitters[e];
  }
  put_varint(raw, plan.global_faces.size());
  previous = -1;
  for (int f : plan.global_faces) {
    put_varint(raw, static_cast<uint64_t>(f - previous));
    previous = f;
  }
  put_varint(raw, plan.halton ? 1 : 0);
  return raw;
}

void put_u64(std::ostream& out, uint64_t v) {
  unsigned char b[8];
  for (int i = 0; i < 8; ++i) b[i] = static_cast<unsigned char>(v >> (8 * i));
  out.write(reinterpret_cast<const char*>(b), 8);
}

void write_frame(std::ostream& out, const std::string& raw, int level) {
  const std::string frame = linestore::zstd_compress(raw, level, true);
  put_u64(out, raw.size());
  put_u64(out, frame.size());
  out.write(frame.data(), static_cast<std::streamsize>(frame.size()));
}

// The fates of the lines of blocks [first_block, ...) of one frame: per
// block, per emitter's run of lines in it, the distinct codes in increasing
// order, each as its step from the one before (the first from 0) and how
// many lines had it, less one.
std::string encode_frame(const PatchMesh& mesh, const Tracer& tracer, const FirstShotPlan& plan,
                         unsigned long long seed, uint64_t first_block) {
  const double tfar = 4.0 * mesh.bounds.diagonal() + 1.0;
  const uint64_t blocks = plan.blocks();
  std::string raw;
  std::vector<uint32_t> codes;
  size_t run_emitter = 0;
  const auto flush = [&] {
    std::sort(codes.begin(), codes.end());
    uint32_t previous = 0;
    for (size_t i = 0; i < codes.size();) {
      size_t j = i;
      while (j < codes.size() && codes[j] == codes[i]) ++j;
      put_varint(raw, codes[i] - previous);
      put_varint(raw, j - i - 1);
      previous = codes[i];
      i = j;
    }
    codes.clear();
  };
  for (uint64_t b = first_block; b < std::min(blocks, first_block + kBlocksPerFrame); ++b) {
    bool started = false;
    trace_first_shot_block(
        mesh, plan, seed, b,
        [&](int from, const Vec3& org, const Vec3& dir) { return tracer.nearest_from(from, org, dir, tfar); },
        [&](size_t e, uint32_t code) {
          if (started && e != run_emitter) flush();
          started = true;
          run_emitter = e;
          codes.push_back(code);
        });
    flush();
  }
  return raw;
}

class ShotReader {
 public:
  ShotReader(const fs::path& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) fail("cannot be opened");
    size_ = fs::file_size(path);
    char magic[8];
    if (!in_.read(magic, 8) || std::memcmp(magic, kMagic, 8) != 0) fail("not a first-shot file (wrong magic)");
  }

  // The next frame's raw bytes, at most `max_raw` of them.
  const std::string& frame(uint64_t max_raw, const char* what) {
    const uint64_t raw_bytes = u64(what), bytes = u64(what);
    const uint64_t left = size_ - static_cast<uint64_t>(in_.tellg());
    if (raw_bytes > max_raw || bytes > left || bytes > ZSTD_compressBound(raw_bytes) + 64)
      fail(fmt::format("{}: corrupted (sizes {} and {} bytes)", what, raw_bytes, bytes));
    compressed_.resize(bytes);
    if (!in_.read(compressed_.data(), static_cast<std::streamsize>(bytes))) fail(fmt::format("{}: truncated", what));
    raw_.resize(raw_bytes);
    const size_t n = ZSTD_decompress(raw_.data(), raw_.size(), compressed_.data(), compressed_.size());
    if (ZSTD_isError(n)) fail(fmt::format("{}: corrupted ({})", what, ZSTD_getErrorName(n)));
    if (n != raw_bytes) fail(fmt::format("{}: corrupted (size {} instead of {})", what, n, raw_bytes));
    return raw_;
  }

  void expect_end() {
    char magic[8];
    if (!in_.read(magic, 8) || std::memcmp(magic, kEndMagic, 8) != 0) fail("truncated (no end mark)");
    if (in_.peek() != std::char_traits<char>::eof()) fail("corrupted (bytes after the end mark)");
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(fmt::format("{}: {}; the store's first shot is damaged: run mpath-preprocess again, or delete "
                                 "the file and mpath-solve traces the first shot itself",
                                 path_.string(), what));
  }

 private:
  uint64_t u64(const char* what) {
    unsigned char b[8];
    if (!in_.read(reinterpret_cast<char*>(b), 8)) fail(fmt::format("{}: truncated", what));
    uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<uint64_t>(b[i]) << (8 * i);
    return v;
  }

  fs::path path_;
  std::ifstream in_;
  uint64_t size_ = 0;
  std::string compressed_, raw_;
};

FirstShotPlan decode_plan(ShotReader& reader, size_t faces, unsigned long long& seed) {
  // Two varints per face at most, and a few more.
  const std::string& raw = reader.frame(64 + 30 * (uint64_t{faces} + 1), "plan");
  const auto* data = reinterpret_cast<const unsigned char*>(raw.data());
  size_t pos = 0;
  const auto next = [&](uint64_t limit) {
    uint64_t v;
    if (!get_varint(data, raw.size(), pos, v) || v > limit) reader.fail("plan: corrupted");
    return v;
  };
  const uint64_t version = next(UINT64_MAX);
  if (version != 1 && version != kVersion) reader.fail("plan: written by another version of mpath");
  seed = next(UINT64_MAX);
  if (next(UINT64_MAX) != kFirstShotBlock || next(UINT64_MAX) != kBlocksPerFrame)
    reader.fail("plan: written by another version of mpath");
  if (next(UINT64_MAX) != faces) reader.fail("plan: made for a mesh of another number of faces");
  FirstShotPlan plan;
  const uint64_t emitters = next(faces);
  int previous = -1;
  // Faces in increasing order, each as its step from the one before.
  const auto next_face = [&](int previous) {
    const uint64_t step = next(static_cast<uint64_t>(faces) - static_cast<uint64_t>(previous + 1));
    if (step == 0) reader.fail("plan: corrupted");
    return previous + static_cast<int>(step);
  };
  for (uint64_t e = 0; e < emitters; ++e) {
    previous = next_face(previous);
    plan.emitters.push_back(previous);
    const uint64_t lines = next(uint64_t{1} << 48);
    if (lines == 0 || plan.first.back() + lines > (uint64_t{1} << 48)) reader.fail("plan: corrupted");
    plan.first.push_back(plan.first.back() + lines);
  }
  const uint64_t global = next(faces);
  previous = -1;
  for (uint64_t g = 0; g < global; ++g) {
    previous = next_face(previous);
    plan.global_faces.push_back(previous);
  }
  plan.halton = version >= 2 && next(1) == 1;
  if (pos != raw.size()) reader.fail("plan: corrupted");
  return plan;
}

// Why a run's plan is not the stored one, in words.
std::string plan_difference(const FirstShotPlan& run, const FirstShotPlan& stored) {
  if (run.emitters != stored.emitters || run.global_faces != stored.global_faces)
    return "this run's emitting faces are not the store's (emission or first_shot.mode changed since mpath-preprocess)";
  return fmt::format("this run gives its emitters other line counts ({} lines, the store {}: first_shot.lines or the "
                     "emitters' relative power changed since mpath-preprocess)",
                     run.lines(), stored.lines());
}

}  // namespace

uint64_t write_stored_shot(const fs::path& path, const PatchMesh& mesh, const Tracer& tracer, const FirstShotPlan& plan,
                           unsigned long long seed, int zstd_level) {
  AtomicFile file(path);
  std::ostream& out = file.stream();
  out.write(kMagic, 8);
  write_frame(out, encode_plan(plan, seed, mesh.face_count()), zstd_level);
  const uint64_t frames = frame_count(plan);
  Progress progress("first shot for the store", plan.lines(), "lines", true);
  uint64_t next = 0, written = 0;
  tbb::parallel_pipeline(
      16,
      tbb::make_filter<void, uint64_t>(tbb::filter_mode::serial_in_order,
                                       [&](tbb::flow_control& fc) -> uint64_t {
                                         if (next >= frames) {
                                           fc.stop();
                                           return 0;
                                         }
                                         return next++;
                                       }) &
          tbb::make_filter<uint64_t, std::string>(tbb::filter_mode::parallel,
                                                  [&](uint64_t f) {
                                                    return encode_frame(mesh, tracer, plan, seed, f * kBlocksPerFrame);
                                                  }) &
          tbb::make_filter<std::string, void>(tbb::filter_mode::serial_in_order, [&](const std::string& raw) {
            write_frame(out, raw, zstd_level);
            const uint64_t lines = std::min(kBlocksPerFrame * kFirstShotBlock, plan.lines() - written);
            written += lines;
            progress.advance(lines);
          }));
  progress.finish();
  out.write(kEndMagic, 8);
  file.commit();
  return fs::file_size(path);
}

FirstShotPlan read_stored_plan(const fs::path& path, size_t faces, unsigned long long& seed) {
  ShotReader reader(path);
  return decode_plan(reader, faces, seed);
}

std::string replay_stored_shot(const fs::path& path, const PatchMesh& mesh, const FirstShotPlan& plan,
                               unsigned long long seed, RadiosityState& state, FirstShotStats& stats) {
  if (!fs::exists(path)) return fmt::format("the store has no {} (made by an older mpath-preprocess)", kStoredShotFile);
  const auto start = std::chrono::steady_clock::now();
  ShotReader reader(path);
  unsigned long long stored_seed = 0;
  const FirstShotPlan stored = decode_plan(reader, mesh.face_count(), stored_seed);
  if (stored_seed != seed) return fmt::format("the store's first shot was drawn with lines.seed = {}", stored_seed);
  // The store's points, Halton or independent, serve any run: both give
  // an unbiased shot (stores made before first_shot.sequence hold
  // independent ones).
  FirstShotPlan same = stored;
  same.halton = plan.halton;
  if (!(same == plan)) return plan_difference(plan, stored);
  stats.halton = stored.halton;

  // Decoded and checked in full before the state changes.
  ShardAccumulator acc;
  acc.reset(state.faces);
  const uint32_t limit = code_limit(mesh.face_count());
  const uint64_t frames = frame_count(plan);
  size_t e = 0;
  for (uint64_t f = 0; f < frames; ++f) {
    const uint64_t lo = f * kBlocksPerFrame * kFirstShotBlock;
    const uint64_t hi = std::min(plan.lines(), lo + kBlocksPerFrame * kFirstShotBlock);
    const std::string& raw = reader.frame((hi - lo) * 20, "lines");
    const auto* data = reinterpret_cast<const unsigned char*>(raw.data());
    size_t pos = 0;
    // Runs of lines of one emitter within one block, in line order.
    for (uint64_t line = lo; line < hi;) {
      while (line >= plan.first[e + 1]) ++e;
      const uint64_t block_end = (line / kFirstShotBlock + 1) * kFirstShotBlock;
      const uint64_t run_end = std::min({hi, plan.first[e + 1], block_end});
      uint64_t code = 0, seen = 0;
      while (seen < run_end - line) {
        uint64_t step, more;
        if (!get_varint(data, raw.size(), pos, step) || !get_varint(data, raw.size(), pos, more) ||
            (seen > 0 && step == 0) || step >= limit - code || more >= run_end - line - seen)
          reader.fail(fmt::format("lines of frame {}: corrupted", f));
        code += step;
        seen += more + 1;
        receive_emitter_lines(state, plan, e, static_cast<uint32_t>(code), more + 1, acc);
      }
      line = run_end;
    }
    if (pos != raw.size()) reader.fail(fmt::format("lines of frame {}: corrupted", f));
  }
  reader.expect_end();
  leave_to_global_lines(plan, state);
  acc.lines = plan.lines();
  merge_received(std::vector<ShardAccumulator>{std::move(acc)}, state);
  stats.lines = plan.lines();
  stats.emitter_faces = plan.emitters.size();
  stats.global_emitter_faces = plan.global_faces.size();
  stats.stored = true;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return "";
}

StoredShotStats store_first_shot(const Options& options, const PreparedScene& prepared,
                                 const std::vector<double>* crossings) {
  const auto start = std::chrono::steady_clock::now();
  const PatchMesh& mesh = prepared.mesh;
  const fs::path path = options.store.dir / kStoredShotFile;
  StoredShotStats stats;
  RadiosityState state = make_state(prepared.scene, mesh);
  const std::vector<PointLight> lights = make_lights(options.scene.lights);
  const FirstShotPlan plan =
      (crossings ? plan_run_first_shot(options, mesh, state, *crossings, lights)
                 : plan_run_first_shot(options, mesh, state, BoxStore(options, mesh).face_crossings(mesh.face_count()), lights))
          .plan;
  stats.lines = plan.lines();
  if (fs::exists(path)) {
    // Kept only when a solve would read it: its plan, and every frame
    // checked (a damaged file is written again, as the solve's error says).
    try {
      RadiosityState scratch = state;
      FirstShotStats read;
      if (replay_stored_shot(path, mesh, plan, options.lines.seed, scratch, read).empty()) {
        stats.bytes = fs::file_size(path);
        spdlog::info("{}: the first shot of this scene, written earlier, kept", path.string());
        return stats;
      }
    } catch (const InputError& e) {
      spdlog::warn("{}; writing it again", e.what());
    }
  }
  const Tracer tracer(mesh);
  stats.bytes = write_stored_shot(path, mesh, tracer, plan, options.lines.seed, options.store.zstd_level);
  stats.written = true;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  spdlog::info("{}: the first shot, {} local lines from {} emitting face(s), {:.2f} MB ({:.2f} s)", path.string(),
               plan.lines(), plan.emitters.size(), stats.bytes / 1e6, stats.seconds);
  return stats;
}

}  // namespace mpath
