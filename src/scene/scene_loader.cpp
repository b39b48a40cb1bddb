// Picks the reader by file extension and applies the configured material overrides.
#include <algorithm>

#include "error.h"
#include "scene_readers.h"

namespace mpath {
namespace {

// Scene materials called `name`, including MGF redefinitions ("name#2").
std::vector<int> materials_named(const Scene& scene, const std::string& name) {
  std::vector<int> found;
  for (size_t i = 0; i < scene.materials.size(); ++i) {
    const std::string& m = scene.materials[i].name;
    if (m == name || m.rfind(name + "#", 0) == 0) found.push_back(static_cast<int>(i));
  }
  return found;
}

std::string material_list(const Scene& scene) {
  std::string s;
  for (size_t i = 0; i < scene.materials.size() && i < 20; ++i) s += (i ? ", " : "") + scene.materials[i].name;
  if (scene.materials.size() > 20) s += ", ...";
  return s;
}

std::vector<int> require_materials(const Scene& scene, const std::string& key, const std::string& name) {
  std::vector<int> found = materials_named(scene, name);
  if (found.empty())
    throw InputError(fmt::format("config key '{}': unknown material '{}' (the scene has: {})", key, name, material_list(scene)));
  return found;
}

}  // namespace

Scene load_scene(const SceneOptions& options, int curve_segments, std::vector<std::string>& warnings) {
  const auto& path = options.file;
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  Scene scene;
  if (ext == ".obj") scene = read_obj(path);
  else if (ext == ".ply") scene = read_ply(path);
  else if (ext == ".mgf") scene = read_mgf(path, curve_segments, options.mgf_default_sides, &warnings);
  else throw InputError(fmt::format("{}: unknown scene format '{}' (expected .obj, .ply or .mgf)", path.string(), ext));

  for (const auto& [name, radiance] : options.emitters)
    for (int m : require_materials(scene, "scene.emitters." + name, name)) scene.materials[m].emission = radiance;
  for (const auto& name : options.two_sided)
    for (int m : require_materials(scene, "scene.two_sided", name)) scene.materials[m].two_sided = true;
  for (const auto& m : scene.materials) validate_material(m, path.string());

  if (scene.polygons.empty()) throw InputError(fmt::format("{}: the scene has no polygons", path.string()));
  const bool any_emitter = std::any_of(scene.polygons.begin(), scene.polygons.end(),
                                       [&](const Polygon& p) { return scene.materials[p.material].emits(); });
  if (!any_emitter)
    throw InputError(fmt::format("{}: the scene has no emitting polygon (give a material emission in the file, "
                                 "or name it in the config's [scene.emitters])", path.string()));
  return scene;
}

}  // namespace mpath
