// The line-set transport of the hierarchy (hierarchy.transport = "lines";
// docs/algorithm.md, "Line-set transport"). Every box's lines see every
// patch inside the box. The exchange between two patches f and g belongs to
// the smallest box holding both (their class; the root's for f and the
// outside), and is carried by the lines of that box and of every box above
// it, all of which meet the pair: the densities of the line sets add up, as
// in multiple importance sampling with the balance heuristic. A crossing of
// f in class k sends (1 / D_k) / Z_f of f's unshot power, D_k the summed
// density of the class's carriers and Z_f the sum of 1 / D over the carrying
// crossings of f, so that f's crossings send all of it and every pair has
// the same weight from both its ends (the pass is a reversible chain whose
// balance is Z, an estimate of the face's area from every line that sees it).
// What a face receives is sent on in the same pass, as in Multipath: its next
// carrying crossing of class k takes D_min / D_k of it. No power is held in
// walls or waits between boxes, and nothing is approximated by
// transmittances: in a furnace the answer is exact up to the noise of the
// lines.
#pragma once

#include <cstdint>
#include <vector>

#include "box_store.h"
#include "hierarchical.h"
#include "radiosity_state.h"
#include "tracer.h"

namespace mpath {

// What the line-set passes need of each box, derived once from the store.
// An entry is a face the box sees and one class the box carries there.
struct LineSetBox {
  std::vector<int> owner;         // per local patch: the box holding it
  std::vector<uint32_t> entry;    // per local face: its first entry (its own box's class); entry[faces]: entries
  std::vector<uint32_t> slot;     // per entry: its slot in LineSets (face and class)
  std::vector<double> carried;    // per entry: this box's crossings that carry the entry's class at its face
};

struct LineSets {
  std::vector<LineSetBox> boxes;
  std::vector<int> depth, parent;   // per box
  std::vector<uint32_t> face_slot;  // per mesh face: first slot (its own box's class), then up to the root
  std::vector<double> density;      // per box: its lines' crossings per unit face area
  std::vector<double> weight;       // per slot: 1 / D, D the summed density of the class's carriers
  std::vector<int> uncarried;       // faces no line can carry: shot with local lines
  size_t slots() const { return face_slot.back(); }
  // The smallest box holding boxes a and b.
  int common_box(int a, int b) const {
    while (a != b) {
      if (depth[a] >= depth[b]) a = parent[a];
      else b = parent[b];
    }
    return a;
  }
};

// Reads every line of the store once (in parallel) to count, per box and
// face, the crossings and the pairs the box carries.
LineSets derive_line_sets(const BoxStore& store, const PatchMesh& mesh, int threads);

// One iteration: one pass over the lines of every box, interleaved; then
// the uncarried faces' power shot with local lines. Every line of every box
// when `power_per_line` is 0; otherwise each box takes as many as carry about
// that power each (the power left over the store's lines, at least the box's
// coverage), a crossing's share of the quota scaled to the lines taken, no
// shard sending more than its expected part.
PassStats line_set_iteration(const PatchMesh& mesh, const Tracer& tracer, const BoxStore& store, const LineSets& sets,
                             RadiosityState& state, unsigned pass, int threads, double power_per_line,
                             unsigned long long seed, std::vector<BoxPassStats>* per_box, uint64_t* uncarried_lines);

}  // namespace mpath
