#include "scene.h"

#include "error.h"

namespace mpath {

Bounds Scene::bounds() const {
  Bounds b;
  for (const auto& p : polygons)
    for (const auto& v : p.vertices) b.extend(v);
  return b;
}

int Scene::find_material(const std::string& name) const {
  for (size_t i = 0; i < materials.size(); ++i)
    if (materials[i].name == name) return static_cast<int>(i);
  return -1;
}

bool Scene::is_grey() const {
  for (const auto& m : materials) {
    if (m.rho[0] != m.rho[1] || m.rho[1] != m.rho[2]) return false;
    if (m.emission[0] != m.emission[1] || m.emission[1] != m.emission[2]) return false;
  }
  return true;
}

Vec3 newell_normal(const std::vector<Vec3>& v) {
  Vec3 n;
  const size_t count = v.size();
  for (size_t i = 0; i < count; ++i) {
    const Vec3& a = v[i];
    const Vec3& b = v[(i + 1) % count];
    n.x += (a.y - b.y) * (a.z + b.z);
    n.y += (a.z - b.z) * (a.x + b.x);
    n.z += (a.x - b.x) * (a.y + b.y);
  }
  return n;
}

double polygon_area(const std::vector<Vec3>& vertices) { return 0.5 * length(newell_normal(vertices)); }

void validate_material(const Material& m, const std::string& where) {
  for (int c = 0; c < 3; ++c) {
    if (!(m.rho[c] >= 0.0 && m.rho[c] <= 1.0))
      throw InputError(fmt::format("{}: material '{}': reflectance {} is outside [0, 1]", where, m.name, m.rho[c]));
    if (!(m.emission[c] >= 0.0) || !std::isfinite(m.emission[c]))
      throw InputError(fmt::format("{}: material '{}': emission {} must be finite and >= 0", where, m.name, m.emission[c]));
    // Far above any light source (the sun's disc is about 2e7), and far enough
    // below the float range of solution.ply for any reflectance below 1.
    if (m.emission[c] > kMaxEmission)
      throw InputError(fmt::format("{}: material '{}': emission {} W/sr/m2 is above {:g} (mpath's limit; scale the "
                                   "scene's emission down)", where, m.name, m.emission[c], kMaxEmission));
  }
}

}  // namespace mpath
