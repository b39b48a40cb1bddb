// Picks the reader by file extension and applies the configured material overrides.
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <span>
#include <vector>

#include "coplanar_overlap.h"
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

// Tracing is in single precision: coordinates must be finite and well inside
// float's range, and the scene no larger than 1e7 m nor smaller than 1e-5 m
// across (a float resolves about 1e-7 of the scene; see docs/user-guide.md).
static void check_extent(const Scene& scene) {
  for (const Polygon& p : scene.polygons)
    for (const Vec3& v : p.vertices)
      for (int i = 0; i < 3; ++i)
        if (!std::isfinite(v[i]) || std::fabs(v[i]) > kMaxCoordinate)
          throw InputError(fmt::format("{}: a vertex at ({}, {}, {}) is beyond {} m, more than single-precision "
                                       "tracing can resolve (check the file's units and transforms)",
                                       scene.file.string(), v.x, v.y, v.z, kMaxCoordinate));
  const double size = scene.bounds().diagonal();
  if (!(size <= kMaxSceneSize && size >= kMinSceneSize))
    throw InputError(fmt::format("{}: the scene is {} m across; mpath solves scenes from {} m to {} m across (check "
                                 "the file's units)", scene.file.string(), size, kMinSceneSize, kMaxSceneSize));
}

// Polygons whose vertex set (in any order, rounded to 1e-9 of the scene)
// is another's.
// Polygons with the same vertices as an earlier one (within 1e-9 of the
// scene's size). One facing the same way is the same surface twice: it is
// dropped (the lines would meet one copy by chance, and power the first
// shot left on the other would never be sent on). One facing the other way
// is kept: two one-sided polygons back to back make a wall with two faces.
struct Repeated {
  size_t dropped = 0;   // same facing
  size_t reversed = 0;  // facing the other way, kept
};

static Repeated drop_repeated_polygons(Scene& scene) {
  const Bounds bounds = scene.bounds();
  const double grid = 1e-9 * std::max(bounds.diagonal(), 1e-30);  // offsets from the corner stay below 1e9 steps
  using GridPoint = std::array<long long, 3>;
  const size_t n = scene.polygons.size();
  // Each polygon's vertices on the grid, sorted: polygon i's are
  // points[start[i]] to points[start[i + 1]], all in one array (a map from
  // vertex sets took an allocation or three per polygon).
  std::vector<GridPoint> points;
  std::vector<size_t> start(n + 1, 0);
  for (size_t i = 0; i < n; ++i) {
    start[i] = points.size();
    for (const Vec3& v : scene.polygons[i].vertices)
      points.push_back({std::llround((v.x - bounds.lo.x) / grid), std::llround((v.y - bounds.lo.y) / grid),
                        std::llround((v.z - bounds.lo.z) / grid)});
    std::sort(points.begin() + static_cast<long>(start[i]), points.end());
  }
  start[n] = points.size();
  const auto vertex_set = [&](size_t i) {
    return std::span<const GridPoint>(points.data() + start[i], start[i + 1] - start[i]);
  };
  const auto before = [&](size_t a, size_t b) {
    const auto x = vertex_set(a), y = vertex_set(b);
    return std::lexicographical_compare(x.begin(), x.end(), y.begin(), y.end());
  };
  // Polygons with the same vertex set next to each other, each run in file order.
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), before);
  Repeated r;
  std::vector<uint8_t> dropped(n, 0);
  std::vector<Vec3> kept_normals;  // of the run's polygons kept so far
  for (size_t run = 0; run < n;) {
    size_t end = run + 1;
    while (end < n && !before(order[run], order[end])) ++end;
    kept_normals.clear();
    for (size_t k = run; end - run > 1 && k < end; ++k) {
      const Vec3 normal = newell_normal(scene.polygons[order[k]].vertices);
      bool duplicate = false, reversed = false;
      for (const Vec3& m : kept_normals) (dot(m, normal) > 0 ? duplicate : reversed) = true;
      if (duplicate) {
        ++r.dropped;
        dropped[order[k]] = 1;
        continue;
      }
      if (reversed) ++r.reversed;
      kept_normals.push_back(normal);
    }
    run = end;
  }
  if (r.dropped > 0) {
    size_t kept = 0;
    for (size_t i = 0; i < n; ++i) {
      if (dropped[i]) continue;
      if (kept != i) scene.polygons[kept] = std::move(scene.polygons[i]);  // never onto itself: that empties it
      ++kept;
    }
    scene.polygons.resize(kept);
  }
  return r;
}

Scene load_scene(const SceneOptions& options, int curve_segments, std::vector<std::string>& warnings) {
  const auto& path = options.file;
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  Scene scene;
  if (ext == ".obj") scene = read_obj(path, &warnings);
  else if (ext == ".ply") scene = read_ply(path);
  else if (ext == ".mgf") scene = read_mgf(path, curve_segments, options.mgf_default_sides, &warnings);
  else throw InputError(fmt::format("{}: unknown scene format '{}' (expected .obj, .ply or .mgf)", path.string(), ext));
  // Names and warnings go to logs, report.json and the store's manifest:
  // bytes of a damaged or foreign file that are not UTF-8 become \xNN.
  for (auto& o : scene.objects) o.name = printable(o.name);
  for (auto& m : scene.materials) m.name = printable(m.name);
  for (auto& w : warnings) w = printable(w);

  for (const auto& [name, radiance] : options.emitters)
    for (int m : require_materials(scene, "scene.emitters." + name, name)) scene.materials[m].emission = radiance;
  for (const auto& [name, rho] : options.materials)
    for (int m : require_materials(scene, "scene.materials." + name, name)) scene.materials[m].rho = rho;
  for (const auto& name : options.two_sided)
    for (int m : require_materials(scene, "scene.two_sided", name)) scene.materials[m].two_sided = true;
  for (const auto& m : scene.materials) validate_material(m, path.string());

  if (scene.polygons.empty()) throw InputError(fmt::format("{}: the scene has no polygons", path.string()));
  for (size_t i = 0; i < scene.polygons.size(); ++i)
    if (scene.polygons[i].vertices.size() > kMaxPolygonVertices)
      throw InputError(fmt::format("{}: polygon {} has {} vertices; mpath takes at most {} (split it into smaller ones)",
                                   path.string(), i + 1, scene.polygons[i].vertices.size(), kMaxPolygonVertices));
  check_extent(scene);
  const Repeated repeated = drop_repeated_polygons(scene);
  if (repeated.dropped > 0)
    warnings.push_back(fmt::format("{} polygon(s) repeat an earlier one facing the same way (duplicated faces): "
                                   "dropped, as one surface", repeated.dropped));
  if (repeated.reversed > 0)
    warnings.push_back(fmt::format(
        "{} polygon(s) have the same vertices as another facing the other way: kept back to back; where both are "
        "two-sided the two coincide and the lines meet them by chance (make them one-sided, or one two-sided)",
        repeated.reversed));
  if (const CoplanarOverlaps o = find_coplanar_overlaps(scene); o.polygons > 0) {
    auto name = [&](int p) {
      return fmt::format("polygon {} of object '{}'", p + 1, scene.objects.at(scene.polygons[p].object).name);
    };
    warnings.push_back(fmt::format(
        "{} polygon(s) overlap a coplanar polygon facing the same way (first: {} and {}): where they overlap the "
        "lines meet one of them by chance and the methods light them differently; remove the overlap or offset "
        "one of them", o.polygons, name(o.first), name(o.second)));
  }
  const bool any_emitter = std::any_of(scene.polygons.begin(), scene.polygons.end(),
                                       [&](const Polygon& p) { return scene.materials[p.material].emits(); });
  if (!any_emitter && options.lights.empty())
    throw InputError(fmt::format("{}: the scene has no emitting polygon (give a material emission in the file, "
                                 "name it in the config's [scene.emitters], or add a [[light]])", path.string()));
  return scene;
}

}  // namespace mpath
