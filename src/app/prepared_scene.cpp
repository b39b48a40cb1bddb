#include "prepared_scene.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>

#include "scene_readers.h"

namespace mpath {

PreparedScene prepare_scene(const Options& options) {
  using clock = std::chrono::steady_clock;
  PreparedScene out;
  auto t0 = clock::now();
  out.scene = load_scene(options.scene, options.mesh.curve_segments, out.warnings);
  if (options.mesh.split_contacts) {
    // A contact is split when larger than a patch, or when it covers more
    // than a fifth of the smaller object (a frame's bar, a picture's back):
    // smaller ones (chair legs, books standing on a board) cover sides below
    // the mesh's resolution and of little of their objects (scene-formats.md).
    const double patch = options.mesh.max_patch_area > 0 ? options.mesh.max_patch_area : automatic_patch_area(out.scene);
    out.contacts = split_contacts(out.scene, options.mesh.contact_min_area > 0 ? options.mesh.contact_min_area : patch,
                                  kContactMinShare);
  }
  auto t1 = clock::now();
  out.mesh = build_mesh(out.scene, options.mesh.max_patch_area);
  auto t2 = clock::now();
  out.load_seconds = std::chrono::duration<double>(t1 - t0).count();
  out.mesh_seconds = std::chrono::duration<double>(t2 - t1).count();
  if (out.mesh.dropped_polygons > 0)
    out.warnings.push_back(fmt::format("{} degenerate polygon(s) (no area) dropped", out.mesh.dropped_polygons));
  for (const auto& w : out.warnings) spdlog::warn("{}", w);
  spdlog::info("scene {}: {} polygons, {} objects, {} materials", options.scene.file.string(), out.scene.polygons.size(),
               out.scene.objects.size(), out.scene.materials.size());
  if (out.contacts.pairs > 0)
    spdlog::info("contacts: {} pairs of polygons touching; {} polygons split into {} (mesh.split_contacts)",
                 out.contacts.pairs, out.contacts.split, out.contacts.pieces);
  if (out.contacts.skipped > 0)
    spdlog::warn("contacts: {} pair(s) of coplanar polygons facing each other left whole: one is not convex",
                 out.contacts.skipped);
  spdlog::info("mesh: {} patches, {} faces, max patch area {:.4g}{}", out.mesh.patches.size(), out.mesh.face_count(),
               out.mesh.max_patch_area, options.mesh.max_patch_area > 0 ? "" : " (automatic)");
  const auto touching = std::count_if(out.mesh.contact_plane.begin(), out.mesh.contact_plane.end(),
                                      [](int plane) { return plane >= 0; });
  if (touching > 0)
    spdlog::info("contacts: {} patches touch another surface there and exchange nothing with it (docs/scene-formats.md, "
                 "\"Surfaces in contact\")", touching);
  return out;
}

}  // namespace mpath
