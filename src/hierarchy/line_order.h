// Order of a line's crossings at equal distance (surfaces in contact), and
// the faces a crossing turns towards either end of the line.
#pragma once

#include <vector>

#include "line_hit.h"
#include "mesh.h"

namespace mpath {

// Faces of a crossing: the one facing along the line and the one facing back
// (-1 for a black back side).
struct Facing {
  int forward;
  int backward;
};

inline Facing facing(const PatchMesh& mesh, const LineHit& h) {
  const auto& f = mesh.patch_faces[h.patch];
  return h.along ? Facing{f[0], f[1]} : Facing{f[1], f[0]};
}

// Reorders crossings at equal distance (within epsilon) so that, where some
// order allows, a live face is never paired with a black back side (objects
// resting on surfaces, back-to-back walls, objects in corners).
void order_ties(const PatchMesh& mesh, double epsilon, std::vector<LineHit>& hits);

}  // namespace mpath
