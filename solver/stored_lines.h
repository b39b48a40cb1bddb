// The line store as the solver reads it: the manifest checked against this
// run's scene and config, every file opened and checked, the exact crossing
// counts summed, and chunks streamed in a fixed global order.
#pragma once

#include <memory>
#include <vector>

#include "box_file.h"
#include "classic.h"
#include "config.h"
#include "manifest.h"
#include "radiosity_state.h"

namespace mpath {

class StoredLines {
 public:
  // Throws InputError naming the mismatching key, or the missing, truncated
  // or foreign file.
  StoredLines(const Options& options, const PatchMesh& mesh);

  const linestore::Manifest& manifest() const { return manifest_; }
  // Exact crossings of every face by the stored lines (as the pass uses them).
  const std::vector<double>& crossings() const { return crossings_; }
  uint64_t chunk_count() const { return chunk_file_.size(); }
  uint64_t lines() const { return manifest_.lines_total; }
  uint64_t events() const;
  uint64_t bytes() const;

  // Per-thread readers, opened lazily.
  struct Cursor {
    std::vector<std::unique_ptr<linestore::BoxFileReader>> readers;
  };
  Cursor cursor() const { return Cursor{std::vector<std::unique_ptr<linestore::BoxFileReader>>(files_.size())}; }
  void read(uint64_t chunk, Cursor& cursor, linestore::DecodedChunk& out) const;

 private:
  linestore::Manifest manifest_;
  std::vector<std::filesystem::path> files_;
  std::vector<std::pair<uint32_t, uint32_t>> chunk_file_;  // global chunk -> (file, chunk in file)
  std::vector<double> crossings_;
};

// One pass over every stored line: each face sends exactly its unshot power,
// spread over its exact crossing count; shards are contiguous chunk ranges.
PassStats stored_pass(const PatchMesh& mesh, const StoredLines& store, RadiosityState& state, unsigned pass, int shards);

}  // namespace mpath
