// Surfaces pressed against each other (a frame on a wall, a book on a shelf,
// a block on the floor): two coplanar polygons facing each other whose
// interiors share area. No light reaches where they touch, so there the two
// see only each other. A patch straddling the edge of the contact would mix
// the lit and the covered part into one radiosity and light the covered
// side of the other surface with it; so each polygon of such a pair is split
// into its part in contact and the rest, at load time, whatever the mesh
// size (docs/scene-formats.md, "Surfaces in contact").
#pragma once

#include <cstddef>
#include <vector>

#include "scene.h"

namespace mpath {

struct ContactSplit {
  size_t pairs = 0;      // polygon pairs in contact
  size_t split = 0;      // polygons split
  size_t pieces = 0;     // the polygons they became
  size_t skipped = 0;    // facing pairs whose boxes overlap, left whole: a polygon is not convex
};

// Splits every polygon of `scene` that is in contact with another: planes
// within 1e-7 of the scene's size, normals opposite within 1e-5, interiors
// sharing area: more than `min_area` of it, or more than `min_share` of
// the surface of the smaller of the two polygons' objects. Convex polygons only (facing pairs with a concave one whose
// boxes overlap are counted in `skipped`). Pieces keep the polygon's material, object and facing; the
// order of polygons is kept (a split polygon's pieces take its place).
ContactSplit split_contacts(Scene& scene, double min_area = 0, double min_share = 0);

// Where surfaces touch, without splitting anything: two crossings of one
// line on one plane are at one point, so where they are neighbours on the
// line the faces they turn towards each other are pressed together and
// exchange nothing (docs/scene-formats.md, "Surfaces in contact").
struct ContactPlanes {
  // Per polygon: an index shared by the polygons it touches (facing the
  // other way on its plane, sharing area; with a concave polygon, boxes
  // overlapping), or -1 for a polygon that touches nothing.
  std::vector<int> plane;
  // Per polygon: the bounding boxes of the polygons it touches.
  std::vector<std::vector<Bounds>> partner_bounds;
};
ContactPlanes contact_planes(const Scene& scene);

// The share of the smaller object's surface above which mpath splits a
// contact whatever its area (mesh.split_contacts).
inline constexpr double kContactMinShare = 0.2;

}  // namespace mpath
