// Wavefront OBJ + MTL reader: Kd is the diffuse reflectance, Ke the emitted
// radiance (W/sr/m2). Each `o` or `g` starts a new object.
#include <map>

#include "error.h"
#include "text_tokenizer.h"
#include "scene_readers.h"

namespace mpath {
namespace {

namespace fs = std::filesystem;

Rgb read_rgb(const TextTokenizer& in, const std::vector<std::string_view>& t) {
  in.expect_count(t, 1, 3, fmt::format("'{} r [g b]'", t[0]));
  const double r = in.number(t[1], t[0]);
  if (t.size() == 2) return {r, r, r};
  if (t.size() != 4) in.fail(fmt::format("malformed '{}': expected 1 or 3 numbers", t[0]));
  return {r, in.number(t[2], t[0]), in.number(t[3], t[0])};
}

void read_mtl(const fs::path& path, Scene& scene, std::map<std::string, std::string>& defined_at,
              std::map<std::string, std::string>& see_through) {
  TextTokenizer in(path);
  std::vector<std::string_view> t;
  Material* current = nullptr;
  auto finish = [&] {
    if (current) validate_material(*current, defined_at[current->name]);
  };
  while (in.next(t)) {
    if (t[0] == "newmtl") {
      in.expect_count(t, 1, 1, "'newmtl name'");
      finish();
      const std::string name(t[1]);
      int index = scene.find_material(name);
      if (index < 0) {
        scene.materials.push_back(Material{name, {0.5, 0.5, 0.5}, {0, 0, 0}, false});
        index = static_cast<int>(scene.materials.size()) - 1;
      }
      current = &scene.materials[index];
      defined_at[name] = in.where();
    } else if (t[0] == "Kd" || t[0] == "Ke") {
      if (!current) in.fail(fmt::format("'{}' before any 'newmtl'", t[0]));
      (t[0] == "Kd" ? current->rho : current->emission) = read_rgb(in, t);
    } else if ((t[0] == "d" || t[0] == "Tr") && current && t.size() >= 2) {
      // Dissolve (d) and its complement Tr: mpath's surfaces are opaque.
      const double d = in.number(t[1], t[0]);
      if (t[0] == "d" ? d < 1 : d > 0) see_through[current->name] = fmt::format("{} {}", t[0], t[1]);
    }
    // Other MTL statements (Ka, Ks, Ns, maps, illum) do not affect diffuse radiosity.
  }
  finish();
}

// Resolves an OBJ vertex reference "i", "i/t", "i//n" or "i/t/n" (negative: relative).
size_t vertex_index(const TextTokenizer& in, std::string_view token, size_t vertex_count) {
  const std::string_view head = token.substr(0, token.find('/'));
  const long long i = in.integer(head, "a face vertex index");
  const long long resolved = i < 0 ? static_cast<long long>(vertex_count) + i : i - 1;
  if (i == 0 || resolved < 0 || resolved >= static_cast<long long>(vertex_count))
    in.fail(fmt::format("face vertex index {} is out of range (1..{} defined so far)", i, vertex_count));
  return static_cast<size_t>(resolved);
}

}  // namespace

Scene read_obj(const fs::path& path, std::vector<std::string>* warnings) {
  Scene scene;
  scene.file = path;
  TextTokenizer in(path);
  std::vector<std::string_view> t;
  std::vector<Vec3> positions;
  std::map<std::string, std::string> defined_at, see_through;
  std::map<std::string, std::pair<size_t, std::string>> unknown;  // statement: count, first place
  std::vector<std::string> notes;
  size_t lines_points = 0;
  int material = -1;
  int object = -1;
  std::string pending_object = path.stem().string();

  while (in.next(t)) {
    const std::string_view key = t[0];
    if (key == "v") {
      if (t.size() < 4) in.fail("malformed 'v': expected 'v x y z'");
      positions.push_back({in.number(t[1], "x"), in.number(t[2], "y"), in.number(t[3], "z")});
    } else if (key == "f") {
      if (t.size() < 4) in.fail("malformed 'f': expected at least 3 vertices");
      if (material < 0) {
        // Faces before any usemtl get a neutral grey material, as most viewers show them.
        material = scene.find_material("default");
        if (material < 0) {
          scene.materials.push_back(Material{"default", {0.5, 0.5, 0.5}, {0, 0, 0}, false});
          material = static_cast<int>(scene.materials.size()) - 1;
        }
      }
      if (object < 0) {
        scene.objects.push_back({pending_object});
        object = static_cast<int>(scene.objects.size()) - 1;
      }
      Polygon poly;
      poly.material = material;
      poly.object = object;
      for (size_t i = 1; i < t.size(); ++i) poly.vertices.push_back(positions[vertex_index(in, t[i], positions.size())]);
      scene.polygons.push_back(std::move(poly));
    } else if (key == "o" || key == "g") {
      pending_object = t.size() > 1 ? std::string(t[1]) : fmt::format("object{}", scene.objects.size());
      object = -1;
    } else if (key == "usemtl") {
      in.expect_count(t, 1, 1, "'usemtl name'");
      const std::string name(t[1]);
      material = scene.find_material(name);
      if (material < 0) {
        // As viewers do: grey, under its own name (so that scene.emitters can light it).
        notes.push_back(fmt::format("{}: material '{}' is in no mtllib read so far: grey 0.5", in.where(), name));
        scene.materials.push_back(Material{name, {0.5, 0.5, 0.5}, {0, 0, 0}, false});
        material = static_cast<int>(scene.materials.size()) - 1;
      }
    } else if (key == "mtllib") {
      in.expect_count(t, 1, 64, "'mtllib file ...'");
      for (size_t i = 1; i < t.size(); ++i) {
        const fs::path mtl = path.parent_path() / std::string(t[i]);
        std::error_code ec;  // a name the file system refuses (too long, ...) is not found either
        if (!fs::exists(mtl, ec)) notes.push_back(fmt::format("{}: material library '{}' not found", in.where(), mtl.string()));
        else read_mtl(mtl, scene, defined_at, see_through);
      }
    } else if (key == "l" || key == "p") {
      ++lines_points;  // lines and points have no area
    } else if (key == "vn" || key == "vt" || key == "vp" || key == "s") {
      // Normals, texture coordinates and smoothing groups carry no radiosity.
    } else {
      auto& [count, first] = unknown[std::string(key.substr(0, 40))];
      if (count++ == 0) first = in.where();
    }
  }
  if (warnings) {
    for (const auto& n : notes) warnings->push_back(n);
    for (const auto& [key, seen] : unknown)
      warnings->push_back(fmt::format("OBJ: statement '{}' not read, {} line(s) skipped, the first at {}", key,
                                      seen.first, seen.second));
    if (lines_points > 0)
      warnings->push_back(fmt::format("OBJ: {} line and point element(s) (l, p) ignored: they have no area", lines_points));
    for (const auto& [name, what] : see_through)
      warnings->push_back(fmt::format("material '{}' is partly transparent ({}): mpath makes every surface opaque",
                                      name, what));
  }
  return scene;
}

}  // namespace mpath
