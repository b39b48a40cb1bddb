// A subscene box and its walls (docs/algorithm.md, "Virtual walls"): each face
// split into 2^k x 2^k virtual patches (VP) and the hemisphere over each VP
// into 24 angular regions (AR) of equal projected solid angle; where lines
// cross boxes.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

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
  // ar_offset from the VP grids.
  void set_ar_offsets();
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

// Where a line org + t dir meets a box: parameters of entry and exit and the
// faces crossed there; false if it misses the box (or only grazes it).
struct BoxCrossing {
  double t_in, t_out;
  int face_in, face_out;
};
bool cross_box(const Bounds& box, const Vec3& org, const Vec3& dir, BoxCrossing& out);

// Does the triangle (a, b, c) meet the open box `box` (its interior)?
bool triangle_meets_box(const Vec3& a, const Vec3& b, const Vec3& c, const Bounds& box);

// Scene box enlarged so that no patch lies on its walls and flat scenes get volume.
Bounds line_box(const Bounds& scene_bounds);

}  // namespace mpath
