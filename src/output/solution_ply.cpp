#include "solution_ply.h"

#include <algorithm>
#include <bit>

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <fstream>
#include <map>
#include <sstream>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "atomic_file.h"
#include "error.h"
#include "scene_readers.h"
#include "mpath_version.h"

namespace mpath {
namespace {

static_assert(std::endian::native == std::endian::little, "solution.ply is written and read as native little-endian");

// Appends v's bytes at `at` and moves past them.
template <typename T>
void put(char*& at, T v) {
  std::memcpy(at, &v, sizeof(T));
  at += sizeof(T);
}

uint8_t srgb8_direct(double linear) {
  const double v = std::clamp(linear, 0.0, 1.0);
  const double s = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
  return static_cast<uint8_t>(std::lround(255.0 * s));
}

// srgb8_direct without a pow per value (half a million of them on an
// 86,000-face scene, a third of the file's time): the linear values where
// the rounded code steps up, found once by bisection on srgb8_direct
// itself, so the table gives its codes exactly.
class Srgb8 {
 public:
  Srgb8() {
    for (int k = 1; k < 256; ++k) {
      double lo = 0.0, hi = 1.0;  // srgb8_direct(lo) < k <= srgb8_direct(hi)
      for (int i = 0; i < 200 && std::nextafter(lo, 2.0) < hi; ++i) {
        const double mid = 0.5 * (lo + hi);
        (srgb8_direct(mid) < k ? lo : hi) = mid;
      }
      step_[k - 1] = hi;
    }
  }
  uint8_t operator()(double linear) const {
    if (!(linear > 0.0)) return 0;  // and 0 for a NaN (solution.ply never has one: checked before writing)
    return static_cast<uint8_t>(std::upper_bound(step_.begin(), step_.end(), linear) - step_.begin());
  }

 private:
  std::array<double, 255> step_{};  // step_[k - 1]: the least linear value coded k
};

// Writes `count` records in blocks: each block's records are placed in
// parallel (`size(i)` bytes each, `fill(i, at)` writes them), then the
// block goes to `out` in one write, so memory stays a block whatever the
// scene's size.
template <typename Size, typename Fill>
void write_records(std::ostream& out, size_t count, Size size, Fill fill) {
  constexpr size_t kBlock = 65536;
  std::vector<size_t> offset;
  std::vector<char> buffer;
  for (size_t first = 0; first < count; first += kBlock) {
    const size_t n = std::min(kBlock, count - first);
    offset.assign(n + 1, 0);
    for (size_t i = 0; i < n; ++i) offset[i + 1] = offset[i] + size(first + i);
    buffer.resize(offset[n]);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) {
        char* at = buffer.data() + offset[i];
        fill(first + i, at);
      }
    });
    out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  }
}

// The display scale of the colours: the 95th percentile (by area) of the
// radiosity of the faces that do not emit (of all, if every face emits)
// shows at 0.8 of white; emitters and the brightest 5 % clip.
double display_scale(const PatchMesh& mesh, const std::vector<SolutionFace>& faces) {
  std::vector<std::pair<double, double>> value_area;
  for (const bool lit_only : {true, false}) {
    for (size_t f = 0; f < faces.size(); ++f) {
      const auto& e = faces[f].exitance;
      if (lit_only && e[0] + e[1] + e[2] > 0) continue;
      const auto& b = faces[f].radiosity;
      value_area.push_back({(b[0] + b[1] + b[2]) / 3, mesh.patches[mesh.face_patch[f]].area});
    }
    if (!value_area.empty()) break;
  }
  std::sort(value_area.begin(), value_area.end());
  double total = 0, seen = 0;
  for (const auto& [v, a] : value_area) total += a;
  for (const auto& [v, a] : value_area)
    if ((seen += a) >= 0.95 * total) return v > 0 ? 0.8 / v : 1.0;
  return 1.0;
}

}  // namespace

uint8_t display_srgb8(double linear) {
  static const Srgb8 table;
  return table(linear);
}

void write_solution_ply(const std::filesystem::path& path, const PatchMesh& mesh, const std::vector<SolutionFace>& faces) {
  // Never a NaN or an infinity in a result: a value no float holds stops the write before anything is written.
  for (size_t f = 0; f < faces.size(); ++f)
    for (const Rgb* values : {&faces[f].rho, &faces[f].exitance, &faces[f].radiosity})
      for (double v : *values)
        if (!(std::fabs(v) <= std::numeric_limits<float>::max()))
          throw std::runtime_error(fmt::format("{}: face {} has a value no float holds ({}); nothing written",
                                               path.string(), f, v));
  // Colours for viewers: per vertex the area-weighted radiosity of the front
  // faces around it (of the back faces where it has no front), per face its
  // own, tone-mapped to sRGB.
  const double scale = display_scale(mesh, faces);
  std::vector<std::array<double, 4>> vertex_sum(mesh.vertices.size(), {0, 0, 0, 0});  // per side below
  std::vector<std::array<double, 4>> back_sum(mesh.vertices.size(), {0, 0, 0, 0});
  for (size_t f = 0; f < faces.size(); ++f) {
    const Patch& p = mesh.patches[mesh.face_patch[f]];
    auto& sums = mesh.face_side[f] ? back_sum : vertex_sum;
    for (int k = 0; k < (p.is_triangle() ? 3 : 4); ++k) {
      auto& s = sums[p.v[k]];
      for (int c = 0; c < 3; ++c) s[c] += p.area * faces[f].radiosity[c];
      s[3] += p.area;
    }
  }
  AtomicFile file(path);
  std::ostream& out = file.stream();
  out << "ply\nformat binary_little_endian 1.0\n"
      << "comment mpath " << MPATH_VERSION << " radiosity solution; B and emit in W/m2, area in scene units^2\n"
      << "comment red green blue: sRGB of B times " << fmt::format("{:.6g}", scale)
      << " (the 95th percentile by area of the faces that do not emit at 0.8), clipped; for viewers only\n"
      << "element vertex " << mesh.vertices.size() << "\n"
      << "property float x\nproperty float y\nproperty float z\n"
      << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
      << "element face " << faces.size() << "\n"
      << "property list uchar int vertex_indices\n";
  for (const char* name : {"area", "rho_r", "rho_g", "rho_b", "emit_r", "emit_g", "emit_b", "B_r", "B_g", "B_b"})
    out << "property float " << name << "\n";
  out << "property int polygon\nproperty int object\n"
      << "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  write_records(out, mesh.vertices.size(), [](size_t) { return size_t{15}; }, [&](size_t i, char*& at) {
    const Vec3& v = mesh.vertices[i];
    put(at, static_cast<float>(v.x));
    put(at, static_cast<float>(v.y));
    put(at, static_cast<float>(v.z));
    const auto& s = vertex_sum[i][3] > 0 ? vertex_sum[i] : back_sum[i];
    for (int c = 0; c < 3; ++c) put<uint8_t>(at, display_srgb8(s[3] > 0 ? scale * s[c] / s[3] : 0.0));
  });
  const auto corners = [&](size_t f) { return mesh.patches[mesh.face_patch[f]].is_triangle() ? 3 : 4; };
  // A face: its corner count and corners, 10 floats, 2 ints, 3 colour bytes.
  write_records(out, faces.size(), [&](size_t f) { return size_t{1 + 40 + 8 + 3} + 4 * corners(f); },
                [&](size_t f, char*& at) {
    const Patch& p = mesh.patches[mesh.face_patch[f]];
    const int n = corners(f);
    put<uint8_t>(at, static_cast<uint8_t>(n));
    // A back face lists its corners in reverse so its normal points its way.
    for (int k = 0; k < n; ++k) {
      const int i = mesh.face_side[f] ? n - 1 - k : k;
      put<int32_t>(at, static_cast<int32_t>(p.v[i]));
    }
    put(at, static_cast<float>(p.area));
    for (double v : faces[f].rho) put(at, static_cast<float>(v));
    for (double v : faces[f].exitance) put(at, static_cast<float>(v));
    for (double v : faces[f].radiosity) put(at, static_cast<float>(v));
    put<int32_t>(at, p.polygon);
    put<int32_t>(at, p.object);
    for (double v : faces[f].radiosity) put<uint8_t>(at, display_srgb8(scale * v));
  });
  file.commit();
}

SolutionFaces read_solution_ply(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot open", path.string()));
  std::string line;
  auto fail = [&](const std::string& why) { return InputError(fmt::format("{}: not an mpath solution.ply: {}", path.string(), why)); };
  if (!std::getline(in, line) || line != "ply") throw fail("no 'ply' magic");
  size_t vertices = 0, faces = 0;
  std::string element;
  bool binary_le = false, list_ok = false;
  std::vector<std::pair<std::string, size_t>> props;  // face scalar properties after the list
  size_t vertex_bytes = 0;
  while (true) {
    if (!std::getline(in, line)) throw fail("the header has no end_header");
    if (line == "end_header") break;
    std::istringstream w(line);
    std::string word;
    w >> word;
    if (word == "format") {
      std::string f;
      w >> f;
      binary_le = f == "binary_little_endian";
    } else if (word == "element") {
      w >> element;
      size_t n = 0;
      if (!(w >> n)) throw fail("element without a count: " + line);
      if (element == "vertex") vertices = n;
      else if (element == "face") faces = n;
      else throw fail("unexpected element " + element);
    } else if (word == "property") {
      std::string type, name;
      w >> type;
      if (type == "list") {
        std::string count_type, item_type;
        w >> count_type >> item_type >> name;
        if (element != "face" || name != "vertex_indices" || count_type != "uchar" || ply_type_size(item_type) != 4)
          throw fail("unexpected list property: " + line);
        list_ok = true;
        continue;
      }
      w >> name;
      const size_t size = ply_type_size(type);
      if (size == 0) throw fail("unknown property type " + type);
      if (element == "vertex") vertex_bytes += size;
      else props.emplace_back(name, size);
    }
  }
  if (!binary_le) throw fail("not binary_little_endian");
  if (!list_ok) throw fail("faces have no vertex_indices list");
  std::map<std::string, size_t> offset;
  size_t record = 0;
  for (const auto& [name, size] : props) {
    offset[name] = record;
    record += size;
  }
  for (const char* name : {"area", "B_r", "B_g", "B_b"})
    if (!offset.count(name)) throw fail(std::string("faces have no float property ") + name);
  const bool has_emit = offset.count("emit_r") && offset.count("emit_g") && offset.count("emit_b");
  in.seekg(static_cast<std::streamoff>(vertices * vertex_bytes), std::ios::cur);
  SolutionFaces out;
  out.area.resize(faces);
  out.radiosity.resize(faces);
  out.exitance.resize(faces);
  std::vector<char> buf(record);
  // Where each wanted float lies in a face's record (looked up once).
  const size_t area_at = offset["area"], b_at[3] = {offset["B_r"], offset["B_g"], offset["B_b"]};
  const size_t e_at[3] = {has_emit ? offset["emit_r"] : 0, has_emit ? offset["emit_g"] : 0,
                          has_emit ? offset["emit_b"] : 0};
  auto get = [&](size_t at) {
    float v;
    std::memcpy(&v, buf.data() + at, sizeof v);
    return v;
  };
  for (size_t f = 0; f < faces; ++f) {
    uint8_t n = 0;
    in.read(reinterpret_cast<char*>(&n), 1);
    in.seekg(4 * n, std::ios::cur);
    in.read(buf.data(), static_cast<std::streamsize>(record));
    if (!in) throw InputError(fmt::format("{}: cut short at face {} of {}", path.string(), f, faces));
    out.area[f] = get(area_at);
    out.radiosity[f] = {get(b_at[0]), get(b_at[1]), get(b_at[2])};
    if (has_emit) out.exitance[f] = {get(e_at[0]), get(e_at[1]), get(e_at[2])};
    // No comparison is made with a value that is not a number or not finite.
    bool finite = std::isfinite(out.area[f]) && out.area[f] >= 0;
    for (int c = 0; c < 3; ++c) finite &= std::isfinite(out.radiosity[f][c]) && std::isfinite(out.exitance[f][c]);
    if (!finite) throw InputError(fmt::format("{}: face {} has a value that is not a finite number", path.string(), f));
  }
  return out;
}

}  // namespace mpath
