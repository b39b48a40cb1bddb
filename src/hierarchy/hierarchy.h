// The hierarchy of subscenes (docs/algorithm.md; paper 3.1 and 3.2): objects
// grouped bottom-up into boxes by the area quotient; the root bounds the scene.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "box_geometry.h"
#include "hierarchy_options.h"
#include "mesh.h"

namespace mpath {

// The smallest box holding boxes a and b, given each box's depth and parent.
template <typename Depth, typename Parent>
int common_ancestor(int a, int b, const Depth& depth, const Parent& parent) {
  while (a != b) {
    if (depth(a) >= depth(b)) a = parent(a);
    else b = parent(b);
  }
  return a;
}

// The class of a pair of consecutive crossings on a line (line sets): the
// patch of box a against the patch of box b, as the levels from a's box up to
// the smallest box holding both (0: a's own box). b < 0: the other end is off
// the line, the outside, which is the root's class for the root's lines and
// no class of a subscene's (-1: its line leaving the box carries no pair).
template <typename Depth, typename Common>
int pair_class(int a, int b, bool root_line, const Depth& depth, const Common& common) {
  if (b < 0) return root_line ? depth(a) : -1;
  return depth(a) - depth(common(a, b));
}

struct Hierarchy {
  std::vector<SceneBox> boxes;       // 0 is the root; parents before children
  std::vector<int> patch_box;        // patch -> box holding it directly
  std::vector<int> depth_order;      // boxes ordered by depth (root first)
  // hierarchy.transport = "lines": a box's lines see every patch inside it
  // (its `patches` are those of its whole subtree) and no box has walls.
  bool transparent = false;
  int max_depth() const;
  size_t ar_total() const;
  // The smallest box holding boxes a and b.
  int common_box(int a, int b) const;
  // Transparent boxes (line sets): how many classes a patch of box `box` can
  // be in for that box's lines, from its own box's up to `box`'s (the width of
  // the box's per-side class counts; docs/store-format.md); 0 otherwise.
  int class_span(int box) const { return transparent ? max_depth() - boxes[box].depth + 1 : 0; }
};

// A hierarchy's tree as two flat arrays, for the loops that ask per crossing
// for a box's depth and the smallest box holding two (the solver's line-set
// passes, the preprocessor's class counts): SceneBox records are far larger.
struct BoxTree {
  std::vector<int> depth, parent;  // per box
  BoxTree() = default;
  explicit BoxTree(const Hierarchy& h) {
    for (const SceneBox& b : h.boxes) {
      depth.push_back(b.depth);
      parent.push_back(b.parent);
    }
  }
  int common_box(int a, int b) const {
    return a == b ? a : common_ancestor(a, b, [this](int x) { return depth[x]; }, [this](int x) { return parent[x]; });
  }
  // pair_class above, for boxes of this tree.
  int pair_class(int a, int b, bool root_line) const {
    return mpath::pair_class(
        a, b, root_line, [this](int x) { return depth[x]; }, [this](int x, int y) { return common_box(x, y); });
  }
};

// Builds the hierarchy of `mesh` (VP grids from vp_area_ratio or vp_grid); `flat` (or hierarchy.max_depth = 0): the
// root alone. Deterministic for a given mesh and options. Candidate pairs and
// intruding items are found in a spatial grid of the items; `all_pairs`
// compares every pair instead (quadratic: the reference the tests hold the
// grid's result to, which must be the same hierarchy). `emitting` (per
// patch, or empty): below max_depth, the smallest group around an emitter
// that is small beside its box is a box of its own (bright subscenes,
// docs/algorithm.md; the pilot budget asks for them).
Hierarchy build_hierarchy(const PatchMesh& mesh, const HierarchyOptions& options, bool flat, bool all_pairs = false,
                          const std::vector<uint8_t>& emitting = {});

// What grouping decided, per box: enough to assemble the hierarchy again
// from the mesh without grouping (a store records it; docs/store-format.md).
struct BoxLayout {
  int parent = -1;
  int depth = 0;
  double quotient = 0;
  std::vector<int> objects;  // the grouping's objects directly in the box (large objects split into their parts)
};
std::vector<BoxLayout> hierarchy_layout(const Hierarchy& h);
// The hierarchy `layout` describes, as build_hierarchy made it; InputError
// when the layout cannot be this mesh's.
Hierarchy assemble_hierarchy(const PatchMesh& mesh, const HierarchyOptions& options, const std::vector<BoxLayout>& layout);

// Turns the boxes transparent (hierarchy.transport = "lines"): each box's
// patches become those of its subtree, ascending, and its walls lose their
// VPs and ARs.
void make_boxes_transparent(Hierarchy& h);

// The tree as text, one box per line (for --print-hierarchy and logs);
// `lines` per box may be empty.
std::string describe_hierarchy(const Hierarchy& h, const std::vector<uint64_t>& lines);

}  // namespace mpath

