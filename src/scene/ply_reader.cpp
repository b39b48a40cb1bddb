// PLY reader (ASCII and binary of either byte order). Vertices need x, y, z;
// faces a vertex_indices list. Optional float face properties rho_r/g/b (or
// red/green/blue, 0-255 when integer), emit_r/g/b (self-emitted exitance, W/m2,
// as mpath writes them), int `object` and `two_sided`. Without `object`, each
// connected component is one object.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <numeric>
#include <sstream>

#include "error.h"
#include "scene_readers.h"
#include "text_tokenizer.h"

namespace mpath {

size_t ply_type_size(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

namespace {

namespace fs = std::filesystem;

enum class Format { ascii, binary_le, binary_be };

struct Property {
  std::string name;
  std::string type;        // scalar type, or the item type of a list
  std::string count_type;  // non-empty for lists
};

struct Element {
  std::string name;
  size_t count = 0;
  std::vector<Property> properties;
};

bool is_integer_type(const std::string& t) { return t != "float" && t != "float32" && t != "double" && t != "float64"; }

// Where in the data a value is, put into words only for an error message.
struct Where {
  const std::string& element;
  size_t item, count;
};
std::string format_as(const Where& w) { return fmt::format("element '{}' item {} of {}", w.element, w.item, w.count); }

// Reads scalar values of the element data, ASCII or binary.
class ValueSource {
 public:
  ValueSource(std::istream& in, Format format, std::string path) : in_(in), format_(format), path_(std::move(path)) {}

  double read(const std::string& type, const Where& where) {
    if (format_ == Format::ascii) return read_ascii(where);
    unsigned char bytes[8];
    const size_t n = ply_type_size(type);
    if (!in_.read(reinterpret_cast<char*>(bytes), static_cast<std::streamsize>(n)))
      throw InputError(fmt::format("{}: unexpected end of file in {}", path_, format_as(where)));
    const bool swap = (format_ == Format::binary_be) == (std::endian::native == std::endian::little);
    if (swap) std::reverse(bytes, bytes + n);
    return decode(bytes, type);
  }

 private:
  static double decode(const unsigned char* b, const std::string& t) {
    if (t == "char" || t == "int8") return static_cast<int8_t>(b[0]);
    if (t == "uchar" || t == "uint8") return b[0];
    if (t == "short" || t == "int16") { int16_t v; std::memcpy(&v, b, 2); return v; }
    if (t == "ushort" || t == "uint16") { uint16_t v; std::memcpy(&v, b, 2); return v; }
    if (t == "int" || t == "int32") { int32_t v; std::memcpy(&v, b, 4); return v; }
    if (t == "uint" || t == "uint32") { uint32_t v; std::memcpy(&v, b, 4); return v; }
    if (t == "float" || t == "float32") { float v; std::memcpy(&v, b, 4); return v; }
    double v; std::memcpy(&v, b, 8); return v;
  }

  double read_ascii(const Where& where) {
    std::string token;
    if (!(in_ >> token)) throw InputError(fmt::format("{}: unexpected end of file in {}", path_, format_as(where)));
    std::istringstream s(token);
    double v;
    if (!(s >> v) || !s.eof())
      throw InputError(fmt::format("{}: expected a number in {}, got '{}'", path_, format_as(where), token));
    return v;
  }

  std::istream& in_;
  Format format_;
  std::string path_;
};

struct Header {
  Format format = Format::ascii;
  std::vector<Element> elements;
};

constexpr long long kMaxPlyItems = 2'000'000'000;

Header read_header(std::istream& in, const std::string& path) {
  Header h;
  std::string line;
  long line_no = 0;
  auto fail = [&](const std::string& msg) -> InputError { return file_error(path, line_no, msg); };
  if (!std::getline(in, line) || line.rfind("ply", 0) != 0) throw file_error(path, 1, "not a PLY file (expected 'ply')");
  ++line_no;
  bool have_format = false;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream s(line);
    std::string key;
    s >> key;
    if (key == "format") {
      std::string f, version;
      s >> f >> version;
      if (f == "ascii") h.format = Format::ascii;
      else if (f == "binary_little_endian") h.format = Format::binary_le;
      else if (f == "binary_big_endian") h.format = Format::binary_be;
      else throw fail(fmt::format("unknown PLY format '{}'", f));
      have_format = true;
    } else if (key == "element") {
      Element e;
      std::string count;
      s >> e.name >> count;
      size_t used = 0;
      long long n = -1;
      try {
        n = std::stoll(count, &used);
      } catch (const std::exception&) {
      }
      if (e.name.empty() || used != count.size() || n < 0)
        throw fail("malformed 'element': expected 'element name count'");
      if (n > kMaxPlyItems)
        throw fail(fmt::format("element '{}' has {} items; mpath reads at most {}", e.name, n, kMaxPlyItems));
      e.count = static_cast<size_t>(n);
      h.elements.push_back(e);
    } else if (key == "property") {
      if (h.elements.empty()) throw fail("'property' before any 'element'");
      Property p;
      std::string type;
      s >> type;
      if (type == "list") s >> p.count_type >> p.type >> p.name;
      else { p.type = type; s >> p.name; }
      if (p.name.empty() || ply_type_size(p.type) == 0 || (!p.count_type.empty() && ply_type_size(p.count_type) == 0))
        throw fail(fmt::format("malformed property '{}'", line));
      h.elements.back().properties.push_back(p);
    } else if (key == "end_header") {
      if (!have_format) throw fail("missing 'format' line");
      return h;
    } else if (key != "comment" && key != "obj_info" && !key.empty()) {
      throw fail(fmt::format("unknown PLY header line '{}'", key));
    }
  }
  throw file_error(path, line_no, "missing 'end_header'");
}

struct Faces {
  std::vector<std::vector<uint32_t>> indices;
  std::vector<Rgb> rho, emit;
  std::vector<int> object, two_sided;
  bool has_rho = false, has_emit = false, has_object = false, has_two_sided = false;
};

int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// Objects from connected components of faces sharing vertices.
std::vector<int> connected_components(const Faces& faces, size_t vertex_count) {
  std::vector<int> parent(vertex_count);
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& f : faces.indices)
    for (size_t i = 1; i < f.size(); ++i) parent[find_root(parent, f[i])] = find_root(parent, f[0]);
  std::map<int, int> component;
  std::vector<int> object(faces.indices.size());
  for (size_t i = 0; i < faces.indices.size(); ++i) {
    const int root = find_root(parent, faces.indices[i][0]);
    object[i] = component.emplace(root, static_cast<int>(component.size())).first->second;
  }
  return object;
}

}  // namespace

Scene read_ply(const fs::path& path) {
  require_scene_file(path);
  std::ifstream in(path, std::ios::binary);
  const std::string name = path.string();
  const Header header = read_header(in, name);
  ValueSource values(in, header.format, name);
  // Every item of an element with properties takes at least a byte: a count
  // beyond the file's size is a damaged header, not minutes of work.
  std::error_code ec;
  const auto file_bytes = std::filesystem::file_size(path, ec);
  for (const Element& e : header.elements)
    if (!e.properties.empty() && !ec && e.count > file_bytes)
      throw InputError(fmt::format("{}: element '{}' claims {} items, more than the file's {} bytes hold", name, e.name,
                                   e.count, file_bytes));

  std::vector<Vec3> vertices;
  Faces faces;
  for (const Element& e : header.elements) {
    if (e.properties.empty()) continue;  // nothing to read, however many
    // rho_r/g/b name the reflectance where they are (red/green/blue beside
    // them are display colours, as in mpath's own solution.ply).
    const bool rho_named = std::any_of(e.properties.begin(), e.properties.end(),
                                       [](const Property& p) { return p.name.rfind("rho_", 0) == 0; });
    for (size_t item = 0; item < e.count; ++item) {
      const Where context{e.name, item, e.count};
      Vec3 p;
      std::vector<uint32_t> list;
      Rgb rho{0.5, 0.5, 0.5}, emit{0, 0, 0};
      int object = 0, two_sided = 0;
      for (const Property& prop : e.properties) {
        if (!prop.count_type.empty()) {
          const double n = values.read(prop.count_type, context);
          if (!(n >= 0 && n <= 1e6) || n != std::floor(n))
            throw InputError(fmt::format("{}: bad list length {} in {}", name, n, format_as(context)));
          for (int k = 0; k < static_cast<int>(n); ++k) {
            const double v = values.read(prop.type, context);
            if (e.name == "face" && (prop.name == "vertex_indices" || prop.name == "vertex_index")) {
              if (!(v >= 0 && v < static_cast<double>(vertices.size())) || v != std::floor(v))
                throw InputError(fmt::format("{}: vertex index {} out of range in {}", name, v, format_as(context)));
              list.push_back(static_cast<uint32_t>(v));
            }
          }
          continue;
        }
        double v = values.read(prop.type, context);
        if (!std::isfinite(v)) throw InputError(fmt::format("{}: non-finite value for '{}' in {}", name, prop.name, format_as(context)));
        if (e.name == "vertex") {
          if (prop.name == "x") p.x = v;
          else if (prop.name == "y") p.y = v;
          else if (prop.name == "z") p.z = v;
        } else if (e.name == "face") {
          static const std::map<std::string, int> channel = {{"rho_r", 0}, {"rho_g", 1}, {"rho_b", 2},
                                                             {"red", 0},   {"green", 1}, {"blue", 2}};
          if (auto it = channel.find(prop.name); it != channel.end()) {
            if (rho_named && prop.name.rfind("rho_", 0) != 0) continue;
            rho[it->second] = is_integer_type(prop.type) ? v / 255.0 : v;
            faces.has_rho = true;
          } else if (prop.name == "emit_r" || prop.name == "emit_g" || prop.name == "emit_b") {
            emit[prop.name.back() == 'r' ? 0 : (prop.name.back() == 'g' ? 1 : 2)] = v / std::numbers::pi;
            faces.has_emit = true;
          } else if (prop.name == "object") {
            if (!(v >= 0 && v <= 1e9) || v != std::floor(v))
              throw InputError(fmt::format("{}: object id {} is not a whole number in [0, 1e9] in {}", name, v, format_as(context)));
            object = static_cast<int>(v);
            faces.has_object = true;
          } else if (prop.name == "two_sided") {
            two_sided = v != 0;
            faces.has_two_sided = true;
          }
        }
      }
      if (e.name == "vertex") vertices.push_back(p);
      if (e.name == "face") {
        if (list.size() < 3) throw InputError(fmt::format("{}: face with fewer than 3 vertices in {}", name, format_as(context)));
        faces.indices.push_back(std::move(list));
        faces.rho.push_back(rho);
        faces.emit.push_back(emit);
        faces.object.push_back(object);
        faces.two_sided.push_back(two_sided);
      }
    }
  }

  Scene scene;
  scene.file = path;
  const std::vector<int> objects = faces.has_object ? faces.object : connected_components(faces, vertices.size());
  std::map<int, int> object_index;
  std::map<std::tuple<Rgb, Rgb, int>, int> material_index;
  for (size_t i = 0; i < faces.indices.size(); ++i) {
    Polygon poly;
    for (uint32_t v : faces.indices[i]) poly.vertices.push_back(vertices[v]);
    auto [oit, new_object] = object_index.emplace(objects[i], static_cast<int>(scene.objects.size()));
    if (new_object) scene.objects.push_back({fmt::format("object{}", objects[i])});
    poly.object = oit->second;
    const auto key = std::make_tuple(faces.rho[i], faces.emit[i], faces.two_sided[i]);
    auto [mit, new_material] = material_index.emplace(key, static_cast<int>(scene.materials.size()));
    if (new_material) {
      Material m{fmt::format("ply{}", scene.materials.size()), faces.rho[i], faces.emit[i], faces.two_sided[i] != 0};
      if (!faces.has_rho && !faces.has_emit) m.name = "default";
      validate_material(m, fmt::format("{}: face {}", name, i));
      scene.materials.push_back(m);
    }
    poly.material = mit->second;
    scene.polygons.push_back(std::move(poly));
  }
  return scene;
}

}  // namespace mpath
