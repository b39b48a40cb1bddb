// The hierarchy of subscenes (design.md section 4, paper 3.1 and 3.2): objects
// grouped bottom-up into boxes by the area quotient, each box's faces split
// into virtual patches (VP) and the hemisphere over each VP into 24 angular
// regions (AR) of equal projected solid angle.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "config.h"
#include "mesh.h"

namespace mpath {

inline constexpr int kSectors = 8;
inline constexpr int kBands = 3;
inline constexpr int kArsPerVp = kSectors * kBands;

struct SceneBox {
  int parent = -1;  // -1: the root, the scene's box
  int depth = 0;
  Bounds bounds;    // the exact bounding box of its objects
  std::vector<int> children;
  std::vector<int> objects;     // objects directly in this box (not in a child)
  std::vector<uint32_t> patches;  // patches directly in this box, ascending
  int objects_total = 0;        // objects in this box and its descendants
  size_t polygons_total = 0;
  double quotient = 0;          // grouping quotient that formed it (root: 0)
  std::array<int, 6> grid{};    // VPs per side of each face (face = 2 axis + high)
  std::array<uint32_t, 7> ar_offset{};  // first AR of each face; ar_offset[6]: ARs in all

  uint32_t ar_count() const { return ar_offset[6]; }
  // The AR crossed at `point` (on face `face`) by the line of direction `dir`,
  // the same whichever way the line runs.
  uint32_t ar_at(int face, const Vec3& point, const Vec3& dir) const;
  // Decomposes an AR into face, VP column and row, sector and band.
  struct ArPlace {
    int face, column, row, sector, band;
  };
  ArPlace place(uint32_t ar) const;
  uint32_t ar_of(const ArPlace& p) const;
};

struct Hierarchy {
  std::vector<SceneBox> boxes;       // 0 is the root; parents before children
  std::vector<int> patch_box;        // patch -> box holding it directly
  std::vector<int> depth_order;      // boxes ordered by depth (root first)
  int max_depth() const;
  size_t ar_total() const;
};

// Builds the hierarchy of `mesh` (VP grids from vp_area_ratio or vp_grid); `flat` (or hierarchy.max_depth = 0): the
// root alone. Deterministic for a given mesh and options.
Hierarchy build_hierarchy(const PatchMesh& mesh, const Options::Hierarchy& options, bool flat);

// Where a line org + t dir meets a box: parameters of entry and exit and the
// faces crossed there; false if it misses the box (or only grazes it).
struct BoxCrossing {
  double t_in, t_out;
  int face_in, face_out;
};
bool cross_box(const Bounds& box, const Vec3& org, const Vec3& dir, BoxCrossing& out);

// Does the triangle (a, b, c) meet the open box `box` (its interior)?
bool triangle_meets_box(const Vec3& a, const Vec3& b, const Vec3& c, const Bounds& box);

// The tree as text, one box per line (for --print-hierarchy and logs);
// `lines` per box may be empty.
std::string describe_hierarchy(const Hierarchy& h, const std::vector<uint64_t>& lines);

}  // namespace mpath

namespace mpath {

// Lines traced for each box (paper 3.3.1): root_fraction of lines.total in
// the root, the rest shared by the subscenes in proportion to their grouping
// quotient (or object count), each box at least 4 lines per AR of its walls
// so that its transmittances are sampled. With no subscenes the root gets all.
std::vector<uint64_t> box_line_budget(const Hierarchy& h, const Options::Lines& lines);

// Coarsens the VP grids (vp_area_ratio) of boxes whose lines would cross
// each AR fewer than 8 times on average (a fine mesh and few lines), so that
// the floor of 4 lines per AR does not swell the store past lines.total.
void fit_vp_grids(Hierarchy& h, const Options::Lines& lines);

// The hierarchy a store is made with: subscenes for solver.method =
// "hierarchical", the root box alone otherwise (design.md section 10), with
// its VP grids fitted to lines.total unless hierarchy.vp_grid is set.
Hierarchy store_hierarchy(const Options& options, const PatchMesh& mesh);

}  // namespace mpath
