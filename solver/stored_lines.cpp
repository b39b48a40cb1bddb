#include "stored_lines.h"

#include <tbb/parallel_for.h>

#include <chrono>

#include "error.h"
#include "progress.h"
#include "store_identity.h"
#include "transport.h"

namespace mpath {

namespace fs = std::filesystem;

StoredLines::StoredLines(const Options& options, const PatchMesh& mesh) {
  const fs::path dir = options.store.dir;
  const fs::path manifest_path = dir / "manifest.json";
  manifest_ = linestore::read_manifest(manifest_path);
  const std::string mismatch = linestore::identity_mismatch(store_identity(options, mesh), manifest_.identity);
  if (!mismatch.empty())
    throw InputError(fmt::format("{}: the store does not match this scene and config: {}; run mpath-preprocess again",
                                 manifest_path.string(), mismatch));
  crossings_.assign(mesh.face_count(), 0);
  uint64_t next_line = 0;
  auto files = manifest_.files;
  std::sort(files.begin(), files.end(), [](const auto& a, const auto& b) { return a.first_line < b.first_line; });
  for (const linestore::StoreFile& f : files) {
    const fs::path path = dir / f.name;
    if (!fs::exists(path)) throw InputError(fmt::format("{}: missing (listed in {})", path.string(), manifest_path.string()));
    if (fs::file_size(path) != f.bytes)
      throw InputError(fmt::format("{}: {} bytes, the manifest says {} (truncated or from another run)", path.string(),
                                   fs::file_size(path), f.bytes));
    if (f.first_line != next_line)
      throw InputError(fmt::format("{}: starts at line {}, expected {} (a shard is missing)", path.string(), f.first_line, next_line));
    const linestore::BoxFileReader reader(path);
    if (reader.lines() != f.lines || reader.face_crossings().size() != crossings_.size())
      throw InputError(fmt::format("{}: does not match the manifest (lines or faces differ)", path.string()));
    for (size_t i = 0; i < crossings_.size(); ++i) crossings_[i] += reader.face_crossings()[i];
    for (uint32_t c = 0; c < reader.chunks().size(); ++c)
      chunk_file_.push_back({static_cast<uint32_t>(files_.size()), c});
    files_.push_back(path);
    next_line += f.lines;
  }
  if (next_line != manifest_.lines_total)
    throw InputError(fmt::format("{}: the files hold {} lines of {} (a shard is missing)", manifest_path.string(),
                                 next_line, manifest_.lines_total));
}

uint64_t StoredLines::events() const {
  uint64_t n = 0;
  for (const auto& f : manifest_.files) n += f.events;
  return n;
}

uint64_t StoredLines::bytes() const {
  uint64_t n = 0;
  for (const auto& f : manifest_.files) n += f.bytes;
  return n;
}

void StoredLines::read(uint64_t chunk, Cursor& cursor, linestore::DecodedChunk& out) const {
  const auto [file, local] = chunk_file_[chunk];
  auto& reader = cursor.readers[file];
  if (!reader) reader = std::make_unique<linestore::BoxFileReader>(files_[file]);
  reader->read_chunk(local, out);
}

PassStats stored_pass(const PatchMesh& mesh, const StoredLines& store, RadiosityState& state, unsigned pass, int shards) {
  const auto start = std::chrono::steady_clock::now();
  const PassInputs in = PassInputs::start(state, mesh, store.crossings());

  std::vector<ShardAccumulator> acc(shards);
  const uint64_t chunks = store.chunk_count();
  Progress progress(fmt::format("iteration {}", pass), store.lines(), "lines", true);
  tbb::parallel_for(0, shards, [&](int s) {
    ShardAccumulator& a = acc[s];
    a.reset(state.faces);
    a.allowance = 1.0;  // exact counts: a face's crossings together send exactly its quota
    StoredLines::Cursor cursor = store.cursor();
    linestore::DecodedChunk chunk;
    std::vector<LineHit> hits;
    for (uint64_t c = chunks * s / shards; c < chunks * (s + 1) / shards; ++c) {
      store.read(c, cursor, chunk);
      for (size_t l = 0; l < chunk.lines(); ++l) {
        hits.clear();
        for (uint32_t k = chunk.first[l]; k < chunk.first[l + 1]; ++k)
          hits.push_back({0.0, static_cast<int>(chunk.events[k].id), chunk.events[k].along});
        transport_line(in, hits, a);
      }
      progress.advance(chunk.lines());
    }
  });
  progress.finish();
  return finish_pass(in, acc, state, pass, start);
}

}  // namespace mpath
