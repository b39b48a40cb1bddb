// What a line store depends on: the scene file, the mesh made from it, and the
// config values that decide the lines. mpath-preprocess records it in the
// manifest; mpath-solve recomputes it and refuses a store that differs.
#pragma once

#include <map>
#include <string>

#include "config.h"
#include "hierarchy.h"
#include "mesh.h"

namespace mpath {

std::map<std::string, std::string> store_identity(const Options& options, const PatchMesh& mesh);

// Hash of the mesh's geometry and faces (catches changes in included files too),
// under kMeshHashKey in store_identity.
std::string mesh_hash(const PatchMesh& mesh);
inline constexpr const char* kMeshHashKey = "mesh.hash";
// lines.box_budget in the identity of a store made with the default pilot
// (lines.pilot = 0: its lines follow lines.total).
inline constexpr const char* kDefaultPilot = "pilot of a twentieth of lines.total (at least 50000 lines, at most 200000)";

// The hierarchy a store is made with: subscenes for solver.method =
// "hierarchical", the root box alone otherwise (docs/user-guide.md), with
// its VP grids fitted to lines.total unless hierarchy.vp_grid is set. With
// `layout` (a store's record of its boxes) the boxes are assembled from it
// instead of grouping again (InputError when it cannot be this mesh's).
// With lines.box_budget = "pilot" and the line sets, the grouping is given
// `scene`'s emitters and makes bright subscenes (docs/algorithm.md).
Hierarchy store_hierarchy(const Options& options, const PatchMesh& mesh, const std::vector<BoxLayout>* layout = nullptr,
                          const Scene* scene = nullptr);

// The per-patch emitter flags store_hierarchy gives the grouping: empty
// unless lines.box_budget = "pilot" and the line sets (bright subscenes).
std::vector<uint8_t> grouping_emitters(const Options& options, const PatchMesh& mesh, const Scene& scene);

}  // namespace mpath
