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

TEST(MgfReader, NamesFileLineAndCauseOfBadInput) {
  EXPECT_NE(mgf_error("# x\nblah 1 2\n").find("e.mgf:2: unknown MGF entity 'blah'"), std::string::npos);
  EXPECT_NE(mgf_error("f a b c\n").find("e.mgf:1: undefined vertex 'a'"), std::string::npos);
  EXPECT_NE(mgf_error("xf\n").find("'xf' end without a matching"), std::string::npos);
  EXPECT_NE(mgf_error("xf -t 1 0 0\n").find("'xf' context left open"), std::string::npos);
  EXPECT_NE(mgf_error("i nowhere.mgf\n").find("included file"), std::string::npos);
  EXPECT_NE(mgf_error("m x =\nsides 3\n").find("e.mgf:2: 'sides' must be 1 or 2"), std::string::npos);
  EXPECT_NE(mgf_error("v a =\np 0 nan 0\n").find("e.mgf:2: expected a finite number"), std::string::npos);
  EXPECT_NE(mgf_error("m x =\nrd 1.5\nv a =\np 0 0 0\nv b =\np 1 0 0\nv c =\np 0 1 0\nf a b c\n").find("outside [0, 1)"),
            std::string::npos);
  EXPECT_NE(mgf_error("c x =\ncxy 0.8 0.5\n").find("outside the CIE diagram"), std::string::npos);
  EXPECT_NE(mgf_error("xf -i 1e12 -t 1 0 0\nxf\n").find("e.mgf:1: '-i 1e12': the count must be a whole number"),
            std::string::npos);
  std::string nested;
  for (int k = 0; k < 300; ++k) nested += "o level" + std::to_string(k) + "\n";
  EXPECT_NE(mgf_error(nested).find("e.mgf:257: objects nested more than 256 deep"), std::string::npos);
  // Colours that have none (found by fuzz/fuzz_mgf: an empty range divided by zero).
  EXPECT_NE(mgf_error("c x =\ncspec 400 400 1 2 3\n").find("e.mgf:2: 'cspec' range 400 to 400 nm"), std::string::npos);
  EXPECT_NE(mgf_error("c x =\ncspec 900 1000 1 2\n").find("outside the visible"), std::string::npos);
  EXPECT_NE(mgf_error("c x =\ncspec 400 700 0 0 0\n").find("'cspec' has no energy"), std::string::npos);
  EXPECT_NE(mgf_error("c x =\ncspec 400 700 1 -2\n").find("'cspec' value -2 is negative"), std::string::npos);
  EXPECT_NE(mgf_error("c x =\ncct 0\n").find("e.mgf:2: 'cct 0': a colour temperature must be"), std::string::npos);
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
