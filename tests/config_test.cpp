#include "config.h"

#include <gtest/gtest.h>

#include "config_keys.h"
#include "error.h"
#include "test_util.h"

namespace mpath {
namespace {

using test::TempDir;
using test::write_file;

std::string error_of(const std::filesystem::path& file, const std::vector<std::string>& overrides = {}) {
  try {
    load_options(file, overrides);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Config, ResolvesPathsInTheFileRelativeToTheFile) {
  TempDir dir;
  write_file(dir / "sub/run.toml", "scene.file = \"scenes/a.obj\"\n[output]\ndir = \"out\"\n");
  const Options o = load_options(dir / "sub/run.toml", {});
  EXPECT_EQ(o.scene.file, dir / "sub/scenes/a.obj");
  EXPECT_EQ(o.output.dir, dir / "sub/out");
  EXPECT_EQ(o.solver.method, SolverMethod::hierarchical);
  EXPECT_EQ(o.lines.total, 1'000'000);
}

TEST(Config, CommandLineOverridesWinAndTheirPathsAreRelativeToTheWorkingDirectory) {
  TempDir dir;
  write_file(dir / "run.toml", "scene.file = \"a.obj\"\n[solver]\niterations = 3\n");
  const Options o = load_options(dir / "run.toml", {"solver.iterations=7", "output.dir=elsewhere", "solver.method=classic",
                                                     "lines.sequence=random", "mesh.max_patch_area=0.5"});
  EXPECT_EQ(o.solver.iterations, 7);
  EXPECT_EQ(o.solver.method, SolverMethod::classic);
  EXPECT_EQ(o.lines.sequence, "random");
  EXPECT_DOUBLE_EQ(o.mesh.max_patch_area, 0.5);
  EXPECT_EQ(o.output.dir, std::filesystem::current_path() / "elsewhere");
}

TEST(Config, UnknownKeyIsNamedWithFileAndLine) {
  TempDir dir;
  write_file(dir / "run.toml", "scene.file = \"a.obj\"\n[solver]\nitterations = 3\n");
  const std::string e = error_of(dir / "run.toml");
  EXPECT_NE(e.find("unknown config key 'solver.itterations'"), std::string::npos) << e;
  EXPECT_NE(e.find("run.toml:3"), std::string::npos) << e;
}

TEST(Config, WrongValueTypeIsNamed) {
  TempDir dir;
  write_file(dir / "run.toml", "scene.file = \"a.obj\"\n[solver]\niterations = \"ten\"\n");
  const std::string e = error_of(dir / "run.toml");
  EXPECT_NE(e.find("'solver.iterations': expected an integer, got a string"), std::string::npos) << e;
}

// The pilot's lines (lines.pilot, docs/algorithm.md "Pilot budget"): by
// default a twentieth of lines.total within [50k, 200k], never above a
// quarter of it; a set count is kept up to that quarter. Negative counts
// are errors.
TEST(Config, ThePilotFollowsLinesTotalUnlessSet) {
  TempDir dir;
  write_file(dir / "run.toml", "scene.file = \"a.obj\"\n");
  const auto pilot = [&](const std::vector<std::string>& keys) { return load_options(dir / "run.toml", keys).lines.pilot_lines(); };
  EXPECT_EQ(pilot({"lines.total=100000"}), 25'000);  // a quarter
  EXPECT_EQ(pilot({"lines.total=250000"}), 50'000);
  EXPECT_EQ(pilot({"lines.total=1000000"}), 50'000);
  EXPECT_EQ(pilot({"lines.total=2000000"}), 100'000);
  EXPECT_EQ(pilot({"lines.total=3000000"}), 150'000);
  EXPECT_EQ(pilot({"lines.total=4000000"}), 200'000);
  EXPECT_EQ(pilot({"lines.total=64000000"}), 200'000);
  EXPECT_EQ(pilot({"lines.total=1000000", "lines.pilot=200000"}), 200'000);
  EXPECT_EQ(pilot({"lines.total=400000", "lines.pilot=200000"}), 100'000);
  EXPECT_EQ(pilot({"lines.total=64000000", "lines.pilot=1000000"}), 1'000'000);
  EXPECT_NE(error_of(dir / "run.toml", {"lines.pilot=-1"}).find("lines.pilot"), std::string::npos);
}

TEST(Config, OutOfRangeAndUnknownChoicesAreRejected) {
  TempDir dir;
  write_file(dir / "run.toml", "scene.file = \"a.obj\"\n");
  EXPECT_NE(error_of(dir / "run.toml", {"lines.root_fraction=1.5"}).find("lines.root_fraction"), std::string::npos);
  EXPECT_NE(error_of(dir / "run.toml", {"solver.method=magic"}).find("unknown method 'magic'"), std::string::npos);
  EXPECT_NE(error_of(dir / "run.toml", {"lines.total=0"}).find("positive"), std::string::npos);
  // Values above a limit are errors, not clamped.
  EXPECT_NE(error_of(dir / "run.toml", {"lines.total=2000000000000"}).find("at most 1000000000000"), std::string::npos);
  EXPECT_NE(error_of(dir / "run.toml", {"first_shot.lines=9000000000000000000"}).find("at most"), std::string::npos);
  EXPECT_NE(error_of(dir / "run.toml", {"solver.iterations=200000"}).find("at most 100000 (got 200000)"), std::string::npos);
  EXPECT_NE(error_of(dir / "run.toml", {"hierarchy.vp_grid=3"}).find("power of two"), std::string::npos);
  EXPECT_NE(error_of(dir / "run.toml", {"no_equals_sign"}).find("expected key=value"), std::string::npos);
  EXPECT_NE(error_of(dir / "run.toml", {"solver.bogus=1"}).find("command line: unknown config key 'solver.bogus'"),
            std::string::npos);
}

// An entry of a table ([scene.emitters], [scene.materials], [[camera]]) is
// named where it was written: its line in the file, or the command line for
// an override, even when the file holds other entries of the same table.
TEST(Config, TableEntriesNameTheirOwnSource) {
  TempDir dir;
  write_file(dir / "run.toml", "scene.file = \"a.obj\"\n[scene.materials]\nwall = 0.5\nfloor = 3\n");
  std::string e = error_of(dir / "run.toml");
  EXPECT_NE(e.find("run.toml:4: config key 'scene.materials.floor'"), std::string::npos) << e;
  write_file(dir / "ok.toml", "scene.file = \"a.obj\"\n[scene.materials]\nwall = 0.5\n");
  e = error_of(dir / "ok.toml", {"scene.materials.floor=3"});
  EXPECT_NE(e.find("command line: config key 'scene.materials.floor'"), std::string::npos) << e;
  e = error_of(dir / "ok.toml", {"scene.emitters.lamp=-1"});
  EXPECT_NE(e.find("command line: config key 'scene.emitters.lamp'"), std::string::npos) << e;
  e = error_of(dir / "ok.toml", {"camera=[{position=[0,0,1], look_at=[0,0,0], width=0}]"});
  EXPECT_NE(e.find("command line: config key 'camera[0].width'"), std::string::npos) << e;
}

TEST(Config, MalformedTomlAndMissingFilesAreReported) {
  TempDir dir;
  write_file(dir / "bad.toml", "scene.file = \"a.obj\"\n[solver\n");
  EXPECT_NE(error_of(dir / "bad.toml").find("bad.toml:2: malformed TOML"), std::string::npos);
  EXPECT_NE(error_of(dir / "missing.toml").find("config file not found"), std::string::npos);
  write_file(dir / "noscene.toml", "[solver]\niterations = 2\n");
  EXPECT_NE(error_of(dir / "noscene.toml").find("'scene.file' is required"), std::string::npos);
}

TEST(Config, EmittersCamerasAndTwoSidedAreRead) {
  TempDir dir;
  write_file(dir / "run.toml", R"(scene.file = "a.obj"
scene.two_sided = ["shade"]
[scene.emitters]
lamp = [1.0, 2.0, 3.0]
bulb = 5.0
[[camera]]
name = "front"
position = [0, 1, 5]
look_at = [0, 1, 0]
width = 64
height = 32
)");
  const Options o = load_options(dir / "run.toml", {});
  EXPECT_EQ(o.scene.emitters.at("lamp"), (Rgb{1, 2, 3}));
  EXPECT_EQ(o.scene.emitters.at("bulb"), (Rgb{5, 5, 5}));
  EXPECT_EQ(o.scene.two_sided, std::vector<std::string>{"shade"});
  ASSERT_EQ(o.cameras.size(), 1u);
  EXPECT_EQ(o.cameras[0].name, "front");
  EXPECT_EQ(o.cameras[0].width, 64);
  write_file(dir / "cam.toml", "scene.file = \"a.obj\"\n[[camera]]\nposition = [0, 0, 0]\nlook_at = [0, 0, 0]\n");
  EXPECT_NE(error_of(dir / "cam.toml").find("camera position equals look_at"), std::string::npos);
  // A camera's name names files in output.dir: never a path, never twice.
  write_file(dir / "path.toml", "scene.file = \"a.obj\"\n[[camera]]\nname = \"../../x\"\nposition = [0, 1, 5]\n");
  EXPECT_NE(error_of(dir / "path.toml").find("'camera[0].name': '../../x' is not a plain file name"), std::string::npos)
      << error_of(dir / "path.toml");
  write_file(dir / "twice.toml", "scene.file = \"a.obj\"\n[[camera]]\nname = \"c\"\nposition = [0, 1, 5]\n"
                                 "[[camera]]\nname = \"c\"\nposition = [0, 2, 5]\n");
  EXPECT_NE(error_of(dir / "twice.toml").find("cameras 0 and 1 are both named 'c'"), std::string::npos)
      << error_of(dir / "twice.toml");
  write_file(dir / "neg.toml", "scene.file = \"a.obj\"\n[scene.emitters]\nlamp = [1, -1, 0]\n");
  EXPECT_NE(error_of(dir / "neg.toml").find("must not be negative"), std::string::npos);
}

TEST(Config, PrintedConfigLoadsBackUnchanged) {
  TempDir dir;
  write_file(dir / "run.toml", "scene.file = \"a.obj\"\n[[camera]]\nposition = [0, 1, 5]\nlook_at = [0, 1, 0]\n");
  const Options a = load_options(dir / "run.toml", {"solver.tolerance=0.01", "scene.emitters.lamp=[1,1,1]"});
  write_file(dir / "printed.toml", options_to_toml(a));
  const Options b = load_options(dir / "printed.toml", {});
  EXPECT_EQ(options_to_toml(a), options_to_toml(b));
}

// The user guide's key table is the code's: every key parsed and printed has
// its row, with the default the code uses.
TEST(Config, UserGuideKeyTableIsTheCodesTable) {
  const std::string guide = test::read_file(std::filesystem::path(MPATH_SOURCE_DIR) / "docs/user-guide.md");
  const std::string begin = "<!-- config keys:", end = "<!-- end of config keys -->";
  const size_t a = guide.find(begin), b = guide.find(end);
  ASSERT_NE(a, std::string::npos);
  ASSERT_NE(b, std::string::npos);
  const size_t table = guide.find('\n', a) + 1;
  EXPECT_EQ(guide.substr(table, b - table), config_keys_markdown())
      << "docs/user-guide.md: replace the key table with the output of mpath-solve --list-keys";
}

// Every key of the table is found by its name and printed by --print-config.
TEST(Config, EveryKeyOfTheTableIsPrinted) {
  TempDir dir;
  write_file(dir / "run.toml", "scene.file = \"a.obj\"\n[[camera]]\nposition = [0, 1, 5]\nlook_at = [0, 1, 0]\n"
                               "[[grid]]\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\n"
                               "[[light]]\nposition = [0, 0, 2]\nintensity_cd = 100\n");
  const toml::table printed = toml::parse(options_to_toml(load_options(dir / "run.toml", {})));
  for (const ConfigKey& k : config_keys()) {
    EXPECT_EQ(find_config_key(k.key), &k);
    EXPECT_FALSE(k.meaning.empty()) << k.key;
    EXPECT_TRUE(printed.at_path(k.key)) << k.key << " is not printed";
  }
  EXPECT_EQ(find_config_key("lines.totl"), nullptr);
}

}  // namespace
}  // namespace mpath
