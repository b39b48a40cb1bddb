// The global lines of a store, chunk by chunk: which lines a chunk holds is
// fixed by the config alone (line index, per-chunk random stream), so a store
// traced in shards, on any number of threads, holds the same lines.
#pragma once

#include <vector>

#include "config.h"
#include "line_record.h"
#include "sampling.h"
#include "tracer.h"

namespace mpath {

class ChunkTracer {
 public:
  ChunkTracer(const Options& options, const PatchMesh& mesh, const Tracer& tracer);
  uint64_t chunk_count() const { return chunks_; }
  uint64_t first_line(uint64_t chunk) const { return chunk * chunk_lines_; }
  uint64_t lines_in(uint64_t chunk) const;
  // The records of chunk `chunk`; adds each face's crossings to `crossings`.
  void trace(uint64_t chunk, std::vector<linestore::LineRecord>& out, std::vector<uint32_t>& crossings) const;

 private:
  const PatchMesh& mesh_;
  const Tracer& tracer_;
  BoxLineSampler sampler_;
  LineSequence sequence_;
  unsigned long long seed_;
  uint64_t total_, chunk_lines_, chunks_;
};

}  // namespace mpath
