// The locally global lines of one box, chunk by chunk (docs/method.md, 5):
// which lines a chunk holds is fixed by the config alone (box, line index,
// per-chunk random stream), so a store traced in shards, on any number of
// threads, holds the same lines. A line is intersected with the box's own
// patches (Embree), its child boxes (entry and exit ARs; their interior is
// not visited) and its own walls (entry and exit ARs).
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "box_file.h"
#include "config.h"
#include "hierarchy.h"
#include "line_record.h"
#include "sampling.h"
#include "tracer.h"

namespace mpath {

// What tracing a box's lines counts besides the records.
struct BoxTally {
  linestore::BoxCounts counts;
  std::unordered_map<uint64_t, uint32_t> first_met;  // (wall AR, patch) -> lines entering there meeting it first
  void merge_into(BoxTally& total) const;
};

// Line indices in order of `key`, ties in index order (the order sorting
// (key, index) pairs gives).
void order_by_key(const std::vector<uint64_t>& key, std::vector<uint32_t>& order);

// A chunk's lines as traced, and their stored order: line k of the file is
// line order[k] of `lines`.
struct TracedChunk {
  linestore::DecodedChunk lines;
  std::vector<uint32_t> order;
  // The lines in stored order (what the file holds once decoded).
  linestore::DecodedChunk stored() const;
};

class ChunkTracer {
 public:
  ChunkTracer(const Options& options, const PatchMesh& mesh, const Hierarchy& hierarchy, int box, uint64_t lines);
  uint64_t chunk_count() const { return chunks_; }
  uint64_t first_line(uint64_t chunk) const { return chunk * chunk_lines_; }
  uint64_t lines_in(uint64_t chunk) const;
  // An empty tally of the right sizes for this box.
  BoxTally empty_tally() const;
  // Completes a tally once all its lines are counted: the class counts that
  // count_classes leaves to the crossing counts (below).
  void finish_tally(BoxTally& tally) const;
  // The lines of chunk `chunk`; adds what they count to `tally`.
  void trace(uint64_t chunk, TracedChunk& out, BoxTally& tally) const;

 private:
  // Transparent boxes: adds the pairs of consecutive crossings of a line's
  // `n` events to the class counts. In the root's lines a crossing of a
  // patch the root holds directly pairs in class 0 whatever it meets next
  // (the smallest box holding both is the root; off the line is the
  // root's outside), on both its sides: those counts equal the patch's
  // crossing counts, and finish_tally writes them from there instead.
  void count_classes(const linestore::Event* events, int n, linestore::BoxCounts& counts) const;
  // The face (or kBlackSide, kInvisibleSide) event `e` turns towards
  // direction d; a child box is never invisible.
  int towards(const linestore::Event& e, int d) const {
    if (e.kind != linestore::Event::patch) return 0;
    return mesh_.patch_faces[box_.patches[e.id]][(d > 0) == e.along ? 0 : 1];
  }

  const PatchMesh& mesh_;
  const Hierarchy& hierarchy_;
  const SceneBox& box_;
  int box_index_;
  Tracer tracer_;
  BoxLineSampler sampler_;
  LineSequence sequence_;
  unsigned long long seed_;
  uint64_t total_, chunk_lines_, chunks_;
  // Line k of the box (chunk after chunk) is point order_(k) of the
  // sequence: a chunk holds lines from the whole sequence, not neighbours in
  // it (IndexPermutation; the store identity's "lines.order").
  IndexPermutation order_;
  std::vector<uint32_t> child_offset_;  // first AR of each child in the child-crossing counts
  int class_span_ = 0;                  // transparent boxes: classes counted per patch side
  // Transparent boxes, per patch of the box (local id): the box holding it
  // and which of its sides are invisible backs (bit s: side s), so that the
  // class counts read one small table instead of the mesh's face records.
  struct Owner {
    int box;
    uint8_t invisible;
  };
  std::vector<Owner> owner_;
  BoxTree tree_;  // transparent boxes: the hierarchy's depths and parents, flat
};

}  // namespace mpath
