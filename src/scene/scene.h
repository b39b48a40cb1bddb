// The scene model: materials, objects and planar polygons, as read from a file
// and before meshing. Polygons are counter-clockwise seen from their front.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "vec3.h"

namespace mpath {

struct Material {
  std::string name;
  Rgb rho{0.5, 0.5, 0.5};   // diffuse reflectance, each in [0, 1)
  Rgb emission{0, 0, 0};    // emitted radiance, W/sr/m2 (exitance is pi times this)
  bool two_sided = false;
  // One-sided only: the back is invisible (what reaches it passes through, as
  // the MGF specification says) rather than black (it absorbs what reaches it).
  bool invisible_back = false;

  bool emits() const { return emission[0] > 0 || emission[1] > 0 || emission[2] > 0; }
};

struct Polygon {
  std::vector<Vec3> vertices;
  int material = 0;
  int object = 0;
};

struct SceneObject {
  std::string name;
};

struct Scene {
  std::filesystem::path file;
  std::vector<Material> materials;
  std::vector<SceneObject> objects;
  std::vector<Polygon> polygons;

  Bounds bounds() const;
  int find_material(const std::string& name) const;  // -1 when absent
  // True when every material has equal r, g, b reflectance and emission.
  bool is_grey() const;
};

// Newell normal of a polygon: direction is the front normal, length is twice the area.
Vec3 newell_normal(const std::vector<Vec3>& vertices);
double polygon_area(const std::vector<Vec3>& vertices);

// The most vertices a polygon may have (triangulating a concave polygon
// takes time growing with the square of its vertices).
inline constexpr size_t kMaxPolygonVertices = 10'000;

// Limits of scenes single-precision tracing resolves (metres).
inline constexpr double kMaxCoordinate = 1e7;
inline constexpr double kMaxSceneSize = 1e7;
inline constexpr double kMinSceneSize = 1e-5;

// The largest emitted radiance a material may have, W/sr/m2.
inline constexpr double kMaxEmission = 1e12;

// Checks a material read from `path`: reflectances in [0, 1), emission finite, >= 0 and at most kMaxEmission.
void validate_material(const Material& m, const std::string& where);

}  // namespace mpath
