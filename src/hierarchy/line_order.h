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

// The crossing that power leaving crossing `i` in direction `dir` (+1 along
// the line, -1 against it) reaches: the next one whose face turned towards
// it, `towards(j, -dir)`, is not an invisible back; -1 or `n` when the power
// leaves the line. Preprocessor and solver pair crossings by this one rule.
template <typename Towards>
inline int next_seen(int i, int dir, int n, const Towards& towards) {
  int j = i + dir;
  while (j >= 0 && j < n && towards(j, -dir) == kInvisibleSide) j += dir;
  return j;
}

// Reorders crossings at equal distance (within epsilon) so that, where some
// order allows, a live face is never paired with a black back side (objects
// resting on surfaces, back-to-back walls, objects in corners). Which faces
// are live comes from `live_faces` where given (Tracer::live_faces: entry
// h.traced, or h.patch over every patch), else from the mesh
// (PatchMesh::live_face_bits).
void order_ties(const PatchMesh& mesh, double epsilon, std::vector<LineHit>& hits,
                const uint8_t* live_faces = nullptr);

}  // namespace mpath
