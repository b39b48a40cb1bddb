// Polygons that overlap another coplanar polygon facing the same way (a
// panel laid twice, a decal modelled on top of a wall without an offset): the
// tracer keeps one crossing where coplanar surfaces facing the same way meet
// a line at one distance, so which of the two a line sees there is chance,
// and the methods light them differently. Found at load time so that every
// method warns of them.
#pragma once

#include <cstddef>
#include <string>

#include "scene.h"

namespace mpath {

struct CoplanarOverlaps {
  size_t polygons = 0;  // polygons overlapping at least one other
  int first = -1, second = -1;  // the first pair found (polygon indices), -1: none
};

// Polygons whose planes agree within 1e-7 of the scene's size and whose
// interiors share area (an edge of one crossing an edge of the other, or a
// vertex or edge midpoint of one strictly inside the other). Polygons with
// the same vertex set are left out (load_scene warns of them already).
// Candidate pairs come from a sweep over bounding boxes per plane; at most
// `budget` box tests and edge pairs are compared in all (then the search
// stops with what it found).
CoplanarOverlaps find_coplanar_overlaps(const Scene& scene, size_t budget = 200'000'000);

}  // namespace mpath
