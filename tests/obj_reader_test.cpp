#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "coplanar_overlap.h"
#include "error.h"
#include "scene_readers.h"
#include "test_util.h"

namespace mpath {
namespace {

using test::TempDir;
using test::write_file;

const char* kMtl = "newmtl wall\nKd 0.5 0.6 0.7\nnewmtl lamp\nKd 0.8\nKe 10 10 5\n";

std::string obj_error(const std::string& obj, const std::string& mtl = kMtl) {
  TempDir dir;
  write_file(dir / "s.mtl", mtl);
  write_file(dir / "s.obj", obj);
  try {
    read_obj(dir / "s.obj");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ObjReader, ReadsMaterialsObjectsAndFaces) {
  TempDir dir;
  write_file(dir / "s.mtl", kMtl);
  write_file(dir / "s.obj", R"(mtllib s.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vn 0 0 1
o floor
usemtl wall
f 1/1/1 2/1/1 3/1/1 4/1/1
g lamp_group
usemtl lamp
f -4 -3 -2
f 1//1 3//1 4//1
)");
  const Scene s = read_obj(dir / "s.obj");
  ASSERT_EQ(s.polygons.size(), 3u);
  ASSERT_EQ(s.objects.size(), 2u);
  EXPECT_EQ(s.objects[0].name, "floor");
  EXPECT_EQ(s.objects[1].name, "lamp_group");
  EXPECT_EQ(s.polygons[0].vertices.size(), 4u);
  EXPECT_EQ(s.polygons[1].vertices[2], (Vec3{1, 1, 0}));
  const Material& wall = s.materials[s.polygons[0].material];
  EXPECT_EQ(wall.rho, (Rgb{0.5, 0.6, 0.7}));
  const Material& lamp = s.materials[s.polygons[1].material];
  EXPECT_EQ(lamp.rho, (Rgb{0.8, 0.8, 0.8}));
  EXPECT_EQ(lamp.emission, (Rgb{10, 10, 5}));
  EXPECT_EQ(s.polygons[2].object, 1);
}

TEST(ObjReader, NamesFileLineAndCauseOfBadInput) {
  const std::string head = "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n";
  std::string e = obj_error("v 0 nan 0\n");
  EXPECT_NE(e.find("s.obj:1: expected a finite number for y, got 'nan'"), std::string::npos) << e;
  e = obj_error(head + "f 1 2\n");
  EXPECT_NE(e.find("s.obj:5: malformed 'f'"), std::string::npos) << e;
  e = obj_error(head + "f 1 2 9\n");
  EXPECT_NE(e.find("s.obj:5: face vertex index 9 is out of range"), std::string::npos) << e;
  e = obj_error("v 1 2 x\n");
  EXPECT_NE(e.find("expected a number for z, got 'x'"), std::string::npos) << e;
  e = obj_error(head, "newmtl glow\nKd 1.2 0.5 0.5\n");
  EXPECT_NE(e.find("reflectance 1.2 is outside [0, 1]"), std::string::npos) << e;
}

// What exporters write beyond mpath's needs loads with warnings: unknown
// statements (counted, named once), lines and points, a missing material
// library or material (grey under its own name), transparency.
TEST(ObjReader, ReadsWhatExportersWriteWithWarnings) {
  TempDir dir;
  write_file(dir / "s.mtl", "newmtl glass\nKd 0.5 0.5 0.5\nd 0.3\nillum 2\nnewmtl solid\nKd 0.2 0.2 0.2\nd 1.0\n");
  write_file(dir / "s.obj", "mtllib s.mtl missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n"
                            "cstype bezier\ncstype bezier\nusemtl glass\nf 1/1/1 2/1/1 3/1/1\nl 1 2\np 3\n"
                            "usemtl solid\nf -3 -2 -1\nusemtl wood\nf 1 2 3\n");
  std::vector<std::string> warnings;
  const Scene s = read_obj(dir / "s.obj", &warnings);
  std::string all;
  for (const auto& w : warnings) all += w + "\n";
  ASSERT_EQ(s.polygons.size(), 3u);
  EXPECT_NE(all.find("material library '" + (dir / "missing.mtl").string() + "' not found"), std::string::npos) << all;
  EXPECT_NE(all.find("statement 'cstype' not read, 2 line(s) skipped, the first at "), std::string::npos) << all;
  EXPECT_NE(all.find("2 line and point element(s) (l, p) ignored"), std::string::npos) << all;
  EXPECT_NE(all.find("material 'glass' is partly transparent (d 0.3)"), std::string::npos) << all;
  EXPECT_EQ(all.find("'solid' is partly"), std::string::npos) << all;
  EXPECT_NE(all.find("s.obj:15: material 'wood' is in no mtllib read so far: grey 0.5"), std::string::npos) << all;
  EXPECT_EQ(s.materials[s.polygons[2].material].name, "wood");
  EXPECT_EQ(s.materials[s.polygons[2].material].rho, (Rgb{0.5, 0.5, 0.5}));
}

TEST(SceneLoader, AppliesConfigEmittersAndTwoSidedMaterialsByName) {
  TempDir dir;
  write_file(dir / "s.mtl", kMtl);
  write_file(dir / "s.obj", "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl wall\nf 1 2 3\n");
  SceneOptions o;
  o.file = dir / "s.obj";
  o.emitters["wall"] = {1, 2, 3};
  o.two_sided = {"wall"};
  std::vector<std::string> warnings;
  const Scene s = load_scene(o, 16, warnings);
  const Material& wall = s.materials[s.find_material("wall")];
  EXPECT_EQ(wall.emission, (Rgb{1, 2, 3}));
  EXPECT_TRUE(wall.two_sided);
  o.emitters["ghost"] = {1, 1, 1};
  try {
    load_scene(o, 16, warnings);
    FAIL() << "an unknown material in scene.emitters must be an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'scene.emitters.ghost': unknown material 'ghost'"), std::string::npos) << e.what();
  }
}

// load_scene on an OBJ scene (its statements after the material's) whose material "light" emits.
Scene load_lit_obj(const std::string& obj, std::vector<std::string>& warnings) {
  TempDir dir;
  write_file(dir / "d.mtl", "newmtl light\nKd 0.5 0.5 0.5\n");
  write_file(dir / "d.obj", "mtllib d.mtl\nusemtl light\n" + obj);
  SceneOptions o;
  o.file = dir / "d.obj";
  o.emitters["light"] = {1, 1, 1};
  return load_scene(o, 16, warnings);
}

// The warnings load_scene gives for such a scene.
std::vector<std::string> loader_warnings(const std::string& obj) {
  std::vector<std::string> w;
  load_lit_obj(obj, w);
  return w;
}

// A polygon given twice facing the same way is one surface: the repeat is
// dropped, with a warning; given the other way round it is kept back to
// back, with a warning of its own.
TEST(SceneLoader, DropsRepeatedPolygonsAndWarnsOfReversedOnes) {
  std::vector<std::string> w;
  const Scene s = load_lit_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n"
                               "f 1 2 3 4\nf 4 3 2 1\nf 2 3 4 1\nf 1 2 5\nf 3 4 1 2\n", w);
  EXPECT_EQ(s.polygons.size(), 3u);  // the square, its reverse and the triangle
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w[0].find("2 polygon(s) repeat an earlier one facing the same way"), 0u) << w[0];
  EXPECT_EQ(w[1].find("1 polygon(s) have the same vertices as another facing the other way"), 0u) << w[1];
}

// Random files (many seeds) of triangles and quads, some given again with
// their corners rotated (the same surface) or reversed (its back), in any
// order: what load_scene keeps, and its counts, match a pairwise check of
// every polygon against the ones kept before it.
TEST(SceneLoader, RepeatedPolygonsInRandomFilesMatchAPairwiseCheck) {
  for (unsigned seed = 1; seed <= 25; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> coord(0.0, 4.0);
    std::vector<std::vector<int>> faces;  // 1-based vertex indices, in file order
    std::vector<Vec3> position;           // the file's vertices, to name the kept corners
    std::string obj;
    const int distinct = 20 + static_cast<int>(seed % 7) * 10;
    for (int i = 0; i < distinct; ++i) {
      const int corners = 3 + static_cast<int>(rng() % 2);
      std::vector<int> f;
      // A quad's corners on one plane (a parallelogram), a triangle's anywhere.
      const Vec3 a{coord(rng), coord(rng), coord(rng)}, b{coord(rng), coord(rng), coord(rng)},
          c{coord(rng), coord(rng), coord(rng)};
      std::vector<Vec3> corner = {a, b, c};
      if (corners == 4) corner = {a, b, b + (c - a), c};
      for (const Vec3& v : corner) {
        obj += fmt::format("v {:.17g} {:.17g} {:.17g}\n", v.x, v.y, v.z);
        position.push_back(v);
        f.push_back(static_cast<int>(position.size()));
      }
      faces.push_back(f);
    }
    const int repeats = 10 + static_cast<int>(rng() % 20);
    for (int r = 0; r < repeats; ++r) {
      std::vector<int> f = faces[rng() % faces.size()];  // possibly itself a repeat
      std::rotate(f.begin(), f.begin() + static_cast<long>(rng() % f.size()), f.end());
      if (rng() % 2) std::reverse(f.begin(), f.end());
      faces.insert(faces.begin() + static_cast<long>(rng() % (faces.size() + 1)), f);
    }
    for (const auto& f : faces) {
      obj += "f";
      for (int v : f) obj += fmt::format(" {}", v);
      obj += "\n";
    }
    // The pairwise check, on vertex indices: the same set of corners is the
    // same polygon; the same cyclic order (either way round) says which side.
    auto same_set = [](std::vector<int> x, std::vector<int> y) {
      std::sort(x.begin(), x.end());
      std::sort(y.begin(), y.end());
      return x == y;
    };
    auto same_way = [](const std::vector<int>& x, const std::vector<int>& y) {
      const size_t at = static_cast<size_t>(std::find(y.begin(), y.end(), x[0]) - y.begin());
      return y[(at + 1) % y.size()] == x[1];
    };
    std::vector<std::vector<int>> kept;
    size_t dropped = 0, reversed = 0;
    for (const auto& f : faces) {
      bool duplicate = false, back = false;
      for (const auto& k : kept)
        if (same_set(f, k)) (same_way(f, k) ? duplicate : back) = true;
      if (duplicate) {
        ++dropped;
        continue;
      }
      if (back) ++reversed;
      kept.push_back(f);
    }
    ASSERT_GT(dropped + reversed, 0u) << "seed " << seed;

    std::vector<std::string> w;
    const Scene s = load_lit_obj(obj, w);
    ASSERT_EQ(s.polygons.size(), kept.size()) << "seed " << seed;
    for (size_t i = 0; i < kept.size(); ++i) {  // in file order, with the corners as given
      ASSERT_EQ(s.polygons[i].vertices.size(), kept[i].size()) << "seed " << seed << ", polygon " << i;
      for (size_t k = 0; k < kept[i].size(); ++k)
        EXPECT_EQ(length(s.polygons[i].vertices[k] - position[static_cast<size_t>(kept[i][k] - 1)]), 0.0)
            << "seed " << seed << ", polygon " << i;
    }
    const auto warned = [&](const std::string& start) {
      for (const auto& m : w)
        if (m.find(start) != std::string::npos) return std::stoul(m);
      return 0ul;
    };
    EXPECT_EQ(warned("polygon(s) repeat an earlier one facing the same way"), dropped) << "seed " << seed;
    EXPECT_EQ(warned("polygon(s) have the same vertices as another facing the other way"), reversed)
        << "seed " << seed;
  }
}

// Coplanar polygons facing the same way that share area are found; tiles
// side by side, back-to-back faces, parallel faces a centimetre apart and
// exact duplicates (warned of on their own) are not.
TEST(SceneLoader, FindsCoplanarOverlapsAndNothingElse) {
  auto square = [](Scene& s, double x, double y, double w, double z = 0, bool down = false) {
    const Vec3 a{x, y, z}, b{x + w, y, z}, c{x + w, y + w, z}, d{x, y + w, z};
    if (down) test::add_quad(s, d, c, b, a, 0, 0);
    else test::add_quad(s, a, b, c, d, 0, 0);
  };
  auto found = [](const Scene& s) { return find_coplanar_overlaps(s).polygons; };
  auto scene = [] {
    Scene s;
    test::add_material(s, "m", 0.5, 0);
    test::add_object(s, "o");
    return s;
  };
  Scene s = scene();
  square(s, 0, 0, 1);
  square(s, 0.5, 0.5, 1);  // overlaps a quarter
  EXPECT_EQ(found(s), 2u);
  s = scene();
  square(s, 0, 0, 1);
  square(s, 0.25, 0.25, 0.5);  // a decal inside
  EXPECT_EQ(found(s), 2u);
  s = scene();
  square(s, 0, 0, 1);
  s.polygons.push_back(Polygon{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}, 0, 0});  // half of it, corners on its corners
  EXPECT_EQ(found(s), 2u);
  s = scene();
  square(s, 0, 0, 1);
  square(s, 1, 0, 1);         // side by side
  square(s, 0, 1, 1);         // side by side
  square(s, 3, 0, 1);         // apart
  square(s, 0, 0, 1, 0, true);  // back to back with the first
  square(s, 0, 0, 1, 0.01);   // a centimetre above
  square(s, 3, 0, 1);         // an exact duplicate
  EXPECT_EQ(found(s), 0u);
  // Random tilings (many seeds): tiles of a grid never overlap; one tile
  // moved by a random fraction of its size overlaps its neighbours.
  for (unsigned seed = 1; seed <= 20; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> shift(0.05, 0.95);
    s = scene();
    const int n = 4 + static_cast<int>(seed % 5);
    const double w = 0.3 + 0.1 * (seed % 3), z = 0.7 * seed;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) square(s, i * w, j * w, w, z);
    EXPECT_EQ(found(s), 0u) << "seed " << seed;
    square(s, shift(rng) * w, shift(rng) * w, w, z);
    const CoplanarOverlaps o = find_coplanar_overlaps(s);
    EXPECT_GE(o.polygons, 2u) << "seed " << seed;
    EXPECT_EQ(o.second, n * n) << "seed " << seed;  // the moved tile is in the first pair
  }
}

// load_scene names the first overlapping pair in its warning.
TEST(SceneLoader, WarnsOfCoplanarOverlaps) {
  const auto w = loader_warnings("o wall\nv 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nf 1 2 3 4\n"
                                 "o poster\nv 0.5 0.5 0\nv 1 0.5 0\nv 1 1 0\nv 0.5 1 0\nf 5 6 7 8\n");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("2 polygon(s) overlap a coplanar polygon facing the same way (first: polygon 1 of object "
                      "'wall' and polygon 2 of object 'poster')"), std::string::npos) << w[0];
}

TEST(SceneLoader, RejectsUnknownFormatsMissingFilesAndDarkScenes) {
  TempDir dir;
  SceneOptions o;
  o.file = dir / "s.xyz";
  std::vector<std::string> w;
  write_file(o.file, "x");
  EXPECT_THROW(load_scene(o, 16, w), InputError);
  o.file = dir / "absent.obj";
  try {
    load_scene(o, 16, w);
    FAIL() << "a missing scene file must be an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("absent.obj: file not found"), std::string::npos);
  }
  write_file(dir / "dark.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  o.file = dir / "dark.obj";
  try {
    load_scene(o, 16, w);
    FAIL() << "a scene without emitters must be an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no emitting polygon"), std::string::npos);
  }
}

std::string load_error(const std::filesystem::path& file) {
  SceneOptions o;
  o.file = file;
  o.emitters["light"] = {1, 1, 1};
  std::vector<std::string> w;
  try {
    load_scene(o, 16, w);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// A device or a pipe named as the scene is refused at once (reading
// /dev/zero would never end), and scenes beyond what single-precision
// tracing resolves are refused with the reason.
TEST(SceneLoader, RefusesDevicesPipesAndScenesFloatsCannotResolve) {
  TempDir dir;
  std::filesystem::create_symlink("/dev/zero", dir / "zero.obj");
  EXPECT_NE(load_error(dir / "zero.obj").find("not a regular file"), std::string::npos);
  ASSERT_EQ(test::run("mkfifo " + (dir / "pipe.mgf").string()).exit_code, 0);
  EXPECT_NE(load_error(dir / "pipe.mgf").find("not a regular file"), std::string::npos);
  const auto scene = [&](const std::string& name, double scale) {
    write_file(dir / (name + ".mtl"), "newmtl light\nKd 0.5 0.5 0.5\n");
    write_file(dir / (name + ".obj"), fmt::format("mtllib {}.mtl\nusemtl light\nv 0 0 0\nv {} 0 0\nv 0 {} 0\nf 1 2 3\n",
                                                   name, scale, scale));
    return dir / (name + ".obj");
  };
  EXPECT_EQ(load_error(scene("metre", 1.0)), "");
  // A polygon of 20,000 vertices (a circle) is refused, not triangulated for minutes.
  std::string circle = "mtllib metre.mtl\nusemtl light\n", face = "f";
  for (int k = 0; k < 20000; ++k) {
    circle += fmt::format("v {} {} 0\n", std::cos(k * 2 * M_PI / 20000), std::sin(k * 2 * M_PI / 20000));
    face += fmt::format(" {}", k + 1);
  }
  write_file(dir / "circle.obj", circle + face + "\n");
  EXPECT_NE(load_error(dir / "circle.obj").find("polygon 1 has 20000 vertices; mpath takes at most 10000"),
            std::string::npos);
  EXPECT_NE(load_error(scene("huge", 1e18)).find("beyond 10000000 m, more than single-precision tracing can resolve"),
            std::string::npos);
  EXPECT_NE(load_error(scene("tiny", 1e-9)).find("mpath solves scenes from 1e-05 m to 10000000 m across"),
            std::string::npos);
}

}  // namespace
}  // namespace mpath
