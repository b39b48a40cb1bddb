// The line-set transport of the hierarchy (hierarchy.transport = "lines";
// docs/algorithm.md, "Line-set transport"). Every box's lines see every
// patch inside the box. The exchange between two patches f and g belongs to
// the smallest box holding both (their class; the root's for f and the
// outside), and is carried by the lines of that box and of every box above
// it, all of which meet the pair: a line's crossing carries 1/M of the
// face's power of that class, M the crossings of the face in that class by
// all those lines (the densities of the line sets add up, as in multiple
// importance sampling with the balance heuristic). Each face's power is split
// among its classes in proportion to the share of its form factor in each,
// estimated from each box's own lines. No power is held in walls and nothing
// is approximated by transmittances: in a furnace the answer is exact up to
// the noise of the lines.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "box_store.h"
#include "hierarchical.h"
#include "radiosity_state.h"
#include "tracer.h"

namespace mpath {

// What the line-set passes need of each box, derived once from the store.
struct LineSetBox {
  std::vector<int> owner;         // per local patch: the box holding it
  std::vector<uint32_t> entry;    // per local face: its first entry (its own box's class); entry[faces]: entries
  std::vector<uint32_t> slot;     // per entry: its slot in LineSets (face and class)
  std::vector<double> carried;    // per entry: this box's crossings that carry the entry's class at its face
  // The distinct values of `carried`, increasing, and per entry the index of
  // its value there: a partial pass's plan weighs each value once, not once
  // per entry (line_sets.cpp, expected_sent).
  std::vector<double> distinct;
  std::vector<uint32_t> rank;
};

// The passes' shard accumulators, kept from pass to pass (line_sets.cpp).
struct SetShardPool;

struct LineSets {
  std::vector<LineSetBox> boxes;
  BoxTree tree;                     // the hierarchy's depths and parents, flat
  std::vector<uint32_t> face_slot;  // per mesh face: first slot (its own box's class), then up to the root
  std::vector<double> alpha;        // per slot: the share of the face's power in that class
  std::vector<int> uncarried;       // faces no line can carry: shot with local lines
  size_t slots() const { return face_slot.back(); }
  // Scratch of the passes, not data of the store: the shards' accumulators,
  // zero between passes, so that a pass neither allocates nor clears them.
  std::shared_ptr<SetShardPool> pool;
};

// The classes, slots and shares, from the crossing counts of the store's
// files (the preprocessor counted, per box and patch side, the crossings and
// the pairs the box carries while it traced; no line is read here).
LineSets derive_line_sets(const BoxStore& store, const PatchMesh& mesh);

// Frees the passes' pooled shard accumulators (the next pass allocates them
// again), so that what a solve does after its passes (the solution, images,
// grids) reuses their memory instead of touching fresh pages.
void release_pass_memory(const LineSets& sets);

// One iteration: every box's pass, deepest first, then the root (a class's
// first carrier is its own box); then the uncarried faces' power shot with
// local lines. Every line of every box when `power_per_line` is 0;
// otherwise each box takes as many as carry about that power each (the power
// left over the store's lines; the root at least its coverage, a subscene
// none below the root's coverage, its classes then carried by the root's
// lines alone), a crossing's
// share of its class scaled so that the carriers' expected shares add up to
// one, none sending more than its expected part.
PassStats line_set_iteration(const PatchMesh& mesh, const TracerOnDemand& tracer, const BoxStore& store,
                             const LineSets& sets, RadiosityState& state, unsigned pass, int shards_wanted,
                             double power_per_line, unsigned long long seed, std::vector<BoxPassStats>* per_box,
                             uint64_t* uncarried_lines);

}  // namespace mpath
