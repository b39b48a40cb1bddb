#include "stored_shot.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_pipeline.h>
#include <zstd.h>

#include <algorithm>
#include <chrono>
#include <initializer_list>
#include <cstring>
#include <fstream>
#include <optional>

#include "atomic_file.h"
#include "box_store.h"
#include "error.h"
#include "hierarchical.h"
#include "progress.h"
#include "radix_sort.h"
#include "second_shot.h"
#include "varint.h"
#include "zstd_frame.h"

namespace mpath {

namespace fs = std::filesystem;
using linestore::get_varint;
using linestore::put_varint;

namespace {

// File layout (docs/store-format.md): the magic, then frames, each as its
// raw and compressed sizes (two little-endian 64-bit words) and a zstd frame
// with its checksum: first the plan, then the lines' fates, frame_blocks
// blocks of kFirstShotBlock lines a frame; then the end magic.
// The second shot's file has magics of its own ("MPSSHOT1", "MPSSEND1"), and
// so has the lights' ("MPLSHOT1", "MPLSEND1"), whose plan differs too.
struct KindTraits {
  char magic[8], end[8];
  const char* name;   // "first shot"
  const char* which;  // "first"
};
constexpr KindTraits kKinds[3] = {
    {{'M', 'P', 'F', 'S', 'H', 'O', 'T', '1'}, {'M', 'P', 'F', 'S', 'E', 'N', 'D', '1'}, "first shot", "first"},
    {{'M', 'P', 'S', 'S', 'H', 'O', 'T', '1'}, {'M', 'P', 'S', 'S', 'E', 'N', 'D', '1'}, "second shot", "second"},
    {{'M', 'P', 'L', 'S', 'H', 'O', 'T', '1'}, {'M', 'P', 'L', 'S', 'E', 'N', 'D', '1'}, "lights' shot", "lights"}};
const KindTraits& traits(ShotKind kind) { return kKinds[static_cast<size_t>(kind)]; }

// The seed of the streams the lines of a shot drawn with lines.seed = `seed` come from.
unsigned long long stream_seed(ShotKind kind, unsigned long long seed) {
  return kind == ShotKind::first ? seed : second_shot_stream(seed);
}
// 1: independent points; 2: the plan ends with its sequence (1: Halton).
constexpr uint64_t kVersion = 2;
constexpr uint64_t kMaxFrameBlocks = 64;

// Blocks a frame of `plan` holds: about a 64th of its blocks, at least one,
// at most 64, so that the threads share even a short shot (with 64 blocks a
// frame, as until December 2026, a 250,000-line second shot was one frame,
// traced by one thread); recorded in the plan, so a reader takes any.
uint64_t frame_blocks(const FirstShotPlan& plan) {
  return std::clamp<uint64_t>((plan.blocks() + 63) / 64, 1, kMaxFrameBlocks);
}

uint64_t frame_count(const FirstShotPlan& plan, uint64_t blocks_a_frame) {
  return (plan.blocks() + blocks_a_frame - 1) / blocks_a_frame;
}

// The header every shot file's plan starts with (PlanFields::header reads
// it): the version, lines.seed, the block's lines, the blocks a frame of
// `frames` holds and the mesh's faces; then `count` (the plan's emitters).
std::string plan_header(uint64_t version, unsigned long long seed, const FirstShotPlan& frames, size_t faces,
                        uint64_t count) {
  std::string raw;
  for (uint64_t v : {version, static_cast<uint64_t>(seed), kFirstShotBlock, frame_blocks(frames), uint64_t{faces}, count})
    put_varint(raw, v);
  return raw;
}

std::string encode_plan(const FirstShotPlan& plan, unsigned long long seed, size_t faces) {
  std::string raw = plan_header(kVersion, seed, plan, faces, plan.emitters.size());
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

// The fates of the lines of blocks [first_block, ...) of one frame of a
// shot of `blocks` blocks (trace_block(b, line) calls line(e, code) for
// block b's lines in order, e the emitter's index): per block, per
// emitter's run of lines in it, the distinct codes in increasing order,
// each as its step from the one before (the first from 0) and how many
// lines had it, less one.
template <typename TraceBlock>
std::string encode_frame(uint64_t blocks, uint64_t first_block, uint64_t blocks_a_frame, const TraceBlock& trace_block) {
  std::string raw;
  std::vector<uint32_t> codes, scratch;
  size_t run_emitter = 0;
  const auto flush = [&] {
    sort_u32(codes, scratch);  // (std::sort was 3 % of office2's preprocess)
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
  for (uint64_t b = first_block; b < std::min(blocks, first_block + blocks_a_frame); ++b) {
    bool started = false;
    trace_block(b, [&](size_t e, uint32_t code) {
      if (started && e != run_emitter) flush();
      started = true;
      run_emitter = e;
      codes.push_back(code);
    });
    flush();
  }
  return raw;
}

// Writes a shot file: the magic, the plan's frame `plan_raw`, the frames of
// `frames`' lines, encoded on the threads (encode(first_block, blocks)),
// and the end magic; under a temporary name until complete. Returns its size.
template <typename Encode>
uint64_t write_shot_file(const fs::path& path, ShotKind kind, const std::string& plan_raw, const FirstShotPlan& frames,
                         int zstd_level, const Encode& encode) {
  AtomicFile file(path);
  std::ostream& out = file.stream();
  out.write(traits(kind).magic, 8);
  write_frame(out, plan_raw, zstd_level);
  const uint64_t blocks_a_frame = frame_blocks(frames);
  const uint64_t frame_total = frame_count(frames, blocks_a_frame);
  Progress progress(fmt::format("{} for the store", traits(kind).name), frames.lines(), "lines", true);
  uint64_t next = 0, written = 0;
  tbb::parallel_pipeline(
      16,
      tbb::make_filter<void, uint64_t>(tbb::filter_mode::serial_in_order,
                                       [&](tbb::flow_control& fc) -> uint64_t {
                                         if (next >= frame_total) {
                                           fc.stop();
                                           return 0;
                                         }
                                         return next++;
                                       }) &
          tbb::make_filter<uint64_t, std::string>(
              tbb::filter_mode::parallel, [&](uint64_t f) { return encode(f * blocks_a_frame, blocks_a_frame); }) &
          tbb::make_filter<std::string, void>(tbb::filter_mode::serial_in_order, [&](const std::string& raw) {
            write_frame(out, raw, zstd_level);
            const uint64_t lines = std::min(blocks_a_frame * kFirstShotBlock, frames.lines() - written);
            written += lines;
            progress.advance(lines);
          }));
  progress.finish();
  out.write(traits(kind).end, 8);
  file.commit();
  return fs::file_size(path);
}

class ShotReader {
 public:
  ShotReader(const fs::path& path, ShotKind kind) : path_(path), kind_(traits(kind)), in_(path, std::ios::binary) {
    if (!in_) fail("cannot be opened");
    size_ = fs::file_size(path);
    char magic[8];
    if (!in_.read(magic, 8) || std::memcmp(magic, kind_.magic, 8) != 0)
      fail(fmt::format("not a {}-shot file (wrong magic)", kind_.which));
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
    if (!in_.read(magic, 8) || std::memcmp(magic, kind_.end, 8) != 0) fail("truncated (no end mark)");
    if (in_.peek() != std::char_traits<char>::eof()) fail("corrupted (bytes after the end mark)");
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(fmt::format("{}: {}; the store's {} is damaged: run mpath-preprocess again, or delete "
                                 "the file and mpath-solve traces the {} itself",
                                 path_.string(), what, kind_.name, kind_.name));
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
  const KindTraits& kind_;
  std::ifstream in_;
  uint64_t size_ = 0;
  std::string compressed_, raw_;
};

// A plan frame's varints, each read against a limit ("plan: corrupted"
// past it or at the frame's end), and the header every shot file's plan
// starts with: the version (returned, one of `versions`), lines.seed, the
// block's lines, the frame's blocks and the mesh's faces.
class PlanFields {
 public:
  PlanFields(ShotReader& reader, uint64_t max_raw) : reader_(reader), raw_(reader.frame(max_raw, "plan")) {}

  uint64_t next(uint64_t limit) {
    uint64_t v;
    if (!get_varint(reinterpret_cast<const unsigned char*>(raw_.data()), raw_.size(), pos_, v) || v > limit)
      reader_.fail("plan: corrupted");
    return v;
  }

  uint64_t header(std::initializer_list<uint64_t> versions, size_t faces, unsigned long long& seed,
                  uint64_t& blocks_a_frame) {
    const uint64_t version = next(UINT64_MAX);
    if (std::find(versions.begin(), versions.end(), version) == versions.end())
      reader_.fail("plan: written by another version of mpath");
    seed = next(UINT64_MAX);
    if (next(UINT64_MAX) != kFirstShotBlock) reader_.fail("plan: written by another version of mpath");
    blocks_a_frame = next(kMaxFrameBlocks);
    if (blocks_a_frame == 0) reader_.fail("plan: corrupted");
    if (next(UINT64_MAX) != faces) reader_.fail("plan: made for a mesh of another number of faces");
    return version;
  }

  void expect_end() const {
    if (pos_ != raw_.size()) reader_.fail("plan: corrupted");
  }

  [[noreturn]] void fail() const { reader_.fail("plan: corrupted"); }

 private:
  ShotReader& reader_;
  const std::string& raw_;
  size_t pos_ = 0;
};

FirstShotPlan decode_plan(ShotReader& reader, size_t faces, unsigned long long& seed, uint64_t* blocks_a_frame = nullptr) {
  // Two varints per face at most, and a few more.
  PlanFields fields(reader, 64 + 30 * (uint64_t{faces} + 1));
  const auto next = [&](uint64_t limit) { return fields.next(limit); };
  uint64_t frame = 0;
  const uint64_t version = fields.header({1, kVersion}, faces, seed, frame);
  if (blocks_a_frame) *blocks_a_frame = frame;
  FirstShotPlan plan;
  const uint64_t emitters = next(faces);
  int previous = -1;
  // Faces in increasing order, each as its step from the one before.
  const auto next_face = [&](int previous) {
    const uint64_t step = next(static_cast<uint64_t>(faces) - static_cast<uint64_t>(previous + 1));
    if (step == 0) fields.fail();
    return previous + static_cast<int>(step);
  };
  for (uint64_t e = 0; e < emitters; ++e) {
    previous = next_face(previous);
    plan.emitters.push_back(previous);
    const uint64_t lines = next(uint64_t{1} << 48);
    if (lines == 0 || plan.first.back() + lines > (uint64_t{1} << 48)) fields.fail();
    plan.first.push_back(plan.first.back() + lines);
  }
  const uint64_t global = next(faces);
  previous = -1;
  for (uint64_t g = 0; g < global; ++g) {
    previous = next_face(previous);
    plan.global_faces.push_back(previous);
  }
  plan.halton = version >= 2 && next(1) == 1;
  fields.expect_end();
  return plan;
}

// Why a run's plan is not the stored one, in words.
std::string plan_difference(ShotKind kind, const FirstShotPlan& run, const FirstShotPlan& stored) {
  if (kind == ShotKind::second)
    return fmt::format("this run's second shot is not the store's ({} lines from {} faces, the store {} from {}: "
                       "materials, emission, lights or second_shot.share changed since mpath-preprocess)",
                       run.lines(), run.emitters.size(), stored.lines(), stored.emitters.size());
  if (run.emitters != stored.emitters || run.global_faces != stored.global_faces)
    return "this run's emitting faces are not the store's (emission or first_shot.mode changed since mpath-preprocess)";
  return fmt::format("this run gives its emitters other line counts ({} lines, the store {}: first_shot.lines or the "
                     "emitters' relative power changed since mpath-preprocess)",
                     run.lines(), stored.lines());
}

// Opens `path` when it holds `plan` drawn with `seed` (the reader then at
// the lines; `stored_halton`: the stored points' sequence; `blocks_a_frame`:
// the file's frames' blocks), else says why not.
std::string open_matching(const fs::path& path, ShotKind kind, const PatchMesh& mesh, const FirstShotPlan& plan,
                          unsigned long long seed, std::optional<ShotReader>& reader, bool& stored_halton,
                          uint64_t& blocks_a_frame) {
  if (!fs::exists(path))
    return kind == ShotKind::first
               ? fmt::format("the store has no {} (made by an older mpath-preprocess)", path.filename().string())
               : fmt::format("the store has no {} (mpath-preprocess planned no second shot, or is older)",
                             path.filename().string());
  reader.emplace(path, kind);
  unsigned long long stored_seed = 0;
  const FirstShotPlan stored = decode_plan(*reader, mesh.face_count(), stored_seed, &blocks_a_frame);
  if (stored_seed != seed) return fmt::format("the store's {} was drawn with lines.seed = {}", traits(kind).name, stored_seed);
  // The store's points, Halton or independent, serve any run: both give
  // an unbiased shot (stores made before first_shot.sequence hold
  // independent ones).
  FirstShotPlan same = stored;
  same.halton = plan.halton;
  if (!(same == plan)) return plan_difference(kind, plan, stored);
  stored_halton = stored.halton;
  return "";
}

// Reads the lines of `plan` and calls receive(e, code, lines) for each run
// of `lines` lines of plan.emitters[e] that met `code`; then the end mark.
template <typename Receive>
void read_lines(ShotReader& reader, const PatchMesh& mesh, const FirstShotPlan& plan, uint64_t blocks_a_frame,
                const Receive& receive) {
  const uint32_t limit = code_limit(mesh.face_count());
  const uint64_t frames = frame_count(plan, blocks_a_frame);
  size_t e = 0;
  for (uint64_t f = 0; f < frames; ++f) {
    const uint64_t lo = f * blocks_a_frame * kFirstShotBlock;
    const uint64_t hi = std::min(plan.lines(), lo + blocks_a_frame * kFirstShotBlock);
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
        receive(e, static_cast<uint32_t>(code), more + 1);
      }
      line = run_end;
    }
    if (pos != raw.size()) reader.fail(fmt::format("lines of frame {}: corrupted", f));
  }
  reader.expect_end();
}

// Reads the lines of `path` into `acc` (reset to `faces` faces, its line
// count set) when the file holds `plan` drawn with `seed`, calling
// receive(e, code, lines, acc) for each run of lines, and returns ""; else
// returns why not and reads nothing. `halton`: the stored points' sequence.
template <typename Receive>
std::string read_matching(const fs::path& path, ShotKind kind, const PatchMesh& mesh, const FirstShotPlan& plan,
                          unsigned long long seed, size_t faces, ShardAccumulator& acc, bool& halton,
                          const Receive& receive) {
  std::optional<ShotReader> reader;
  uint64_t blocks_a_frame = 0;
  if (std::string why = open_matching(path, kind, mesh, plan, seed, reader, halton, blocks_a_frame); !why.empty())
    return why;
  acc.reset(faces);
  read_lines(*reader, mesh, plan, blocks_a_frame,
             [&](size_t e, uint32_t code, uint64_t lines) { receive(e, code, lines, acc); });
  acc.lines = plan.lines();
  return "";
}

// The lights' shot's plan: the seed, and per light its lines (shoot_light's
// count) and lines_hash (where those lines go: a light moved, re-aimed or
// given another distribution sends them elsewhere; its power does not).
struct LightsPlan {
  unsigned long long seed = 0;
  std::vector<uint64_t> lines, hashes;
  bool operator==(const LightsPlan&) const = default;
};
constexpr uint64_t kLightsVersion = 1;
constexpr uint64_t kMaxLights = uint64_t{1} << 16;

LightsPlan lights_plan(const std::vector<PointLight>& lights, const std::vector<uint64_t>& lines,
                       unsigned long long seed) {
  LightsPlan plan;
  plan.seed = seed;
  plan.lines = lines;
  for (const PointLight& l : lights) plan.hashes.push_back(l.lines_hash());
  return plan;
}

// The lights as the emitters of a plan, for its frames: light e's lines
// are lines [first[e], first[e + 1]).
FirstShotPlan lights_frames(const LightsPlan& plan) {
  FirstShotPlan frames;
  for (size_t e = 0; e < plan.lines.size(); ++e) {
    frames.emitters.push_back(static_cast<int>(e));
    frames.first.push_back(frames.first.back() + plan.lines[e]);
  }
  return frames;
}

std::string encode_lights_plan(const LightsPlan& plan, size_t faces) {
  std::string raw = plan_header(kLightsVersion, plan.seed, lights_frames(plan), faces, plan.lines.size());
  for (size_t e = 0; e < plan.lines.size(); ++e) {
    put_varint(raw, plan.lines[e]);
    put_varint(raw, plan.hashes[e]);
  }
  return raw;
}

LightsPlan decode_lights_plan(ShotReader& reader, size_t faces, uint64_t& blocks_a_frame) {
  PlanFields fields(reader, 64 + 20 * kMaxLights);
  LightsPlan plan;
  fields.header({kLightsVersion}, faces, plan.seed, blocks_a_frame);
  const uint64_t lights = fields.next(kMaxLights);
  uint64_t total = 0;
  for (uint64_t e = 0; e < lights; ++e) {
    plan.lines.push_back(fields.next(uint64_t{1} << 48));
    plan.hashes.push_back(fields.next(UINT64_MAX));
    total += plan.lines.back();
    if (total > (uint64_t{1} << 48)) fields.fail();
  }
  fields.expect_end();
  return plan;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

uint64_t write_stored_shot(const fs::path& path, const PatchMesh& mesh, const Tracer& tracer, const FirstShotPlan& plan,
                           unsigned long long seed, int zstd_level, ShotKind kind) {
  const double tfar = 4.0 * mesh.bounds.diagonal() + 1.0;
  const unsigned long long streams = stream_seed(kind, seed);
  return write_shot_file(
      path, kind, encode_plan(plan, seed, mesh.face_count()), plan, zstd_level,
      [&](uint64_t first_block, uint64_t blocks_a_frame) {
        return encode_frame(plan.blocks(), first_block, blocks_a_frame, [&](uint64_t b, const auto& line) {
          trace_first_shot_block(
              mesh, plan, streams, b,
              [&](int from, const Vec3& org, const Vec3& dir) { return tracer.nearest_from(from, org, dir, tfar); },
              line);
        });
      });
}

FirstShotPlan read_stored_plan(const fs::path& path, size_t faces, unsigned long long& seed, ShotKind kind) {
  ShotReader reader(path, kind);
  return decode_plan(reader, faces, seed);
}

std::string replay_stored_shot(const fs::path& path, const PatchMesh& mesh, const FirstShotPlan& plan,
                               unsigned long long seed, RadiosityState& state, FirstShotStats& stats) {
  const auto start = std::chrono::steady_clock::now();
  // Decoded and checked in full before the state changes.
  std::vector<ShardAccumulator> acc(1);
  bool halton = false;
  if (std::string why = read_matching(path, ShotKind::first, mesh, plan, seed, state.faces, acc[0], halton,
                                      [&](size_t e, uint32_t code, uint64_t lines, ShardAccumulator& a) {
                                        receive_emitter_lines(state, plan, e, code, lines, a);
                                      });
      !why.empty())
    return why;
  leave_to_global_lines(plan, state);
  merge_received(acc, state);
  stats.halton = halton;
  stats.lines = plan.lines();
  stats.emitter_faces = plan.emitters.size();
  stats.global_emitter_faces = plan.global_faces.size();
  stats.stored = true;
  stats.seconds = seconds_since(start);
  return "";
}

std::string replay_stored_second_shot(const fs::path& path, const PatchMesh& mesh, const FirstShotPlan& plan,
                                      unsigned long long seed, RadiosityState& state, SecondShotStats& stats) {
  const auto start = std::chrono::steady_clock::now();
  // Decoded and checked in full before the state changes.
  std::vector<ShardAccumulator> acc(1);
  bool halton = false;
  const std::vector<double> per_line = second_shot_line_power(state, plan);
  if (std::string why = read_matching(path, ShotKind::second, mesh, plan, seed, state.faces, acc[0], halton,
                                      [&](size_t e, uint32_t code, uint64_t lines, ShardAccumulator& a) {
                                        receive_second_shot_lines(state, plan, per_line, e, code, lines, a);
                                      });
      !why.empty())
    return why;
  stats = finish_second_shot(plan, acc, state);
  stats.halton = halton;
  stats.stored = true;
  stats.seconds = seconds_since(start);
  return "";
}

uint64_t write_stored_lights(const fs::path& path, const PatchMesh& mesh, const Tracer& tracer,
                             const std::vector<PointLight>& lights, const std::vector<uint64_t>& lines,
                             unsigned long long seed, int zstd_level) {
  const LightsPlan plan = lights_plan(lights, lines, seed);
  const FirstShotPlan frames = lights_frames(plan);
  std::vector<ShiftedHalton> points;
  for (size_t l = 0; l < lights.size(); ++l) points.push_back(light_points(light_seed(seed, l)));
  return write_shot_file(
      path, ShotKind::lights, encode_lights_plan(plan, mesh.face_count()), frames, zstd_level,
      [&](uint64_t first_block, uint64_t blocks_a_frame) {
        return encode_frame(frames.blocks(), first_block, blocks_a_frame, [&](uint64_t b, const auto& line) {
          const uint64_t lo = b * kFirstShotBlock, hi = std::min(frames.lines(), lo + kFirstShotBlock);
          size_t e = std::upper_bound(frames.first.begin(), frames.first.end(), lo) - frames.first.begin() - 1;
          for (uint64_t k = lo; k < hi; ++k) {
            while (k >= frames.first[e + 1]) ++e;
            double u[4];
            points[e].point(k - frames.first[e], u);
            line(e, light_line_outcome(mesh, tracer, lights[e], u));
          }
        });
      });
}

std::string replay_stored_lights(const fs::path& path, const PatchMesh& mesh, const std::vector<PointLight>& lights,
                                 const std::vector<uint64_t>& lines, unsigned long long seed, RadiosityState& state,
                                 LightsShotStats& stats) {
  const auto start = std::chrono::steady_clock::now();
  if (!fs::exists(path))
    return fmt::format("the store has no {} (mpath-preprocess saw no lights, first_shot.sequence was \"random\", or "
                       "it is older)",
                       path.filename().string());
  ShotReader reader(path, ShotKind::lights);
  uint64_t blocks_a_frame = 0;
  const LightsPlan stored = decode_lights_plan(reader, mesh.face_count(), blocks_a_frame);
  if (stored.seed != seed) return fmt::format("the store's lights' shot was drawn with lines.seed = {}", stored.seed);
  const LightsPlan run = lights_plan(lights, lines, seed);
  const FirstShotPlan frames = lights_frames(run);
  if (!(stored == run))
    return fmt::format("this run's lights are not the store's ({} light(s), {} lines; the store {} light(s), {} lines: "
                       "a light added, moved, re-aimed or given another distribution, or first_shot.lines or the "
                       "lights' share of the power changed since mpath-preprocess)",
                       run.lines.size(), frames.lines(), stored.lines.size(), lights_frames(stored).lines());
  // Decoded and checked in full before the state changes.
  std::vector<ShardAccumulator> acc(1);
  acc[0].reset(state.faces);
  read_lines(reader, mesh, frames, blocks_a_frame, [&](size_t e, uint32_t code, uint64_t n) {
    if (code_contact(code)) reader.fail("lines: corrupted (a light's line in contact)");
    receive_light_lines(state, lights[e], run.lines[e], code, n, acc[0]);
  });
  acc[0].lines = frames.lines();
  for (const PointLight& l : lights)
    for (int c = 0; c < state.channels; ++c) state.energy.emitted[c] += l.power();
  merge_received(acc, state);
  stats.lines = frames.lines();
  stats.stored = true;
  stats.seconds = seconds_since(start);
  return "";
}

namespace {

// Keeps the file at `path` when check() finds it holds what this run would
// write (every frame read into a copy of the state; it returns why not),
// else writes it (write() returns its size). `what`: the lines' source, for
// the log.
template <typename Check, typename Write>
StoredShotStats keep_or_write(const fs::path& path, ShotKind kind, uint64_t lines, const std::string& what,
                              const Check& check, const Write& write) {
  const auto start = std::chrono::steady_clock::now();
  StoredShotStats stats;
  stats.lines = lines;
  if (fs::exists(path)) {
    // Kept only when a solve would read it: its plan, and every frame
    // checked (a damaged file is written again, as the solve's error says).
    try {
      if (check().empty()) {
        stats.bytes = fs::file_size(path);
        spdlog::info("{}: the {} of this scene, written earlier, kept", path.string(), traits(kind).name);
        return stats;
      }
    } catch (const InputError& e) {
      spdlog::warn("{}; writing it again", e.what());
    }
  }
  stats.bytes = write();
  stats.written = true;
  stats.seconds = seconds_since(start);
  spdlog::info("{}: the {}, {} local lines from {}, {:.2f} MB ({:.2f} s)", path.string(), traits(kind).name, lines,
               what, stats.bytes / 1e6, stats.seconds);
  return stats;
}

// keep_or_write of a first or second shot's `plan`.
StoredShotStats keep_or_write_shot(const fs::path& path, ShotKind kind, const Options& options, const PatchMesh& mesh,
                                   const TracerOnDemand& tracer, const FirstShotPlan& plan,
                                   const RadiosityState& state) {
  return keep_or_write(
      path, kind, plan.lines(), fmt::format("{} face(s)", plan.emitters.size()),
      [&] {
        RadiosityState scratch = state;
        FirstShotStats first;
        SecondShotStats second;
        return kind == ShotKind::first ? replay_stored_shot(path, mesh, plan, options.lines.seed, scratch, first)
                                       : replay_stored_second_shot(path, mesh, plan, options.lines.seed, scratch, second);
      },
      [&] { return write_stored_shot(path, mesh, tracer.get(), plan, options.lines.seed, options.store.zstd_level, kind); });
}

}  // namespace

StoredShots store_shots(const Options& options, const PreparedScene& prepared, const StoreCrossings* crossings) {
  const PatchMesh& mesh = prepared.mesh;
  const fs::path dir = options.store.dir;
  RadiosityState state = make_state(prepared.scene, mesh);
  const std::vector<PointLight> lights = make_lights(options.scene.lights);
  StoreCrossings counted;
  if (!crossings) {
    const BoxStore store(options, mesh);
    counted = {store.face_crossings(mesh.face_count()), store.root_crossings(mesh.face_count())};
    crossings = &counted;
  }
  const RunFirstShot run = plan_run_first_shot(options, mesh, state, crossings->all, lights);
  TracerOnDemand tracer(mesh);
  StoredShots shots;
  shots.first = keep_or_write_shot(dir / kStoredShotFile, ShotKind::first, options, mesh, tracer, run.plan, state);
  // The lights' shot, where its lines do not depend on the threads (a
  // light's independent points are drawn per shard).
  const fs::path lights_path = dir / kStoredLightsFile;
  const std::vector<uint64_t> light_lines = light_line_counts(lights, run.light_lines);
  const bool store_lights = !lights.empty() && options.first_shot.halton();
  if (store_lights) {
    uint64_t lines = 0;
    for (uint64_t n : light_lines) lines += n;
    shots.lights = keep_or_write(
        lights_path, ShotKind::lights, lines, fmt::format("{} light(s)", lights.size()),
        [&] {
          RadiosityState scratch = state;
          LightsShotStats stats;
          return replay_stored_lights(lights_path, mesh, lights, light_lines, options.lines.seed, scratch, stats);
        },
        [&] {
          return write_stored_lights(lights_path, mesh, tracer.get(), lights, light_lines, options.lines.seed,
                                     options.store.zstd_level);
        });
  } else {
    fs::remove(lights_path);  // a solve traces its lights
  }
  // The state a solve of this store has before its second shot: the stored
  // first shot read back, then the lights (solve.cpp, start_state), read
  // back too where they are stored.
  const auto start = std::chrono::steady_clock::now();
  FirstShotPlan plan;
  if (options.second_shot.share > 0) {
    const auto read_back = [&](const fs::path& path, const std::string& why) {
      if (!why.empty()) throw std::runtime_error(fmt::format("{}: written and then not read back: {}", path.string(), why));
    };
    FirstShotStats read;
    read_back(dir / kStoredShotFile,
              replay_stored_shot(dir / kStoredShotFile, mesh, run.plan, options.lines.seed, state, read));
    if (store_lights) {
      LightsShotStats lights_read;
      read_back(lights_path,
                replay_stored_lights(lights_path, mesh, lights, light_lines, options.lines.seed, state, lights_read));
    } else {
      shoot_lights(options, mesh, tracer.get(), state, lights, run.light_lines);
    }
    plan = plan_run_second_shot(options, state, crossings->root);
  }
  const fs::path path = dir / kStoredSecondShotFile;
  if (plan.emitters.empty()) {
    fs::remove(path);  // a solve plans none either
    return shots;
  }
  shots.second = keep_or_write_shot(path, ShotKind::second, options, mesh, tracer, plan, state);
  shots.second.seconds = seconds_since(start);
  return shots;
}

}  // namespace mpath
