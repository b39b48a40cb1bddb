// The patch mesh: polygons split into planar patches (triangles or convex
// quads) of at most max_patch_area, and the patch faces that carry radiosity.
// Face i < patch count is the front of patch i; two-sided patches add a back
// face after those. The back of a one-sided patch is black and has no face.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "scene.h"

namespace mpath {

struct Patch {
  std::array<uint32_t, 4> v{};  // corners; v[3] == v[2] for a triangle
  Vec3 normal;                  // unit front normal
  double area = 0;
  int polygon = 0;
  int object = 0;
  int material = 0;

  bool is_triangle() const { return v[3] == v[2]; }
};

// The back side of a one-sided patch, where patch_faces holds no face: black
// (it absorbs what reaches it) or invisible (power passes it, unchanged, to
// the next surface along its way; docs/scene-formats.md, "Sides").
inline constexpr int kBlackSide = -1;
inline constexpr int kInvisibleSide = -2;

struct PatchMesh {
  std::vector<Vec3> vertices;
  std::vector<Patch> patches;
  // Per patch: front and back face, kBlackSide for a black back and
  // kInvisibleSide for an invisible one (kept apart from Patch so the hot
  // transport loop reads 8 bytes a crossing).
  std::vector<std::array<int, 2>> patch_faces;
  std::vector<int> face_patch;     // face -> patch
  std::vector<uint8_t> face_side;  // face -> 0 front, 1 back
  // Per patch: its polygon's contact plane (contact.h) where the patch may
  // touch another surface (its box overlaps one its polygon touches), else
  // -1; empty when no patch touches anything.
  std::vector<int> contact_plane;
  double max_patch_area = 0;
  size_t dropped_polygons = 0;     // degenerate polygons left out
  Bounds bounds;

  size_t face_count() const { return face_patch.size(); }
  // Unit normal of a face (the back face points against the patch normal).
  Vec3 face_normal(int face) const {
    const Vec3& n = patches[face_patch[face]].normal;
    return face_side[face] ? -n : n;
  }
  double face_area(int face) const { return patches[face_patch[face]].area; }
  // The side of `patch` a line along `dir` meets (0 front, 1 back), and its
  // face there (negative: the black or invisible back of a one-sided patch).
  int side_met(int patch, const Vec3& dir) const { return dot(patches[patch].normal, dir) < 0 ? 0 : 1; }
  int face_met(int patch, const Vec3& dir) const { return patch_faces[patch][side_met(patch, dir)]; }
  // Which faces of `patch` are live (neither a black nor an invisible side):
  // bit s for face s.
  uint8_t live_face_bits(int patch) const {
    const auto& f = patch_faces[patch];
    return static_cast<uint8_t>((f[0] >= 0 ? 1 : 0) | (f[1] >= 0 ? 2 : 0));
  }
  // Whether crossings of patches `a` and `b` that are neighbours on a line
  // touch: both lie on one contact plane, so the faces they turn towards
  // each other are pressed together and exchange nothing.
  bool touching(int a, int b) const { return may_touch(a) && contact_plane[a] == contact_plane[b]; }
  // Whether `patch` has a contact plane (may touch its neighbour on a line).
  bool may_touch(int patch) const { return !contact_plane.empty() && contact_plane[patch] >= 0; }
};

// The most patches a mesh may have (about 10 GB of memory in all).
inline constexpr double kMaxPatches = 50e6;

// Automatic patch size: the scene box's surface area / 2000.
double automatic_patch_area(const Scene& scene);

PatchMesh build_mesh(const Scene& scene, double max_patch_area);

// Splits a simple polygon into triangles (ear clipping in its plane); returns
// index triples into `polygon`. Falls back to a fan if the polygon is not simple.
std::vector<std::array<uint32_t, 3>> triangulate(const std::vector<Vec3>& polygon);

}  // namespace mpath
