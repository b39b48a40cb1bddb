// Tessellation of curved primitives (MGF's sph, cyl, cone, ring, torus, prism)
// into planar polygons with outward normals (inward when `inward`).
#pragma once

#include <vector>

#include "vec3.h"

namespace mpath {

using PolygonList = std::vector<std::vector<Vec3>>;

// Open cone frustum from c1 (radius r1) to c2 (radius r2); a cylinder when r1 == r2.
PolygonList tessellate_cone(Vec3 c1, double r1, Vec3 c2, double r2, int segments, bool inward);
PolygonList tessellate_sphere(Vec3 center, double radius, int segments, bool inward);
// Annulus (disc when r_inner == 0) in the plane through `center` facing `normal`.
PolygonList tessellate_ring(Vec3 center, Vec3 normal, double r_inner, double r_outer, int segments);
// Torus around `normal` through `center`, between r_inner and r_outer from the axis.
PolygonList tessellate_torus(Vec3 center, Vec3 normal, double r_inner, double r_outer, int segments, bool inward);
// Closed right prism: `base` (its own orientation kept) extruded by `length`
// against its normal; negative length extrudes along it and faces point inward.
PolygonList tessellate_prism(const std::vector<Vec3>& base, double length);

}  // namespace mpath
