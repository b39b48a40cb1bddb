#include "mesh.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LongestEdgeT.hh>
#include <algorithm>
#include <cmath>

#include "contact.h"
#include "error.h"

namespace mpath {
namespace {

struct DoubleTraits : OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
};
using TriMesh = OpenMesh::TriMesh_ArrayKernelT<DoubleTraits>;

// Polygon corners with consecutive duplicates removed.
std::vector<Vec3> clean_polygon(const std::vector<Vec3>& in, double eps) {
  std::vector<Vec3> out;
  for (const Vec3& v : in)
    if (out.empty() || length(v - out.back()) > eps) out.push_back(v);
  while (out.size() > 1 && length(out.front() - out.back()) <= eps) out.pop_back();
  return out;
}

bool is_parallelogram(const std::vector<Vec3>& p, double eps) {
  return p.size() == 4 && length((p[0] + p[2]) - (p[1] + p[3])) <= eps;
}

bool is_convex(const std::vector<Vec3>& p, const Vec3& n) {
  for (size_t i = 0; i < p.size(); ++i) {
    const Vec3 a = p[i], b = p[(i + 1) % p.size()], c = p[(i + 2) % p.size()];
    if (dot(cross(b - a, c - b), n) < 0) return false;
  }
  return true;
}

class MeshBuilder {
 public:
  explicit MeshBuilder(PatchMesh& mesh) : mesh_(mesh) {}

  void add_polygon(const Polygon& poly, int index, double eps) {
    const std::vector<Vec3> p = clean_polygon(poly.vertices, eps);
    const Vec3 newell = p.size() >= 3 ? newell_normal(p) : Vec3{};
    const double area = 0.5 * length(newell);
    if (p.size() < 3 || !(area > eps * eps)) {
      ++mesh_.dropped_polygons;
      return;
    }
    current_ = {index, poly.object, poly.material, newell / (2.0 * area), eps};
    const double max_area = mesh_.max_patch_area;
    if (is_parallelogram(p, eps)) {
      add_grid(p, max_area);
    } else if (area <= max_area && p.size() <= 4 && is_convex(p, current_.normal)) {
      const uint32_t base = add_vertices(p);
      add_patch({base, base + 1, base + 2, p.size() == 4 ? base + 3 : base + 2});
    } else {
      add_subdivided(p, area > max_area ? max_area : 0.0);
    }
  }

 private:
  struct Current {
    int polygon, object, material;
    Vec3 normal;
    double eps;
  };

  uint32_t add_vertices(const std::vector<Vec3>& p) {
    const auto base = static_cast<uint32_t>(mesh_.vertices.size());
    mesh_.vertices.insert(mesh_.vertices.end(), p.begin(), p.end());
    return base;
  }

  void add_patch(std::array<uint32_t, 4> v) {
    Patch patch;
    patch.v = v;
    std::vector<Vec3> corners{mesh_.vertices[v[0]], mesh_.vertices[v[1]], mesh_.vertices[v[2]]};
    if (v[3] != v[2]) corners.push_back(mesh_.vertices[v[3]]);
    patch.area = polygon_area(corners);
    // A sliver of a triangulation (corners on one line, as along a keyhole
    // seam) has no area and receives no light: it is no patch.
    if (!(patch.area > current_.eps * current_.eps)) return;
    patch.normal = current_.normal;
    patch.polygon = current_.polygon;
    patch.object = current_.object;
    patch.material = current_.material;
    mesh_.patches.push_back(patch);
  }

  // A parallelogram becomes an n x m grid of equal parallelograms.
  void add_grid(const std::vector<Vec3>& p, double max_area) {
    const Vec3 e1 = p[1] - p[0], e2 = p[3] - p[0];
    const double side = std::sqrt(max_area);
    const int n = std::max(1, static_cast<int>(std::ceil(length(e1) / side - 1e-9)));
    const int m = std::max(1, static_cast<int>(std::ceil(length(e2) / side - 1e-9)));
    const auto base = static_cast<uint32_t>(mesh_.vertices.size());
    for (int j = 0; j <= m; ++j)
      for (int i = 0; i <= n; ++i) mesh_.vertices.push_back(p[0] + e1 * (double(i) / n) + e2 * (double(j) / m));
    auto at = [&](int i, int j) { return base + static_cast<uint32_t>(j * (n + 1) + i); };
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < n; ++i) add_patch({at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
  }

  // Triangulates, then splits edges longer than L until every triangle is at
  // most max_area (an edge bound L gives area <= sqrt(3)/4 L^2).
  void add_subdivided(const std::vector<Vec3>& p, double max_area) {
    const auto triangles = triangulate(p);
    if (max_area <= 0) {
      const uint32_t base = add_vertices(p);
      for (const auto& t : triangles) add_patch({base + t[0], base + t[1], base + t[2], base + t[2]});
      return;
    }
    TriMesh tm;
    std::vector<TriMesh::VertexHandle> handles;
    for (const Vec3& v : p) handles.push_back(tm.add_vertex(TriMesh::Point(v.x, v.y, v.z)));
    for (const auto& t : triangles) tm.add_face(handles[t[0]], handles[t[1]], handles[t[2]]);
    OpenMesh::Subdivider::Uniform::LongestEdgeT<TriMesh, double> subdivider;
    subdivider.attach(tm);
    subdivider.set_max_edge_length(std::sqrt(4.0 * max_area / std::sqrt(3.0)));
    subdivider(1);
    subdivider.detach();
    const auto base = static_cast<uint32_t>(mesh_.vertices.size());
    for (const auto& vh : tm.vertices()) {
      const auto& q = tm.point(vh);
      mesh_.vertices.push_back({q[0], q[1], q[2]});
    }
    for (const auto& fh : tm.faces()) {
      std::array<uint32_t, 4> v{};
      int k = 0;
      for (const auto& vh : tm.fv_range(fh)) v[k++] = base + static_cast<uint32_t>(vh.idx());
      v[3] = v[2];
      add_patch(v);
    }
  }

  PatchMesh& mesh_;
  Current current_{};
};

double signed_area_2d(const std::vector<std::array<double, 2>>& q, const std::vector<uint32_t>& idx) {
  double a = 0;
  for (size_t i = 0; i < idx.size(); ++i) {
    const auto& p = q[idx[i]];
    const auto& r = q[idx[(i + 1) % idx.size()]];
    a += p[0] * r[1] - r[0] * p[1];
  }
  return 0.5 * a;
}

double cross2(const std::array<double, 2>& a, const std::array<double, 2>& b, const std::array<double, 2>& c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

}  // namespace

std::vector<std::array<uint32_t, 3>> triangulate(const std::vector<Vec3>& polygon) {
  const size_t n = polygon.size();
  std::vector<std::array<uint32_t, 3>> out;
  if (n < 3) return out;
  // Project on the plane of the largest normal component.
  const Vec3 normal = newell_normal(polygon);
  int axis = 0;
  for (int i = 1; i < 3; ++i)
    if (std::fabs(normal[i]) > std::fabs(normal[axis])) axis = i;
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  std::vector<std::array<double, 2>> q(n);
  for (size_t i = 0; i < n; ++i) q[i] = {polygon[i][u], polygon[i][v]};
  std::vector<uint32_t> idx(n);
  for (size_t i = 0; i < n; ++i) idx[i] = static_cast<uint32_t>(i);
  const double orientation = signed_area_2d(q, idx) >= 0 ? 1.0 : -1.0;

  size_t guard = 0;
  while (idx.size() > 3 && guard < 4 * n * n) {
    bool clipped = false;
    for (size_t i = 0; i < idx.size() && !clipped; ++i) {
      const uint32_t a = idx[(i + idx.size() - 1) % idx.size()], b = idx[i], c = idx[(i + 1) % idx.size()];
      if (orientation * cross2(q[a], q[b], q[c]) <= 0) continue;  // reflex corner
      bool empty = true;
      for (uint32_t k : idx) {
        if (k == a || k == b || k == c) continue;
        // A corner repeated where a polygon runs to a hole and back (a
        // keyhole seam) lies on the ear's corner, not in it.
        if (q[k] == q[a] || q[k] == q[b] || q[k] == q[c]) continue;
        if (orientation * cross2(q[a], q[b], q[k]) >= 0 && orientation * cross2(q[b], q[c], q[k]) >= 0 &&
            orientation * cross2(q[c], q[a], q[k]) >= 0) {
          empty = false;
          break;
        }
      }
      if (!empty) continue;
      out.push_back({a, b, c});
      idx.erase(idx.begin() + static_cast<long>(i));
      clipped = true;
    }
    if (!clipped) break;
    ++guard;
  }
  // What is left (a triangle, or a non-simple remainder) becomes a fan.
  for (size_t i = 1; i + 1 < idx.size(); ++i) out.push_back({idx[0], idx[i], idx[i + 1]});
  return out;
}

namespace {

// Per patch, the contact plane of its polygon when the patch's box overlaps
// (by more than `eps` across) the box of a polygon it touches; else -1.
// Empty when no patch touches anything.
std::vector<int> touching_planes(const Scene& scene, const PatchMesh& mesh, double eps) {
  const ContactPlanes contacts = contact_planes(scene);
  std::vector<int> out(mesh.patches.size(), -1);
  bool any = false;
  for (size_t i = 0; i < mesh.patches.size(); ++i) {
    const Patch& p = mesh.patches[i];
    const size_t polygon = static_cast<size_t>(p.polygon);
    if (contacts.plane[polygon] < 0) continue;
    Bounds box;
    for (const uint32_t v : p.v) box.extend(mesh.vertices[v]);
    // On the plane the boxes are flat along its normal: only the other two
    // axes must overlap by more than eps.
    const int axis = std::fabs(p.normal.x) >= std::fabs(p.normal.y) && std::fabs(p.normal.x) >= std::fabs(p.normal.z) ? 0
                     : std::fabs(p.normal.y) >= std::fabs(p.normal.z)                                          ? 1
                                                                                                              : 2;
    for (const Bounds& q : contacts.partner_bounds[polygon]) {
      bool overlap = true;
      for (int a = 0; a < 3; ++a)
        if (a != axis) overlap &= std::min(box.hi[a], q.hi[a]) - std::max(box.lo[a], q.lo[a]) > eps;
      if (overlap) {
        out[i] = contacts.plane[polygon];
        any = true;
        break;
      }
    }
  }
  if (!any) out.clear();
  return out;
}

}  // namespace

double automatic_patch_area(const Scene& scene) { return scene.bounds().surface_area() / 2000.0; }

PatchMesh build_mesh(const Scene& scene, double max_patch_area) {
  PatchMesh mesh;
  mesh.bounds = scene.bounds();
  mesh.max_patch_area = max_patch_area > 0 ? max_patch_area : automatic_patch_area(scene);
  double area = 0;
  for (const Polygon& p : scene.polygons) area += polygon_area(p.vertices);
  if (!(area > 0) || !(mesh.max_patch_area > 0))
    throw InputError(fmt::format("{}: no polygon of the scene has an area (all {} are degenerate: collinear or "
                                 "repeated vertices)", scene.file.string(), scene.polygons.size()));
  const double eps = 1e-9 * mesh.bounds.diagonal();
  // Refuse a patch size that would fill memory before trying: every patch
  // costs about 200 bytes across mesh, tracer and solver.
  double total_area = 0;
  for (const Polygon& p : scene.polygons) total_area += polygon_area(p.vertices);
  const double expected_patches = total_area / mesh.max_patch_area;
  if (expected_patches > kMaxPatches)
    throw InputError(fmt::format("config key 'mesh.max_patch_area': {} gives about {:.3g} patches for {:.4g} square units "
                                 "of surface (at most {:.3g}); use a larger value",
                                 mesh.max_patch_area, expected_patches, total_area, static_cast<double>(kMaxPatches)));
  MeshBuilder builder(mesh);
  for (size_t i = 0; i < scene.polygons.size(); ++i) builder.add_polygon(scene.polygons[i], static_cast<int>(i), eps);

  // Faces: all fronts, then the backs of two-sided patches.
  const int patches = static_cast<int>(mesh.patches.size());
  mesh.contact_plane = touching_planes(scene, mesh, eps);
  mesh.patch_faces.assign(patches, {kBlackSide, kBlackSide});
  for (int i = 0; i < patches; ++i) {
    mesh.patch_faces[i][0] = i;
    mesh.face_patch.push_back(i);
    mesh.face_side.push_back(0);
  }
  for (int i = 0; i < patches; ++i) {
    const Material& m = scene.materials[mesh.patches[i].material];
    if (!m.two_sided) {
      if (m.invisible_back) mesh.patch_faces[i][1] = kInvisibleSide;
      continue;
    }
    mesh.patch_faces[i][1] = static_cast<int>(mesh.face_patch.size());
    mesh.face_patch.push_back(i);
    mesh.face_side.push_back(1);
  }
  return mesh;
}

}  // namespace mpath
