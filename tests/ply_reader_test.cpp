#include <gtest/gtest.h>

#include <random>
#include <algorithm>
#include <set>

#include <cmath>
#include <limits>

#include <cstring>
#include <numbers>

#include "error.h"
#include "scene_readers.h"
#include "solution_ply.h"
#include "test_util.h"

namespace mpath {
namespace {

using test::TempDir;
using test::write_file;

const char* kAsciiPly = R"(ply
format ascii 1.0
comment two triangles, one emitting, in two components
element vertex 6
property float x
property float y
property float z
element face 2
property list uchar int vertex_indices
property float rho_r
property float rho_g
property float rho_b
property float emit_r
property float emit_g
property float emit_b
end_header
0 0 0
1 0 0
0 1 0
0 0 1
1 0 1
0 1 1
3 0 1 2 0.5 0.5 0.5 0 0 0
3 3 4 5 0.2 0.3 0.4 3.14159265 0 0
)";

// The same scene, binary, in the given byte order.
std::string binary_ply(bool big_endian) {
  std::string header = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                       " 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
                       "element face 2\nproperty list uchar int vertex_indices\nproperty float rho_r\n"
                       "property float rho_g\nproperty float rho_b\nproperty float emit_r\nproperty float emit_g\n"
                       "property float emit_b\nend_header\n";
  std::string body;
  auto put = [&](auto v) {
    char bytes[sizeof(v)];
    std::memcpy(bytes, &v, sizeof(v));
    if (big_endian) std::reverse(bytes, bytes + sizeof(v));
    body.append(bytes, sizeof(v));
  };
  const float vertices[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  for (const auto& v : vertices)
    for (float c : v) put(c);
  const float props[2][6] = {{0.5f, 0.5f, 0.5f, 0, 0, 0}, {0.2f, 0.3f, 0.4f, 3.14159265f, 0, 0}};
  for (int f = 0; f < 2; ++f) {
    put(static_cast<uint8_t>(3));
    for (int k = 0; k < 3; ++k) put(static_cast<int32_t>(3 * f + k));
    for (float p : props[f]) put(p);
  }
  return header + body;
}

void expect_two_triangles(const Scene& s) {
  ASSERT_EQ(s.polygons.size(), 2u);
  EXPECT_EQ(s.objects.size(), 2u);  // connected components
  EXPECT_EQ(s.polygons[1].vertices[1], (Vec3{1, 0, 1}));
  const Material& lamp = s.materials[s.polygons[1].material];
  EXPECT_NEAR(lamp.rho[2], 0.4, 1e-6);
  EXPECT_NEAR(lamp.emission[0], 1.0, 1e-6);  // exitance pi -> radiance 1
  EXPECT_FALSE(s.materials[s.polygons[0].material].emits());
}

TEST(PlyReader, ReadsAsciiAndBothBinaryByteOrdersAlike) {
  TempDir dir;
  write_file(dir / "a.ply", kAsciiPly);
  write_file(dir / "le.ply", binary_ply(false));
  write_file(dir / "be.ply", binary_ply(true));
  for (const char* name : {"a.ply", "le.ply", "be.ply"}) {
    SCOPED_TRACE(name);
    expect_two_triangles(read_ply(dir / name));
  }
}

// A solution with a value no float holds is never written (no Inf or NaN in a result).
TEST(SolutionPly, RefusesValuesNoFloatHolds) {
  TempDir dir;
  const Scene scene = test::furnace_scene(0.5, 1.0);
  const PatchMesh mesh = build_mesh(scene, 0.5);
  RadiosityState state = make_state(scene, mesh);
  for (const double bad : {1e300, std::numeric_limits<double>::infinity(), std::nan("")}) {
    state.phi[state.at(3, 0)] = bad;
    EXPECT_THROW(write_solution_ply(dir / "solution.ply", mesh, state.solution_faces(mesh)), std::runtime_error)
        << bad;
    EXPECT_FALSE(std::filesystem::exists(dir / "solution.ply")) << bad;
  }
}

// mpath-compare and scripts read solutions with read_solution_ply: a NaN or
// an infinity in one is refused by face, never compared.
TEST(SolutionPly, ReadingRefusesValuesThatAreNotFiniteNumbers) {
  TempDir dir;
  const auto solution = [&](float b) {
    std::string text = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                       "property float z\nelement face 1\nproperty list uchar int vertex_indices\nproperty float area\n"
                       "property float B_r\nproperty float B_g\nproperty float B_b\nend_header\n";
    const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    text.append(reinterpret_cast<const char*>(v), sizeof v);
    text.push_back(3);
    const int32_t idx[3] = {0, 1, 2};
    text.append(reinterpret_cast<const char*>(idx), sizeof idx);
    const float values[4] = {0.5f, b, 1.0f, 1.0f};
    text.append(reinterpret_cast<const char*>(values), sizeof values);
    write_file(dir / "s.ply", text);
    return dir / "s.ply";
  };
  EXPECT_FLOAT_EQ(read_solution_ply(solution(2.0f)).radiosity[0][0], 2.0f);
  for (const float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    try {
      read_solution_ply(solution(bad));
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("face 0 has a value that is not a finite number"), std::string::npos) << e.what();
    }
  }
}

TEST(PlyReader, ReadsBackTheSolutionItWrote) {
  TempDir dir;
  const Scene scene = test::furnace_scene(0.5, 1.0);
  const PatchMesh mesh = build_mesh(scene, 0.5);
  RadiosityState state = make_state(scene, mesh);
  for (size_t i = 0; i < state.phi.size(); ++i) state.phi[i] *= 2.0;
  write_solution_ply(dir / "solution.ply", mesh, state.solution_faces(mesh));
  const std::string text = test::read_file(dir / "solution.ply");
  for (const char* prop : {"property float area", "property float rho_r", "property float emit_b", "property float B_g",
                           "property int polygon", "property int object", "format binary_little_endian 1.0"})
    EXPECT_NE(text.find(prop), std::string::npos) << prop;
  const Scene back = read_ply(dir / "solution.ply");
  ASSERT_EQ(back.polygons.size(), mesh.face_count());
  EXPECT_EQ(back.objects.size(), scene.objects.size());
  for (size_t f = 0; f < back.polygons.size(); f += 7) {
    EXPECT_NEAR(polygon_area(back.polygons[f].vertices), mesh.face_area(static_cast<int>(f)), 1e-5);
    EXPECT_NEAR(back.materials[back.polygons[f].material].rho[0], 0.5, 1e-6);
    EXPECT_NEAR(back.materials[back.polygons[f].material].emission[1], 1.0 / std::numbers::pi, 1e-6);
  }
}

// Viewers (MeshLab, Blender) show solution.ply's per-vertex and per-face
// red green blue: sRGB of the radiosity scaled so that the 95th percentile
// (by area, faces that do not emit) shows at 0.8 of white.
TEST(SolutionPly, CarriesToneMappedColoursForViewers) {
  TempDir dir;
  Scene scene = test::furnace_scene(0.5, 1.0);
  for (Material& m : scene.materials) m.emission = {0, 0, 0};
  const PatchMesh mesh = build_mesh(scene, 0.5);
  RadiosityState state = make_state(scene, mesh);
  for (size_t f = 0; f < mesh.face_count(); ++f)
    for (int c = 0; c < state.channels; ++c) state.phi[state.at(f, c)] = 3.0 * mesh.face_area(static_cast<int>(f));
  state.phi[state.at(0, 0)] *= 10;  // one face far brighter than the rest: it clips
  write_solution_ply(dir / "solution.ply", mesh, state.solution_faces(mesh));
  const std::string text = test::read_file(dir / "solution.ply");
  ASSERT_NE(text.find("property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face"),
            std::string::npos);
  ASSERT_NE(text.find("property int object\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header"),
            std::string::npos);
  size_t at = text.find("end_header\n") + 11;
  const auto srgb = [](double v) { return static_cast<int>(std::lround(255 * (1.055 * std::pow(v, 1 / 2.4) - 0.055))); };
  std::set<int> vertex_red;
  for (size_t v = 0; v < mesh.vertices.size(); ++v, at += 15) vertex_red.insert(static_cast<uint8_t>(text[at + 12]));
  EXPECT_TRUE(vertex_red.count(srgb(0.8))) << "the common radiosity shows at 0.8";
  std::vector<int> face_red;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const int corners = static_cast<uint8_t>(text[at]);
    at += 1 + 4 * corners + 10 * 4 + 2 * 4;
    face_red.push_back(static_cast<uint8_t>(text[at]));
    EXPECT_EQ(static_cast<uint8_t>(text[at + 1]), static_cast<uint8_t>(text[at])) << "face " << f;  // grey
    at += 3;
  }
  EXPECT_EQ(at, text.size());
  EXPECT_EQ(face_red[0], 255);
  for (size_t f = 1; f < face_red.size(); ++f) EXPECT_EQ(face_red[f], srgb(0.8)) << "face " << f;
}

// display_srgb8 looks codes up in a table of the values where they step up;
// it must give the transfer function's rounded code everywhere, at the
// steps above all (computed here from the inverse function, and a few
// float steps either side of each).
TEST(SolutionPly, ColourTableGivesTheTransferFunctionsCodes) {
  const auto direct = [](double v) {
    v = std::clamp(v, 0.0, 1.0);
    const double s = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
    return static_cast<int>(std::lround(255 * s));
  };
  std::vector<double> values = {-1.0, 0.0, 1e-300, 0.0031308, 1.0, 2.0, 1e300};
  for (int k = 1; k < 256; ++k) {
    const double s = (k - 0.5) / 255;  // the sRGB value where code k begins
    const double linear = s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
    double below = linear, above = linear;
    for (int u = 0; u < 8; ++u) {
      values.push_back(below = std::nextafter(below, 0.0));
      values.push_back(above = std::nextafter(above, 1.0));
    }
    values.push_back(linear);
  }
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int i = 0; i < 1000000; ++i) values.push_back(std::pow(uniform(rng), 3.0));
  int wrong = 0;
  for (const double v : values)
    if (display_srgb8(v) != direct(v) && ++wrong <= 5)
      ADD_FAILURE() << "linear " << v << ": " << +display_srgb8(v) << ", not " << direct(v);
  EXPECT_EQ(wrong, 0);
}

// solution.ply is written in blocks of 65,536 records filled in parallel:
// a mesh of more faces reads back face by face as the state holds it.
TEST(SolutionPly, ManyFacesReadBackInOrder) {
  TempDir dir;
  Scene scene;
  scene.materials.push_back(Material{});
  scene.materials[0].rho = {0.5, 0.4, 0.3};
  scene.objects.push_back({"plate"});
  Polygon quad;
  quad.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  scene.polygons.push_back(quad);
  const PatchMesh mesh = build_mesh(scene, 1.0 / 150000);
  ASSERT_GT(mesh.face_count(), 2 * 65536u);
  RadiosityState state = make_state(scene, mesh);
  for (size_t f = 0; f < mesh.face_count(); ++f)
    for (int c = 0; c < state.channels; ++c)
      state.phi[state.at(f, c)] = (1.0 + static_cast<double>(f % 977) + c / 4.0) * mesh.face_area(static_cast<int>(f));
  write_solution_ply(dir / "solution.ply", mesh, state.solution_faces(mesh));
  const SolutionFaces back = read_solution_ply(dir / "solution.ply");
  ASSERT_EQ(back.area.size(), mesh.face_count());
  const std::vector<SolutionFace> faces = state.solution_faces(mesh);
  size_t differ = 0;
  for (size_t f = 0; f < faces.size(); ++f)
    for (int c = 0; c < 3; ++c)
      differ += back.radiosity[f][c] != static_cast<float>(faces[f].radiosity[c]) ||
                back.area[f] != static_cast<float>(mesh.face_area(static_cast<int>(f)));
  EXPECT_EQ(differ, 0u);
  const Scene geometry = read_ply(dir / "solution.ply");
  ASSERT_EQ(geometry.polygons.size(), mesh.face_count());
  for (size_t f = 0; f < geometry.polygons.size(); f += 4099)
    EXPECT_NEAR(polygon_area(geometry.polygons[f].vertices), mesh.face_area(static_cast<int>(f)), 1e-9) << f;
}

TEST(PlyReader, ReportsTruncatedAndMalformedFiles) {
  TempDir dir;
  std::string truncated = binary_ply(false);
  truncated.resize(truncated.size() - 10);
  write_file(dir / "t.ply", truncated);
  try {
    read_ply(dir / "t.ply");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unexpected end of file in element 'face' item 1 of 2"), std::string::npos) << e.what();
  }
  std::string bad_index = kAsciiPly;
  bad_index.replace(bad_index.find("3 3 4 5"), 7, "3 3 4 9");
  write_file(dir / "i.ply", bad_index);
  EXPECT_THROW(read_ply(dir / "i.ply"), InputError);
  write_file(dir / "h.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quaternion x\nend_header\n");
  try {
    read_ply(dir / "h.ply");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("h.ply:4: malformed property"), std::string::npos) << e.what();
  }
  write_file(dir / "n.ply", "solid x\n");
  EXPECT_THROW(read_ply(dir / "n.ply"), InputError);
  // Counts a small file cannot hold end at once, not after minutes of looping
  // (found by fuzz/fuzz_ply): one past the integers, one beyond the file.
  const auto error_of = [&](const std::string& name, const std::string& text) {
    write_file(dir / name, text);
    try {
      read_ply(dir / name);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string header = "ply\nformat binary_little_endian 1.0\n";
  EXPECT_NE(error_of("c1.ply", header + "element vertex 333333333333333333333333333\nproperty float x\nend_header\n")
                .find("c1.ply:3: malformed 'element'"),
            std::string::npos);
  EXPECT_NE(error_of("c2.ply", header + "element vertex 1000000000\nproperty float x\nend_header\n")
                .find("element 'vertex' claims 1000000000 items, more than the file's"),
            std::string::npos);
  EXPECT_NE(error_of("c3.ply", header + "element vertex 3000000000\nproperty float x\nend_header\n")
                .find("mpath reads at most"),
            std::string::npos);
  // A non-integer object id is refused, not cast.
  EXPECT_NE(error_of("o.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                              "element face 1\nproperty list uchar int vertex_indices\nproperty float object\nend_header\n"
                              "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 1e30\n")
                .find("object id 1e+30 is not a whole number"),
            std::string::npos);
}

}  // namespace
}  // namespace mpath
