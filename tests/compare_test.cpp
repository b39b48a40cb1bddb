// mpath-compare: the error measures against values worked by hand, the
// solution reader's refusals, and the program on the shipped room.
#include <gtest/gtest.h>

#include <array>
#include <limits>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>

#include "compare.h"
#include "error.h"
#include "test_util.h"

namespace mpath {
namespace {

using test::TempDir;

SolutionFaces faces(std::vector<float> area, std::vector<std::array<float, 3>> b,
                    std::vector<std::array<float, 3>> e = {}) {
  SolutionFaces s;
  s.area = std::move(area);
  s.radiosity = std::move(b);
  s.exitance = e.empty() ? std::vector<std::array<float, 3>>(s.area.size(), {0, 0, 0}) : std::move(e);
  return s;
}

TEST(Compare, MeasuresAgainstHandWorkedValues) {
  // Three faces: an emitter (E = 10, reflected 1) the result gets right, a
  // face of area 2 off by 0.5 in every channel, a face of area 1 off by 1 in red.
  const auto reference = faces({1, 2, 1}, {{{11, 11, 11}}, {{2, 2, 2}}, {{4, 4, 4}}}, {{{10, 10, 10}}, {{0, 0, 0}}, {{0, 0, 0}}});
  const auto result = faces({1, 2, 1}, {{{11, 11, 11}}, {{2.5, 2.5, 2.5}}, {{5, 4, 4}}}, {{{10, 10, 10}}, {{0, 0, 0}}, {{0, 0, 0}}});
  const Comparison c = compare_solutions(result, reference);
  // Squared errors, area-weighted: 2 * 3 * 0.25 + 1 * 1 = 2.5; area 4; three channels.
  EXPECT_NEAR(c.mse, 2.5 / 4 / 3, 1e-12);
  // Reflected reference: 1 * 3 * 1 + 2 * 3 * 4 + 1 * 3 * 16 = 75; with emission: 3 * 121 + 24 + 48 = 435.
  EXPECT_NEAR(c.rel_rms, std::sqrt(2.5 / 75), 1e-7);
  EXPECT_NEAR(c.rel_rms_total, std::sqrt(2.5 / 435), 1e-7);
  // Per face: 0, 0.5 / 2 = 0.25, (1/3) / 4 = 1/12; area-weighted mean (0 + 0.5 + 1/12) / 4.
  EXPECT_NEAR(c.relative[0], 0.0, 1e-7);
  EXPECT_NEAR(c.relative[1], 0.25, 1e-7);
  EXPECT_NEAR(c.relative[2], 1.0 / 12, 1e-7);
  EXPECT_NEAR(c.mean_relative, (0.5 + 1.0 / 12) / 4, 1e-7);
  // Area-weighted quantiles: sorted 0 (area 1), 1/12 (1), 0.25 (2) of 4.
  EXPECT_NEAR(c.p50, 1.0 / 12, 1e-7);
  EXPECT_NEAR(c.p90, 0.25, 1e-7);
}

TEST(Compare, DarkReferenceFacesHaveNoRelativeError) {
  const auto reference = faces({1, 1}, {{{1, 1, 1}}, {{1e-9f, 1e-9f, 1e-9f}}});
  const auto result = faces({1, 1}, {{{1, 1, 1}}, {{1, 1, 1}}});
  const Comparison c = compare_solutions(result, reference);
  EXPECT_LT(c.relative[1], 0.0);
  EXPECT_NEAR(c.mean_relative, 0.0, 1e-12);
  EXPECT_GT(c.mse, 0.3);  // still counted in the MSE
}

// compare_solutions throws an InputError whose message holds `says`.
void expect_refused(const SolutionFaces& result, const SolutionFaces& reference, const std::string& says) {
  try {
    compare_solutions(result, reference);
    ADD_FAILURE() << "compared";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
  }
}

TEST(Compare, RefusesSolutionsOfDifferentMeshes) {
  expect_refused(faces({1, 1}, {{{1, 1, 1}}, {{1, 1, 1}}}), faces({1}, {{{1, 1, 1}}}),
                 "the solutions have different faces (2 and 1): not the same mesh");
  expect_refused(faces({1, 1}, {{{1, 1, 1}}, {{1, 1, 1}}}), faces({1, 2}, {{{1, 1, 1}}, {{1, 1, 1}}}),
                 "face 1 has area 1 in one solution and 2 in the other: not the same mesh");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  expect_refused(faces({1}, {{{1, nan, 1}}}), faces({1}, {{{1, 1, 1}}}), "face 0 has a radiosity that is not a number");
}

void write_ply(const std::filesystem::path& path, const std::string& header, const std::string& body) {
  std::ofstream(path, std::ios::binary) << header << body;
}

// Reading `path` throws an InputError whose message holds `says`.
void expect_refused(const std::filesystem::path& path, const std::string& says) {
  try {
    read_solution_ply(path);
    ADD_FAILURE() << path << " was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
  }
}

TEST(Compare, ReaderNamesWhatIsWrongWithAFile) {
  TempDir dir;
  const std::string head =
      "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 2\nproperty list uchar int vertex_indices\nproperty float area\nproperty float B_r\n"
      "property float B_g\nproperty float B_b\nend_header\n";
  const float values[4] = {0.5f, 1, 2, 3};
  const std::string face = std::string(1, '\0') + std::string(reinterpret_cast<const char*>(values), 16);  // no corners
  write_ply(dir / "good.ply", head, face + face);
  const SolutionFaces good = read_solution_ply(dir / "good.ply");
  ASSERT_EQ(good.area.size(), 2u);
  EXPECT_EQ(good.area[1], 0.5f);
  EXPECT_EQ(good.radiosity[1][2], 3.0f);

  write_ply(dir / "short.ply", head, face);
  expect_refused(dir / "short.ply", "short.ply: cut short at face 1 of 2");
  std::string no_b = head;
  no_b.replace(no_b.find("property float B_b\n"), 19, "property float B_x\n");
  write_ply(dir / "nob.ply", no_b, face + face);
  expect_refused(dir / "nob.ply", "no float property B_b");
  std::string ascii = head;
  ascii.replace(ascii.find("binary_little_endian"), 20, "ascii");
  write_ply(dir / "ascii.ply", ascii, "");
  expect_refused(dir / "ascii.ply", "not binary_little_endian");
  write_ply(dir / "text.ply", "not a ply\n", "");
  expect_refused(dir / "text.ply", "no 'ply' magic");
  // Headers that are not mpath's: each names what it found.
  for (const auto& [from, to, says] : std::vector<std::array<std::string, 3>>{
           {"element face 2", "element face", "element without a count: element face"},
           {"element vertex 0", "element vertox 0", "unexpected element vertox"},
           {"property float area", "property list uchar int area", "unexpected list property: property list uchar int area"},
           {"property float B_r", "property flaot B_r", "unknown property type flaot"},
           {"property list uchar int vertex_indices\n", "", "faces have no vertex_indices list"},
           {"end_header\n", "", "the header has no end_header"}}) {
    std::string h = head;
    h.replace(h.find(from), from.size(), to);
    write_ply(dir / "header.ply", h, face + face);
    expect_refused(dir / "header.ply", "header.ply: not an mpath solution.ply: " + says);
  }
}

const std::string kRoom = std::string(MPATH_SOURCE_DIR) + "/configs/room.toml";
std::string compare_bin() { return test::program_bin("mpath-compare"); }

TEST(ComparePrograms, TwoSeedsOfTheShippedRoomAndItsErrorImage) {
  TempDir dir;
  const std::string common = " solver.method=classic lines.total=200000 first_shot.lines=50000 output.png=false "
                             "output.exr=false -q";
  for (const char* seed : {"1", "2"})
    ASSERT_EQ(test::run(test::solve_bin() + " " + kRoom + common + " lines.seed=" + seed + " output.dir=" +
                        (dir / seed).string()).exit_code, 0);
  // Against itself: nothing.
  test::RunResult r = test::run(compare_bin() + " " + kRoom + " -q --no-images --result " + (dir / "1").string() +
                                " --reference " + (dir / "1/solution.ply").string() + " --out " + (dir / "self").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto j = nlohmann::json::parse(test::read_file(dir / "self/compare.json"));
  EXPECT_EQ(j["mse"].get<double>(), 0.0);
  EXPECT_EQ(j["rel_rms"].get<double>(), 0.0);

  // Two seeds: an error of the size the line count gives, and an image per camera.
  r = test::run(compare_bin() + " " + kRoom + " -q --result " + (dir / "2").string() + " --reference " +
                (dir / "1").string() + " --out " + (dir / "two").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  j = nlohmann::json::parse(test::read_file(dir / "two/compare.json"));
  EXPECT_GT(j["rel_rms"].get<double>(), 0.01);
  EXPECT_LT(j["rel_rms"].get<double>(), 1.0);
  EXPECT_LT(j["rel_rms_total"].get<double>(), j["rel_rms"].get<double>());  // the lamp's emission dilutes it
  EXPECT_EQ(j["faces"].get<size_t>(), nlohmann::json::parse(test::read_file(dir / "1/report.json"))["scene"]["faces"]);
  ASSERT_EQ(j["images"].size(), 1u);
  EXPECT_TRUE(std::filesystem::exists(dir / "two/room_error.png"));
  EXPECT_TRUE(std::filesystem::exists(dir / "two/room_error.exr"));

  // A solution of another mesh is refused by name.
  r = test::run(compare_bin() + " " + kRoom + " -q --result " + (dir / "2").string() + " --reference " +
                (dir / "1").string() + " --out " + (dir / "other").string() + " mesh.max_patch_area=0.05");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("not the config the solutions were made with"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "other/compare.json"));
}

}  // namespace
}  // namespace mpath
