#include "store_identity.h"

#include "hash.h"
#include "line_budget.h"

namespace mpath {

// The geometry the store is made of: vertices, patches with their polygons
// and objects (the hierarchy groups objects), faces. Not the materials'
// reflectances and emission, which no stored line depends on.
std::string mesh_hash(const PatchMesh& mesh) {
  Fnv1a h;
  for (const Vec3& v : mesh.vertices) h.add(&v, sizeof v);
  for (const Patch& p : mesh.patches) {
    h.add(p.v.data(), sizeof p.v);
    h.add(&p.polygon, sizeof p.polygon);
    h.add(&p.object, sizeof p.object);
  }
  for (const auto& f : mesh.patch_faces) h.add(f.data(), sizeof f);
  return hex64(h.value());
}

std::map<std::string, std::string> store_identity(const Options& o, const PatchMesh& mesh) {
  std::string two_sided;
  for (const auto& name : o.scene.two_sided) two_sided += (two_sided.empty() ? "" : ",") + name;
  return {
      {kMeshHashKey, mesh_hash(mesh)},
      {"mesh.faces", std::to_string(mesh.face_count())},
      {"mesh.max_patch_area", fmt::format("{}", o.mesh.max_patch_area)},
      {"mesh.curve_segments", std::to_string(o.mesh.curve_segments)},
      {"mesh.split_contacts", o.mesh.split_contacts ? "true" : "false"},
      {"mesh.contact_min_area", fmt::format("{}", o.mesh.contact_min_area)},
      {"scene.two_sided", two_sided},
      {"scene.mgf_default_sides", std::to_string(o.scene.mgf_default_sides)},
      {"lines.total", std::to_string(o.lines.total)},
      {"lines.root_fraction", fmt::format("{}", o.lines.root_fraction)},
      // The pilot as set (its lines follow from it and lines.total, which is
      // checked on its own: a run with other lines.total is named by that).
      {"lines.box_budget", o.lines.box_budget != "pilot" ? o.lines.box_budget
                           : o.lines.pilot > 0         ? fmt::format("pilot of {} lines", o.lines.pilot)
                                                       : std::string(kDefaultPilot)},
      {"lines.min_density", fmt::format("{}", o.lines.min_density)},
      {"hierarchy.subscenes", o.solver.method == SolverMethod::hierarchical ? "yes" : "no (solver.method = multipath)"},
      {"hierarchy.group_threshold", fmt::format("{}", o.hierarchy.group_threshold)},
      {"hierarchy.vp_area_ratio", fmt::format("{}", o.hierarchy.vp_area_ratio)},
      {"hierarchy.vp_grid", std::to_string(o.hierarchy.vp_grid)},
      {"hierarchy.max_depth", std::to_string(o.hierarchy.max_depth)},
      {"hierarchy.max_share", fmt::format("{}", o.hierarchy.max_share)},
      {"hierarchy.transport", o.solver.method == SolverMethod::hierarchical ? o.hierarchy.transport : "none"},
      {"lines.seed", std::to_string(o.lines.seed)},
      {"lines.sequence", o.lines.sequence},
      // Which points of the sequence a chunk holds: since December 2026 a
      // permutation of the whole box's (docs/algorithm.md, "Order of lines in
      // a pass"); a store of consecutive points is traced again.
      {"lines.order", "permuted"},
      {"store.chunk_lines", std::to_string(o.store.chunk_lines)},
  };
}

std::vector<uint8_t> grouping_emitters(const Options& options, const PatchMesh& mesh, const Scene& scene) {
  std::vector<uint8_t> emitting;
  if (options.lines.box_budget == "pilot" && options.hierarchy.transport == "lines") {
    emitting.resize(mesh.patches.size(), 0);
    for (size_t p = 0; p < mesh.patches.size(); ++p) emitting[p] = scene.materials[mesh.patches[p].material].emits();
  }
  return emitting;
}

Hierarchy store_hierarchy(const Options& options, const PatchMesh& mesh, const std::vector<BoxLayout>* layout,
                          const Scene* scene) {
  const std::vector<uint8_t> emitting = scene ? grouping_emitters(options, mesh, *scene) : std::vector<uint8_t>{};
  Hierarchy h = layout ? assemble_hierarchy(mesh, options.hierarchy, *layout)
                       : build_hierarchy(mesh, options.hierarchy, options.solver.method != SolverMethod::hierarchical,
                                         false, emitting);
  if (h.boxes.size() > 1 && options.hierarchy.transport == "lines") make_boxes_transparent(h);
  else if (options.hierarchy.vp_grid <= 0) fit_vp_grids(h, options.lines);
  return h;
}

}  // namespace mpath
