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

struct Hierarchy {
  std::vector<SceneBox> boxes;       // 0 is the root; parents before children
  std::vector<int> patch_box;        // patch -> box holding it directly
  std::vector<int> depth_order;      // boxes ordered by depth (root first)
  // hierarchy.transport = "lines": a box's lines see every patch inside it
  // (its `patches` are those of its whole subtree) and no box has walls.
  bool transparent = false;
  int max_depth() const;
  size_t ar_total() const;
};

// Builds the hierarchy of `mesh` (VP grids from vp_area_ratio or vp_grid); `flat` (or hierarchy.max_depth = 0): the
// root alone. Deterministic for a given mesh and options.
Hierarchy build_hierarchy(const PatchMesh& mesh, const HierarchyOptions& options, bool flat);

// Turns the boxes transparent (hierarchy.transport = "lines"): each box's
// patches become those of its subtree, ascending, and its walls lose their
// VPs and ARs.
void make_boxes_transparent(Hierarchy& h);

// The tree as text, one box per line (for --print-hierarchy and logs);
// `lines` per box may be empty.
std::string describe_hierarchy(const Hierarchy& h, const std::vector<uint64_t>& lines);

}  // namespace mpath

