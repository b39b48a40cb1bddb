#include <gtest/gtest.h>

#include <numbers>
#include <sstream>

#include "error.h"
#include "scene_readers.h"
#include "test_util.h"

namespace mpath {
namespace {

using test::TempDir;
using test::write_file;

// Every entity mpath reads, with the polygon count each makes at 8 segments.
const char* kMain = R"(# every MGF entity mpath reads
c red =
	cxy 0.64 0.33
c spec =
	cspec 400 700 1 1 1 1
c warm =
	cct 3000
c mix =
	cmix 1 red 1 spec
m wall =
	c
	rd 0.5
m redwall = wall
	c red
	rd 0.3
m lamp =
	c warm
	rd 0.1
	ed 1790
	sides 1
m shade =
	sides 2
	rd 0.4
v a =
	p 0 0 0
	n 0 0 1
v b = a
	p 1 0 0
v c =
	p 1 1 0
v d =
	p 0 1 0
o room
	m wall
	f a b c d
	o inner
		m redwall
		xf -t 10 0 0
			f a b c
		xf
	o
	xf -a 3 -t 0 0 2
		f a b c
	xf
o
o lamps
	m lamp
	xf -mx
		f a b c
	xf
	m shade
	ring a 0 1
o
o curved
	m wall
	sph a 1
	cyl a 0.5 c
	cone a 1 b 0.5
	torus a 1 2
	prism a b c d 1
o
i part.mgf -s 2 -t 0 0 5
)";

const char* kPart = "m wall\nf a b c\n";

Scene read_test_scene(const TempDir& dir) {
  write_file(dir / "main.mgf", kMain);
  write_file(dir / "part.mgf", kPart);
  return read_mgf(dir / "main.mgf", 8, 1, nullptr);
}

TEST(MgfReader, ReadsEveryEntityWithTheExpectedCounts) {
  TempDir dir;
  const Scene s = read_test_scene(dir);
  // room 1 + inner 1 + array 3; lamps 1 + ring 8; sph 32, cyl 8, cone 8, torus 32, prism 6; include 1
  EXPECT_EQ(s.polygons.size(), 5u + 9u + 86u + 1u);
  ASSERT_EQ(s.objects.size(), 5u);
  EXPECT_EQ(s.objects[0].name, "room");
  EXPECT_EQ(s.objects[1].name, "room/inner");
  EXPECT_EQ(s.objects[4].name, "main");
  int emitting = 0;
  for (const Polygon& p : s.polygons) emitting += s.materials[p.material].emits();
  EXPECT_EQ(emitting, 1);
}

TEST(MgfReader, AppliesTransformsArraysAndIncludes) {
  TempDir dir;
  const Scene s = read_test_scene(dir);
  EXPECT_EQ(s.polygons[1].vertices[1], (Vec3{11, 0, 0}));  // xf -t 10 0 0
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(s.polygons[2 + k].vertices[2].z, 2.0 * k, 1e-12);  // -a 3 -t 0 0 2
  const Polygon& mirrored = s.polygons[5];
  EXPECT_NEAR(mirrored.vertices[1].x, -1.0, 1e-12);
  EXPECT_GT(newell_normal(mirrored.vertices).z, 0);  // a mirror keeps faces facing their way
  const Polygon& included = s.polygons.back();
  EXPECT_EQ(included.vertices[0], (Vec3{0, 0, 5}));
  EXPECT_EQ(included.vertices[2], (Vec3{2, 2, 5}));
  EXPECT_EQ(included.object, 4);
}

// An include takes arrays as 'xf' does: the file is read once per element
// (RenderPark's hospital places its lamps so), last array fastest.
TEST(MgfReader, IncludesArraysOfAFile) {
  TempDir dir;
  write_file(dir / "part.mgf", "m lamp =\n\tc\n\ted 100\nv a =\n\tp 0 0 0\nv b =\n\tp 1 0 0\nv c =\n\tp 1 1 0\n"
                               "v d =\n\tp 0 1 0\nf a b c d\n");
  write_file(dir / "main.mgf", "i part.mgf -s 0.5 -a 2 -t 0 3 0 -a 3 -t 5 0 0\n");
  std::vector<std::string> warnings;
  const Scene s = read_mgf(dir / "main.mgf", 16, 2, &warnings);
  EXPECT_TRUE(warnings.empty()) << warnings.front();
  ASSERT_EQ(s.polygons.size(), 6u);
  for (int j = 0; j < 2; ++j)
    for (int k = 0; k < 3; ++k) {
      const Polygon& p = s.polygons[static_cast<size_t>(j * 3 + k)];
      EXPECT_NEAR(polygon_area(p.vertices), 0.25, 1e-12);
      EXPECT_NEAR(p.vertices[0].x, 5.0 * k, 1e-12);
      EXPECT_NEAR(p.vertices[0].y, 3.0 * j, 1e-12);
    }
}

TEST(MgfReader, ConvertsColoursReflectanceAndEmittance) {
  TempDir dir;
  const Scene s = read_test_scene(dir);
  const Material& wall = s.materials[s.polygons[0].material];
  for (double c : wall.rho) EXPECT_NEAR(c, 0.5, 1e-12);  // default colour is equal-energy white
  const Material& red = s.materials[s.polygons[1].material];
  EXPECT_GT(red.rho[0], 3 * red.rho[1]);
  const Material& lamp = s.materials[s.polygons[5].material];
  // ed 1790 lm/m2 at 179 lm/W: exitance of luminance 10 W/m2, warm white.
  EXPECT_GT(lamp.emission[0], lamp.emission[2]);
  EXPECT_NEAR(std::numbers::pi * (0.2126 * lamp.emission[0] + 0.7152 * lamp.emission[1] + 0.0722 * lamp.emission[2]), 10.0, 0.5);
  EXPECT_FALSE(lamp.two_sided);
  EXPECT_TRUE(s.materials[s.polygons[6].material].two_sided);  // the ring has sides 2
}

TEST(MgfReader, TessellatesCurvedPrimitivesFacingOutward) {
  TempDir dir;
  const Scene s = read_test_scene(dir);
  // The sphere's 32 polygons follow the lamps' 9: all face away from its centre.
  for (size_t i = 14; i < 14 + 32; ++i) {
    const auto& v = s.polygons[i].vertices;
    Vec3 centroid;
    for (const Vec3& p : v) centroid += p;
    centroid = centroid / static_cast<double>(v.size());
    EXPECT_GT(dot(newell_normal(v), centroid), 0) << "polygon " << i;
  }
}

std::string mgf_error(const std::string& text) {
  TempDir dir;
  write_file(dir / "e.mgf", text);
  try {
    read_mgf(dir / "e.mgf", 8, 1, nullptr);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Files that include the next one twice: 2^20 reads from 21 small files,
// refused once 100,000 files have been read, in well under a second.
TEST(MgfReader, BoundsIncludesThatFanOut) {
  TempDir dir;
  const int files = 21;
  for (int k = 0; k < files - 1; ++k)
    write_file(dir / fmt::format("f{}.mgf", k), fmt::format("i f{}.mgf\ni f{}.mgf\n", k + 1, k + 1));
  write_file(dir / fmt::format("f{}.mgf", files - 1), "# a leaf\n");
  try {
    read_mgf(dir / "f0.mgf", 8, 1, nullptr);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("more than 100000 files read through 'i'"), std::string::npos) << e.what();
  }
}

// What the reader skips and says (as the reference parser goes on after an
// unknown entity): the warnings, one string, empty when nothing was skipped.
std::string mgf_warnings(const std::string& text, Scene* out = nullptr) {
  TempDir dir;
  write_file(dir / "e.mgf", text);
  std::vector<std::string> warnings;
  Scene s = read_mgf(dir / "e.mgf", 8, 2, &warnings);
  if (out) *out = std::move(s);
  std::string all;
  for (const auto& w : warnings) all += w + "\n";
  return all;
}

const char* kTriangle = "v a =\np 0 0 0\nv b =\np 1 0 0\nv c =\np 0 1 0\nf a b c\n";

// Malformed lines and unknown entities are skipped with a warning naming the
// file and line, and the rest of the scene is read.
TEST(MgfReader, SkipsMalformedLinesAndUnknownEntitiesWithWarnings) {
  const auto skipped = [](const std::string& bad, const std::string& expect) {
    Scene s;
    const std::string w = mgf_warnings(bad + kTriangle, &s);
    EXPECT_NE(w.find(expect), std::string::npos) << bad << ": " << w;
    EXPECT_EQ(s.polygons.size(), 1u) << bad;
  };
  skipped("# x\nblah 1 2\n", "entity 'blah' not read, 1 line(s) skipped, the first at ");
  skipped("/usr/people27/model.rad\n", "entity '/usr/people27/model.rad' not read");
  skipped("f p q r\n", "e.mgf:1: undefined vertex 'p'");
  skipped("xf\n", "'xf' end without a matching");
  skipped("m x =\nsides 3\n", "e.mgf:2: 'sides' must be 1 or 2");
  skipped("v z =\np 0 nan 0\n", "e.mgf:2: expected a finite number");
  skipped("c x =\ncxy 0.8 0.5\n", "outside the CIE diagram");
  skipped("xf -i 1e12 -t 1 0 0\nxf\n", "e.mgf:1: '-i 1e12': the count must be a whole number");
  skipped("c x =\ncspec 400 400 1 2 3\n", "e.mgf:2: 'cspec' range 400 to 400 nm");
  skipped("c x =\ncspec 900 1000 1 2\n", "outside the visible");
  skipped("c x =\ncspec 400 700 0 0 0\n", "'cspec' has no energy");
  skipped("c x =\ncspec 400 700 1 -2\n", "'cspec' value -2 is negative");
  skipped("c x =\ncct 0\n", "e.mgf:2: 'cct 0': a colour temperature must be");
  skipped("fh a b c\n", "entity 'fh (faces with holes");
  // An entity seen many times is named once, with its count.
  std::string many;
  for (int k = 0; k < 50; ++k) many += "zz 1\n";
  const std::string w = mgf_warnings(many + kTriangle);
  EXPECT_NE(w.find("entity 'zz' not read, 50 line(s) skipped, the first at "), std::string::npos) << w;
  // (The entity quoted: the temporary file's random name may hold "zz" too.)
  EXPECT_EQ(w.find("'zz'", w.find("'zz'") + 4), std::string::npos) << w;
  // Nothing in the file is left open for the next: an unclosed xf is closed at its end.
  EXPECT_NE(mgf_warnings(std::string("xf -t 1 0 0\n") + kTriangle).find("'xf' context left open"), std::string::npos);
}

// A vertex with no `p` is at the origin (the specification's default), so
// a line `0 0 0` after `v name =` (as RenderPark's hospital has) is one
// skipped line and the vertex is still usable.
TEST(MgfReader, VertexWithoutPointIsAtTheOrigin) {
  Scene s;
  const std::string w = mgf_warnings("v o =\n0 0 0\nv b =\np 1 0 0\nv c =\np 0 1 0\nf o b c\n", &s);
  EXPECT_NE(w.find("entity '0' not read"), std::string::npos) << w;
  ASSERT_EQ(s.polygons.size(), 1u);
  EXPECT_EQ(s.polygons[0].vertices[0], (Vec3{0, 0, 0}));
}

// Reflectance 1 is allowed (a warning says a closed scene of it cannot
// converge); surfaces are two-sided unless `sides 1` says otherwise.
TEST(MgfReader, ReflectanceUpToOneAndTwoSidedByDefault) {
  Scene s;
  const std::string w = mgf_warnings(std::string("m white =\nc\nrd 1.0000\n") + kTriangle +
                                         "m one =\nsides 1\nrd 0.5\nf a b c\n", &s);
  EXPECT_NE(w.find("material 'white' reflects all the light"), std::string::npos) << w;
  ASSERT_EQ(s.polygons.size(), 2u);
  const Material& white = s.materials[s.polygons[0].material];
  for (int c = 0; c < 3; ++c) EXPECT_EQ(white.rho[c], 1.0);
  EXPECT_TRUE(white.two_sided);
  EXPECT_FALSE(s.materials[s.polygons[1].material].two_sided);
  EXPECT_NO_THROW(validate_material(white, "e.mgf"));
}

// Limits and unreadable input are errors that name the file and line.
TEST(MgfReader, RefusesWhatItCannotRead) {
  EXPECT_NE(mgf_error("i nowhere.mgf\n").find("included file"), std::string::npos);
  std::string nested;
  for (int k = 0; k < 300; ++k) nested += "o level" + std::to_string(k) + "\n";
  EXPECT_NE(mgf_error(nested).find("e.mgf:257: objects nested more than 256 deep"), std::string::npos);
  // Nested arrays of 1e5 copies each: refused at once, not run out of memory on.
  EXPECT_NE(mgf_error("v a =\np 0 0 0\nxf -a 100000 -t 1 0 0\nxf -a 100000 -t 0 1 0\nsph a 1\nxf\nxf\n")
                .find("e.mgf:4: nested 'xf -a' arrays make 1e+10 copies"),
            std::string::npos);
}

TEST(MgfReader, LoadsTheRenderParkOffice) {
  const auto path = test::shared_scene("office2/office2.mgf");
  if (path.empty()) return;
  const Scene s = read_mgf(path, 16, 1, nullptr);
  EXPECT_EQ(s.polygons.size(), 422u);
  int emitting = 0;
  for (const Polygon& p : s.polygons) emitting += s.materials[p.material].emits();
  EXPECT_EQ(emitting, 1);
  EXPECT_EQ(s.objects.size(), 67u);
  // The file has no transforms: the scene spans exactly its vertices' points.
  Bounds points;
  std::istringstream in(test::read_file(path));
  for (std::string line; std::getline(in, line);) {
    std::istringstream words(line);
    std::string key;
    Vec3 p;
    if (words >> key && key == "p" && words >> p.x >> p.y >> p.z) points.extend(p);
  }
  const Bounds b = s.bounds();
  for (int k = 0; k < 3; ++k) {
    EXPECT_DOUBLE_EQ(b.lo[k], points.lo[k]);
    EXPECT_DOUBLE_EQ(b.hi[k], points.hi[k]);
  }
}

}  // namespace
}  // namespace mpath
