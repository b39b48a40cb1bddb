#include "solution_ply.h"

#include <bit>

#include "atomic_file.h"
#include "mpath_version.h"

namespace mpath {
namespace {

static_assert(std::endian::native == std::endian::little, "solution.ply is written as native little-endian");

template <typename T>
void put(std::ostream& out, T v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof(T));
}

}  // namespace

void write_solution_ply(const std::filesystem::path& path, const PatchMesh& mesh, const RadiosityState& state) {
  AtomicFile file(path);
  std::ostream& out = file.stream();
  out << "ply\nformat binary_little_endian 1.0\n"
      << "comment mpath " << MPATH_VERSION << " radiosity solution; B and emit in W/m2, area in scene units^2\n"
      << "element vertex " << mesh.vertices.size() << "\n"
      << "property float x\nproperty float y\nproperty float z\n"
      << "element face " << state.faces << "\n"
      << "property list uchar int vertex_indices\n";
  for (const char* name : {"area", "rho_r", "rho_g", "rho_b", "emit_r", "emit_g", "emit_b", "B_r", "B_g", "B_b"})
    out << "property float " << name << "\n";
  out << "property int polygon\nproperty int object\nend_header\n";
  for (const Vec3& v : mesh.vertices) {
    put(out, static_cast<float>(v.x));
    put(out, static_cast<float>(v.y));
    put(out, static_cast<float>(v.z));
  }
  for (size_t f = 0; f < state.faces; ++f) {
    const Patch& p = mesh.patches[mesh.face_patch[f]];
    const int corners = p.is_triangle() ? 3 : 4;
    put<uint8_t>(out, static_cast<uint8_t>(corners));
    // A back face lists its corners in reverse so its normal points its way.
    for (int k = 0; k < corners; ++k) {
      const int i = mesh.face_side[f] ? corners - 1 - k : k;
      put<int32_t>(out, static_cast<int32_t>(p.v[i]));
    }
    put(out, static_cast<float>(p.area));
    for (double v : state.face_rho(f)) put(out, static_cast<float>(v));
    for (double v : state.face_exitance(f)) put(out, static_cast<float>(v));
    for (double v : state.radiosity(mesh, f)) put(out, static_cast<float>(v));
    put<int32_t>(out, p.polygon);
    put<int32_t>(out, p.object);
  }
  file.commit();
}

}  // namespace mpath
