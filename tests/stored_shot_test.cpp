// The store's first shot (first_shot.bin): what mpath-preprocess writes, a
// solve on the store reads instead of tracing, and it must give what tracing
// the same plan gives; another plan is traced, a damaged file is an error.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <numeric>
#include <random>
#include <set>

#include "error.h"
#include "stored_shot.h"
#include "test_util.h"
#include "varint.h"
#include "zstd_frame.h"

namespace mpath {
namespace {

using test::TempDir;

// A closed room with random boxes in it: floating, standing on the floor
// (faces in contact), one from floor to ceiling; some of them and part of
// the ceiling emit, in random colours.
Scene random_room(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Scene scene;
  scene.file = "random room";
  const double w = 2 + 2 * u(rng), d = 1.5 + 2 * u(rng), h = 1 + u(rng);
  const int wall = test::add_material(scene, "wall", 0.3 + 0.6 * u(rng), 0);
  test::add_box(scene, {0, 0, 0}, {w, d, h}, true, wall, test::add_object(scene, "room"));
  const int lamp = test::add_material(scene, "lamp", 0.2, 5 + 20 * u(rng));
  scene.materials[lamp].emission = {5 + 20 * u(rng), 5 + 20 * u(rng), 5 + 20 * u(rng)};
  test::add_quad(scene, {0.3 * w, 0.3 * d, h - 1e-3}, {0.3 * w, 0.5 * d, h - 1e-3}, {0.5 * w, 0.5 * d, h - 1e-3},
                 {0.5 * w, 0.3 * d, h - 1e-3}, lamp, test::add_object(scene, "ceiling lamp"));
  const int boxes = 2 + static_cast<int>(rng() % 5);
  for (int b = 0; b < boxes; ++b) {
    const bool glowing = rng() % 3 == 0;
    const int m = test::add_material(scene, fmt::format("box {}", b), 0.1 + 0.8 * u(rng), glowing ? 2 * u(rng) : 0);
    const double x = u(rng) * (w - 0.5), y = u(rng) * (d - 0.5), sx = 0.1 + 0.4 * u(rng), sy = 0.1 + 0.4 * u(rng);
    const double z0 = b == 0 ? 0.0 : (rng() % 2 ? 0.0 : u(rng) * 0.5 * h), z1 = b == 0 ? h : z0 + 0.1 + 0.4 * u(rng) * h;
    test::add_box(scene, {x, y, z0}, {x + sx, y + sy, std::min(z1, h)}, false, m,
                  test::add_object(scene, fmt::format("box {}", b)));
  }
  return scene;
}

struct Prepared {
  PatchMesh mesh;
  RadiosityState state;
};

Prepared prepared_room(const Scene& scene, double max_patch_area) {
  Prepared s{build_mesh(scene, max_patch_area), {}};
  s.state = make_state(scene, s.mesh);
  return s;
}

// Every face's Phi and U, and the energy terms, equal to a relative 1e-12.
void expect_same_state(const RadiosityState& a, const RadiosityState& b, const std::string& what) {
  ASSERT_EQ(a.phi.size(), b.phi.size());
  double scale = 0;
  for (double p : a.phi) scale = std::max(scale, std::abs(p));
  for (size_t i = 0; i < a.phi.size(); ++i) {
    ASSERT_NEAR(a.phi[i], b.phi[i], 1e-12 * scale) << what << ", entry " << i;
    ASSERT_NEAR(a.unshot[i], b.unshot[i], 1e-12 * scale) << what << ", entry " << i;
  }
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(a.energy.absorbed[c], b.energy.absorbed[c], 1e-12 * a.emitted_total()) << what;
    EXPECT_NEAR(a.energy.escaped[c], b.energy.escaped[c], 1e-12 * a.emitted_total()) << what;
  }
}

// A fate's code names a face of the mesh, -1 or none, and the codes below
// code_limit are exactly those (a reader takes no code at or above it).
TEST(StoredShot, CodesNameFacesOfTheMeshOnly) {
  for (size_t faces : {1, 2, 12, 1000}) {
    std::set<uint32_t> codes{kEscaped};
    for (int f = -1; f < static_cast<int>(faces); ++f)
      for (bool contact : {false, true}) {
        const uint32_t code = met_code(f, contact);
        EXPECT_EQ(code_face(code), f);
        EXPECT_EQ(code_contact(code), contact);
        codes.insert(code);
      }
    EXPECT_EQ(codes.size(), 2 * (faces + 1) + 1);
    EXPECT_EQ(*codes.rbegin() + 1, code_limit(faces)) << faces << " faces";
  }
}

// Read back, the stored first shot is the traced one, on random rooms, with
// every emitter shot locally and with some left to the global lines.
TEST(StoredShot, ReadingItGivesWhatTracingTheSamePlanGives) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    TempDir dir;
    Prepared s = prepared_room(random_room(seed), 0.02);
    ASSERT_FALSE(s.mesh.contact_plane.empty()) << "the boxes on the floor touch it";
    const Tracer tracer(s.mesh);
    std::vector<double> crossings;
    if (seed % 2 == 0) {  // the global lines take the faces they cross often
      crossings.assign(s.mesh.face_count(), 0.0);
      for (size_t f = 0; f < crossings.size(); f += 3) crossings[f] = 1e9;
    }
    const long long budget = 20'000 + 7'919 * seed;
    const FirstShotPlan plan = plan_first_shot(s.mesh, s.state, budget, crossings);
    EXPECT_EQ(!plan.global_faces.empty(), seed % 2 == 0);
    const auto path = dir / kStoredShotFile;
    write_stored_shot(path, s.mesh, tracer, plan, seed, 3);

    RadiosityState traced = s.state, stored = s.state;
    first_shot(s.mesh, tracer, traced, plan, seed, 1 + static_cast<int>(seed % 4));
    FirstShotStats stats;
    ASSERT_EQ(replay_stored_shot(path, s.mesh, plan, seed, stored, stats), "") << "seed " << seed;
    EXPECT_TRUE(stats.stored);
    EXPECT_EQ(stats.lines, plan.lines());
    expect_same_state(traced, stored, fmt::format("room {}", seed));
    EXPECT_LT(std::abs(stored.energy_residual()), 1e-12 * stored.emitted_total()) << "emitted = absorbed + escaped + unshot";
  }
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// The state after a traced first shot of `budget` lines and the second shot
// a store of `crossings` root crossings per face would plan after it.
FirstShotPlan after_first_shot(const Prepared& s, const Tracer& tracer, long long budget, double crossings,
                               unsigned long long seed, RadiosityState& state) {
  state = s.state;
  first_shot(s.mesh, tracer, state, plan_first_shot(s.mesh, s.state, budget, {}), seed, 2);
  return plan_second_shot(state, budget / 4, std::vector<double>(s.mesh.face_count(), crossings), true);
}

// Read back, the stored second shot is the traced one (its lines' power from
// the state before it, contacts' part left unshot), on random rooms whose
// boxes stand on the floor; and it serves a run whose unshot power is the
// same in other proportions per channel.
TEST(StoredShot, ReadingTheSecondShotGivesWhatTracingItGives) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    TempDir dir;
    Prepared s = prepared_room(random_room(seed), 0.02);
    const Tracer tracer(s.mesh);
    RadiosityState before;
    const FirstShotPlan plan = after_first_shot(s, tracer, 30'000 + 5'003 * seed, 2.0 * seed, seed, before);
    ASSERT_GT(plan.emitters.size(), 3u) << "seed " << seed;
    ASSERT_LT(plan.emitters.size(), s.mesh.face_count()) << "seed " << seed << ": some faces left to the global lines";
    const auto path = dir / kStoredSecondShotFile;
    write_stored_shot(path, s.mesh, tracer, plan, seed, 3, ShotKind::second);
    RadiosityState traced = before, stored = before;
    const SecondShotStats t = second_shot(s.mesh, tracer, traced, plan, seed, 1 + static_cast<int>(seed % 3));
    SecondShotStats r;
    ASSERT_EQ(replay_stored_second_shot(path, s.mesh, plan, seed, stored, r), "") << "seed " << seed;
    EXPECT_TRUE(r.stored);
    EXPECT_FALSE(t.stored);
    EXPECT_EQ(r.lines, plan.lines());
    EXPECT_EQ(r.faces, t.faces);
    EXPECT_DOUBLE_EQ(r.power_share, t.power_share);
    expect_same_state(traced, stored, fmt::format("room {}", seed));
    EXPECT_LT(std::abs(stored.energy_residual()), 1e-12 * stored.emitted_total()) << "emitted = absorbed + escaped + unshot";
    // Not the first shot's file, nor read as one.
    unsigned long long read_seed = 0;
    EXPECT_EQ(read_stored_plan(path, s.mesh.face_count(), read_seed, ShotKind::second), plan);
    EXPECT_EQ(read_seed, seed);
    EXPECT_NE(message_of([&] { read_stored_plan(path, s.mesh.face_count(), read_seed); })
                  .find("not a first-shot file (wrong magic)"),
              std::string::npos);

    // Another state's unshot power, the same faces and line shares: each
    // channel's power scaled on its own reads back as tracing it.
    RadiosityState other = before;
    for (size_t f = 0; f < other.faces; ++f)
      for (int c = 0; c < other.channels; ++c) other.unshot[other.at(f, c)] *= 1.0 + 0.5 * c;
    RadiosityState other_traced = other;
    second_shot(s.mesh, tracer, other_traced, plan, seed, 2);
    ASSERT_EQ(replay_stored_second_shot(path, s.mesh, plan, seed, other, r), "");
    expect_same_state(other_traced, other, fmt::format("room {}, other colours", seed));
  }
}

// A second shot of another plan or seed is not read, and says why.
TEST(StoredShot, AnotherSecondShotIsNotReadAndSaysWhy) {
  TempDir dir;
  Prepared s = prepared_room(random_room(7), 0.02);
  const Tracer tracer(s.mesh);
  RadiosityState before;
  const FirstShotPlan plan = after_first_shot(s, tracer, 40'000, 4.0, 1, before);
  const auto path = dir / kStoredSecondShotFile;
  SecondShotStats stats;
  RadiosityState state = before;
  EXPECT_NE(replay_stored_second_shot(path, s.mesh, plan, 1, state, stats).find("planned no second shot"),
            std::string::npos);
  write_stored_shot(path, s.mesh, tracer, plan, 1, 3, ShotKind::second);
  EXPECT_NE(replay_stored_second_shot(path, s.mesh, plan, 2, state, stats).find("second shot was drawn with lines.seed = 1"),
            std::string::npos);
  const FirstShotPlan more = plan_second_shot(before, 20'000, std::vector<double>(s.mesh.face_count(), 4.0), true);
  ASSERT_NE(more, plan);
  EXPECT_NE(replay_stored_second_shot(path, s.mesh, more, 1, state, stats).find("this run's second shot is not the store's"),
            std::string::npos);
  EXPECT_EQ(state.phi, before.phi);
  EXPECT_EQ(state.unshot, before.unshot);
  EXPECT_FALSE(stats.stored);
  // The first shot's file under the second's name is damaged, not read.
  write_stored_shot(path, s.mesh, tracer, plan, 1, 3);
  const std::string why = message_of([&] { replay_stored_second_shot(path, s.mesh, plan, 1, state, stats); });
  EXPECT_NE(why.find("not a second-shot file (wrong magic); the store's second shot is damaged"), std::string::npos) << why;
}

// A line's fate does not depend on how many shards trace it.
TEST(StoredShot, TheTracedFirstShotIsTheSameOnAnyNumberOfShards) {
  Prepared s = prepared_room(random_room(11), 0.02);
  const Tracer tracer(s.mesh);
  const FirstShotPlan plan = plan_first_shot(s.mesh, s.state, 30'000, {});
  RadiosityState one = s.state, five = s.state;
  first_shot(s.mesh, tracer, one, plan, 3, 1);
  first_shot(s.mesh, tracer, five, plan, 3, 5);
  expect_same_state(one, five, "1 and 5 shards");
}

// The lines' fates do not depend on the emitters' power: the same plan with
// every emitter three times as bright and with other colours reads back as
// tracing it with those emitters.
TEST(StoredShot, AStoredFirstShotServesOtherEmission) {
  TempDir dir;
  const Scene scene = random_room(5);
  Prepared s = prepared_room(scene, 0.02);
  const Tracer tracer(s.mesh);
  const FirstShotPlan plan = plan_first_shot(s.mesh, s.state, 40'000, {});
  write_stored_shot(dir / kStoredShotFile, s.mesh, tracer, plan, 9, 3);

  Scene brighter = scene;
  for (Material& m : brighter.materials)
    for (double& e : m.emission) e *= 3;
  RadiosityState state = make_state(brighter, s.mesh);
  EXPECT_EQ(plan_first_shot(s.mesh, state, 40'000, {}), plan) << "the same shares of the power";
  RadiosityState traced = state;
  first_shot(s.mesh, tracer, traced, plan, 9, 2);
  FirstShotStats stats;
  ASSERT_EQ(replay_stored_shot(dir / kStoredShotFile, s.mesh, plan, 9, state, stats), "");
  expect_same_state(traced, state, "three times the emission");
}

// Another plan or seed is not read: the reason says what differs and the
// state is left as it was.
TEST(StoredShot, AnotherPlanIsNotReadAndSaysWhy) {
  TempDir dir;
  Prepared s = prepared_room(random_room(3), 0.02);
  const Tracer tracer(s.mesh);
  const FirstShotPlan plan = plan_first_shot(s.mesh, s.state, 10'000, {});
  const auto path = dir / kStoredShotFile;
  FirstShotStats stats;
  RadiosityState state = s.state;
  EXPECT_NE(replay_stored_shot(path, s.mesh, plan, 1, state, stats).find("the store has no first_shot.bin"),
            std::string::npos);
  write_stored_shot(path, s.mesh, tracer, plan, 1, 3);
  const FirstShotPlan more = plan_first_shot(s.mesh, s.state, 20'000, {});
  EXPECT_NE(replay_stored_shot(path, s.mesh, more, 1, state, stats).find("other line counts"), std::string::npos);
  EXPECT_NE(replay_stored_shot(path, s.mesh, plan, 2, state, stats).find("lines.seed = 1"), std::string::npos);
  std::vector<double> crossings(s.mesh.face_count(), 1e9);
  const FirstShotPlan global = plan_first_shot(s.mesh, s.state, 10'000, crossings);
  EXPECT_NE(replay_stored_shot(path, s.mesh, global, 1, state, stats).find("emitting faces are not the store's"),
            std::string::npos);
  EXPECT_EQ(state.phi, s.state.phi);
  EXPECT_EQ(state.unshot, s.state.unshot);
  EXPECT_FALSE(stats.stored);
}

// Every cut and every flipped bit that changes what the file says is an
// InputError naming it, before the state changes; never a crash or a wrong
// answer.
TEST(StoredShot, ADamagedFileIsAnErrorNamingIt) {
  TempDir dir;
  Prepared s = prepared_room(random_room(4), 0.05);
  const Tracer tracer(s.mesh);
  const FirstShotPlan plan = plan_first_shot(s.mesh, s.state, 2 * kFirstShotBlock * 64 + 100, {});
  const auto path = dir / kStoredShotFile;
  write_stored_shot(path, s.mesh, tracer, plan, 1, 3);
  const std::string good = test::read_file(path);
  RadiosityState state;
  const auto read = [&](const std::string& bytes) {
    test::write_file(path, bytes);
    state = s.state;
    FirstShotStats stats;
    const std::string why = message_of([&] { replay_stored_shot(path, s.mesh, plan, 1, state, stats); });
    if (!why.empty()) {
      EXPECT_EQ(state.phi, s.state.phi) << "the state is left as it was";
    }
    return why;
  };
  EXPECT_EQ(read(good), "");
  const RadiosityState right = state;
  std::mt19937 rng(1);
  for (size_t cut = 0; cut < good.size(); cut += 1 + rng() % 97) {
    const std::string why = read(good.substr(0, cut));
    EXPECT_NE(why.find("first_shot.bin"), std::string::npos) << "cut at " << cut << ": " << why;
  }
  // A flipped bit is an error, or one zstd does not read (a frame header's
  // unused bit) and the answer is the same.
  int errors = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::string bad = good;
    const size_t at = trial < 40 ? static_cast<size_t>(trial) : rng() % bad.size();
    bad[at] = static_cast<char>(bad[at] ^ (1 << (rng() % 8)));
    const std::string why = read(bad);
    if (why.empty()) {
      EXPECT_EQ(state.phi, right.phi) << "byte " << at << " changed, no error, another answer";
      EXPECT_EQ(state.unshot, right.unshot) << "byte " << at;
      continue;
    }
    ++errors;
    EXPECT_NE(why.find("the store's first shot is damaged"), std::string::npos) << "byte " << at << ": " << why;
  }
  EXPECT_GT(errors, 280);
  EXPECT_NE(read("XXXXXXXXXXXXXXXXXXXXXXXX").find("not a first-shot file (wrong magic)"), std::string::npos);
  EXPECT_NE(read(good + "x").find("corrupted (bytes after the end mark)"), std::string::npos);
  EXPECT_NE(read(good.substr(0, good.size() - 8)).find("truncated (no end mark)"), std::string::npos);

  test::write_file(path, good);
  unsigned long long seed = 0;
  EXPECT_NE(message_of([&] { read_stored_plan(path, s.mesh.face_count() + 1, seed); })
                .find("plan: made for a mesh of another number of faces"),
            std::string::npos);
  // The plan's points: the good file's are Halton (first_shot.sequence's default).
  test::write_file(path, good);
  EXPECT_TRUE(read_stored_plan(path, s.mesh.face_count(), seed).halton);
  // A plan frame alone, of the given varints.
  const auto plan_file = [&](std::initializer_list<uint64_t> values) {
    std::string raw;
    for (uint64_t v : values) linestore::put_varint(raw, v);
    const std::string frame = linestore::zstd_compress(raw, 3, true);
    std::string file = good.substr(0, 8);
    for (uint64_t v : {uint64_t{raw.size()}, uint64_t{frame.size()}})
      for (int i = 0; i < 8; ++i) file += static_cast<char>(v >> (8 * i));
    test::write_file(path, file + frame);
  };
  // Another format version, well formed otherwise.
  plan_file({3, 1, 4096, 64});
  EXPECT_NE(message_of([&] { read_stored_plan(path, s.mesh.face_count(), seed); })
                .find("plan: written by another version of mpath"),
            std::string::npos);
  // Version 1 (before first_shot.sequence): independent points, no sequence field.
  plan_file({1, 7, 4096, 64, uint64_t{s.mesh.face_count()}, 1, 3, 100, 0});
  const FirstShotPlan v1 = read_stored_plan(path, s.mesh.face_count(), seed);
  EXPECT_FALSE(v1.halton);
  EXPECT_EQ(seed, 7u);
  EXPECT_EQ(v1.emitters, std::vector<int>{2});
  EXPECT_EQ(v1.lines(), 100u);
  // Version 2 with a sequence other than 0 or 1.
  plan_file({2, 7, 4096, 64, uint64_t{s.mesh.face_count()}, 1, 3, 100, 0, 2});
  EXPECT_NE(message_of([&] { read_stored_plan(path, s.mesh.face_count(), seed); }).find("plan: corrupted"),
            std::string::npos);
}

// End to end: mpath-preprocess writes first_shot.bin, mpath-solve reads it
// (the report says so) and solves what it solves without the file; a run
// with another first_shot.lines traces its own and says why.
TEST(StoredShot, TheSolveReadsThePreprocessorsFirstShot) {
  TempDir dir;
  const std::string config = std::string(MPATH_SOURCE_DIR) + "/configs/cornell_box.toml";
  const std::string common = " -q lines.total=150000 store.chunk_lines=4096 solver.method=hierarchical output.png=false"
                             " output.exr=false store.dir=" + (dir / "store").string();
  const auto solve = [&](const std::string& out, const std::string& more) {
    const test::RunResult r = test::run(test::solve_bin() + " " + config + common + " output.dir=" + (dir / out).string() + more);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return nlohmann::json::parse(test::read_file(dir / out / "report.json"));
  };
  ASSERT_EQ(test::run(test::program_bin("mpath-preprocess") + " " + config + common).exit_code, 0);
  ASSERT_TRUE(std::filesystem::exists(dir / "store" / kStoredShotFile));
  const auto stats = nlohmann::json::parse(test::read_file(dir / "store" / "preprocess.json"));
  // first_shot.lines = 0: the pilot's share of lines.total, recorded in the manifest for the solves.
  const double share = stats["first_shot_share"].get<double>();
  EXPECT_GE(share, 0.125);
  EXPECT_LE(share, 4.0);
  const uint64_t lines = stats["first_shot_lines"].get<uint64_t>();
  EXPECT_EQ(lines, static_cast<uint64_t>(std::llround(share * 150'000)));
  EXPECT_EQ(nlohmann::json::parse(test::read_file(dir / "store" / "manifest.json"))["first_shot_lines"].get<uint64_t>(),
            lines);

  const nlohmann::json read = solve("read", "");
  EXPECT_TRUE(read["first_shot"]["from_store"].get<bool>());
  EXPECT_EQ(read["first_shot"]["lines"].get<uint64_t>(), lines);
  EXPECT_EQ(read["first_shot"]["lines_from"].get<std::string>(), "store");
  EXPECT_LT(std::abs(read["energy"]["relative_residual"].get<double>()), 1e-9);
  // Both shots read and every face carried by the stored lines: nothing
  // needs a traced line, and the solve builds no BVH (shoot_unshot with the
  // on-demand tracer); a solve tracing its first shot builds it.
  EXPECT_TRUE(read["second_shot"]["from_store"].get<bool>());
  EXPECT_EQ(read["lines"]["local_uncarried"].get<uint64_t>(), 0u);
  EXPECT_EQ(read["timings"]["bvh"].get<double>(), 0.0);

  const nlohmann::json other = solve("other", " first_shot.lines=60000");
  EXPECT_GT(other["timings"]["bvh"].get<double>(), 0.0);
  EXPECT_FALSE(other["first_shot"]["from_store"].get<bool>());
  EXPECT_NE(other["first_shot"]["traced_because"].get<std::string>().find("other line counts"), std::string::npos);

  std::filesystem::rename(dir / "store" / kStoredShotFile, dir / "first_shot.kept");
  const nlohmann::json traced = solve("traced", "");
  EXPECT_FALSE(traced["first_shot"]["from_store"].get<bool>());
  EXPECT_EQ(test::read_file(dir / "read" / "solution.ply"), test::read_file(dir / "traced" / "solution.ply"))
      << "the solutions agree to the last bit of their floats";
  // mpath-preprocess run again keeps the store and writes the missing first shot.
  ASSERT_EQ(test::run(test::program_bin("mpath-preprocess") + " " + config + common).exit_code, 0);
  const std::string good = test::read_file(dir / "first_shot.kept");
  EXPECT_EQ(test::read_file(dir / "store" / kStoredShotFile), good);
  // A damaged one (a byte of its last frame of lines, which the plan does
  // not show) is refused by the solve and written again by the preprocess,
  // as the solve's message says.
  std::string bad = good;
  bad[bad.size() - 20] = static_cast<char>(bad[bad.size() - 20] ^ 0x10);
  test::write_file(dir / "store" / kStoredShotFile, bad);
  const test::RunResult refused =
      test::run(test::solve_bin() + " " + config + common + " output.dir=" + (dir / "refused").string());
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.output.find("run mpath-preprocess again"), std::string::npos) << refused.output;
  ASSERT_EQ(test::run(test::program_bin("mpath-preprocess") + " " + config + common).exit_code, 0);
  EXPECT_EQ(test::read_file(dir / "store" / kStoredShotFile), good);
}

// End to end: mpath-preprocess writes second_shot.bin after the first shot,
// the solve reads it and solves what it solves tracing it; a run with
// another second_shot.share traces its own and says why; a damaged file is
// refused by the solve and written again by the preprocess.
TEST(StoredShot, TheSolveReadsThePreprocessorsSecondShot) {
  TempDir dir;
  const std::string config = std::string(MPATH_SOURCE_DIR) + "/configs/cornell_box.toml";
  const std::string common = " -q lines.total=150000 store.chunk_lines=4096 solver.method=hierarchical output.png=false"
                             " output.exr=false store.dir=" + (dir / "store").string();
  const auto path = dir / "store" / kStoredSecondShotFile;
  const auto solve = [&](const std::string& out, const std::string& more) {
    const test::RunResult r = test::run(test::solve_bin() + " " + config + common + " output.dir=" + (dir / out).string() + more);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return nlohmann::json::parse(test::read_file(dir / out / "report.json"));
  };
  ASSERT_EQ(test::run(test::program_bin("mpath-preprocess") + " " + config + common).exit_code, 0);
  ASSERT_TRUE(std::filesystem::exists(path));
  const auto stats = nlohmann::json::parse(test::read_file(dir / "store" / "preprocess.json"));
  const uint64_t lines = stats["second_shot_lines"].get<uint64_t>();
  EXPECT_NEAR(static_cast<double>(lines), 0.25 * 150'000, 100) << "second_shot.share's lines, at least one a face";
  EXPECT_EQ(stats["second_shot_bytes"].get<uint64_t>(), std::filesystem::file_size(path));

  const nlohmann::json read = solve("read", "");
  EXPECT_TRUE(read["second_shot"]["from_store"].get<bool>()) << read["second_shot"];
  EXPECT_EQ(read["second_shot"]["lines"].get<uint64_t>(), lines);
  EXPECT_GT(read["second_shot"]["faces"].get<uint64_t>(), 0u);
  EXPECT_LT(std::abs(read["energy"]["relative_residual"].get<double>()), 1e-9);

  const nlohmann::json other = solve("other", " second_shot.share=0.5");
  EXPECT_FALSE(other["second_shot"]["from_store"].get<bool>());
  EXPECT_NE(other["second_shot"]["traced_because"].get<std::string>().find("second_shot.share changed"), std::string::npos)
      << other["second_shot"];

  std::filesystem::rename(path, dir / "second_shot.kept");
  const nlohmann::json traced = solve("traced", "");
  EXPECT_FALSE(traced["second_shot"]["from_store"].get<bool>());
  EXPECT_NE(traced["second_shot"]["traced_because"].get<std::string>().find("has no second_shot.bin"), std::string::npos);
  EXPECT_EQ(test::read_file(dir / "read" / "solution.ply"), test::read_file(dir / "traced" / "solution.ply"))
      << "the solutions agree to the last bit of their floats";
  ASSERT_EQ(test::run(test::program_bin("mpath-preprocess") + " " + config + common).exit_code, 0);
  const std::string good = test::read_file(dir / "second_shot.kept");
  EXPECT_EQ(test::read_file(path), good) << "written again, the same";
  std::string bad = good;
  bad[bad.size() - 20] = static_cast<char>(bad[bad.size() - 20] ^ 0x10);
  test::write_file(path, bad);
  const test::RunResult refused =
      test::run(test::solve_bin() + " " + config + common + " output.dir=" + (dir / "refused").string());
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.output.find("second_shot.bin"), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("run mpath-preprocess again"), std::string::npos) << refused.output;
  ASSERT_EQ(test::run(test::program_bin("mpath-preprocess") + " " + config + common).exit_code, 0);
  EXPECT_EQ(test::read_file(path), good);
  // A preprocess with second_shot.share = 0 plans none and leaves no file.
  ASSERT_EQ(test::run(test::program_bin("mpath-preprocess") + " " + config + common + " second_shot.share=0").exit_code, 0);
  EXPECT_FALSE(std::filesystem::exists(path));
}

// 1 to 3 lights at random places in a random room (random_room's box of
// w x d x h lies within 4 x 3.5 x 2 m; a light may fall inside a box): an
// isotropic one and downlights of a random candela table, tilted.
std::vector<PointLight> random_lights(unsigned seed, const PatchMesh& mesh) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<PointLight> lights;
  const int n = 1 + static_cast<int>(seed % 3);
  for (int l = 0; l < n; ++l) {
    LightOptions o;
    o.name = fmt::format("light {}", l);
    const Vec3 lo = mesh.bounds.lo, size = mesh.bounds.hi - mesh.bounds.lo;
    o.position = {lo.x + (0.1 + 0.8 * u(rng)) * size.x, lo.y + (0.1 + 0.8 * u(rng)) * size.y,
                  lo.z + (0.5 + 0.45 * u(rng)) * size.z};
    o.intensity_cd = 100 + 900 * u(rng);
    o.nadir = {0.3 * (u(rng) - 0.5), 0.3 * (u(rng) - 0.5), -1};
    PointLight light = make_light(o);
    if (l > 0) {  // a downlight: intensity falling with the angle from nadir, ragged across C planes
      std::vector<double> vertical, horizontal{0, 90, 180, 270, 360}, candela;
      for (int v = 0; v <= 90; v += 15) vertical.push_back(v);
      for (size_t h = 0; h < horizontal.size(); ++h)
        for (size_t v = 0; v < vertical.size(); ++v)
          candela.push_back(v + 1 == vertical.size() ? 0.0 : (500 + 300 * u(rng)) * std::cos(vertical[v] * 0.0174533));
      for (size_t v = 0; v < vertical.size(); ++v) candela[4 * vertical.size() + v] = candela[v];  // 360 = 0
      light.distribution = LightDistribution(vertical, horizontal, candela);
    }
    lights.push_back(light);
  }
  return lights;
}

// Read back, the stored lights' shot is the traced one (shoot_lights), on
// random rooms with random lights; the lines carry this run's power.
TEST(StoredShot, ReadingTheLightsShotGivesWhatTracingItGives) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    TempDir dir;
    Prepared s = prepared_room(random_room(seed), 0.02);
    const Tracer tracer(s.mesh);
    std::vector<PointLight> lights = random_lights(seed, s.mesh);
    Options o;
    o.lines.seed = seed;
    o.solver.shards = 1 + static_cast<int>(seed % 4);
    std::vector<long long> asked;
    std::vector<uint64_t> lines;
    for (const PointLight& l : lights) {
      asked.push_back(10'000 + 3'917 * seed);
      lines.push_back(light_line_count(l, asked.back()));
    }
    const auto path = dir / kStoredLightsFile;
    write_stored_lights(path, s.mesh, tracer, lights, lines, seed, 3);
    RadiosityState traced = s.state, stored = s.state;
    EXPECT_EQ(shoot_lights(o, s.mesh, tracer, traced, lights, asked), lines);
    LightsShotStats stats;
    ASSERT_EQ(replay_stored_lights(path, s.mesh, lights, lines, seed, stored, stats), "") << "room " << seed;
    EXPECT_TRUE(stats.stored);
    EXPECT_EQ(stats.lines, std::accumulate(lines.begin(), lines.end(), uint64_t{0}));
    expect_same_state(traced, stored, fmt::format("room {}", seed));
    for (int c = 0; c < 3; ++c) EXPECT_EQ(traced.energy.emitted[c], stored.energy.emitted[c]);
    // The room's emitting faces are not shot here: what the lights emit is
    // what their lines left absorbed, escaped or unshot.
    EXPECT_LT(std::abs(stored.energy_residual() - s.state.energy_residual()), 1e-12 * stored.emitted_total())
        << "emitted = absorbed + escaped + unshot";
    // Dimmed lights send the same lines with their power of this run.
    for (PointLight& l : lights) l.options.multiplier = 0.25 + 0.5 * (seed % 2);
    RadiosityState dimmed_traced = s.state, dimmed_stored = s.state;
    shoot_lights(o, s.mesh, tracer, dimmed_traced, lights, asked);
    ASSERT_EQ(replay_stored_lights(path, s.mesh, lights, lines, seed, dimmed_stored, stats), "") << "room " << seed;
    expect_same_state(dimmed_traced, dimmed_stored, fmt::format("room {}, dimmed", seed));
  }
}

// A lights' shot of other lights, lines or seed is not read, and says why;
// a damaged one is an InputError naming the file and leaves the state.
TEST(StoredShot, ALightsShotOfOtherLightsIsNotReadAndSaysWhy) {
  TempDir dir;
  Prepared s = prepared_room(random_room(3), 0.02);
  const Tracer tracer(s.mesh);
  const std::vector<PointLight> lights = random_lights(3, s.mesh);
  ASSERT_EQ(lights.size(), 1u);
  const std::vector<uint64_t> lines{20'000};
  const auto path = dir / kStoredLightsFile;
  LightsShotStats stats;
  RadiosityState state = s.state;
  EXPECT_NE(replay_stored_lights(path, s.mesh, lights, lines, 1, state, stats).find("has no lights_shot.bin"),
            std::string::npos);
  write_stored_lights(path, s.mesh, tracer, lights, lines, 1, 3);
  EXPECT_NE(replay_stored_lights(path, s.mesh, lights, lines, 2, state, stats).find("drawn with lines.seed = 1"),
            std::string::npos);
  EXPECT_NE(replay_stored_lights(path, s.mesh, lights, {30'000}, 1, state, stats).find("lights are not the store's"),
            std::string::npos);
  std::vector<PointLight> moved = lights;
  moved[0].options.position.x += 0.01;
  EXPECT_NE(replay_stored_lights(path, s.mesh, moved, lines, 1, state, stats).find("moved, re-aimed"), std::string::npos);
  std::vector<PointLight> two = random_lights(2, s.mesh);
  EXPECT_NE(replay_stored_lights(path, s.mesh, two, {20'000, 20'000}, 1, state, stats).find("2 light(s)"),
            std::string::npos);
  EXPECT_EQ(state.phi, s.state.phi) << "nothing read";
  // The first shot's file under the lights' name: another kind of file.
  write_stored_shot(dir / "first.bin", s.mesh, tracer, plan_first_shot(s.mesh, s.state, 5'000, {}), 1, 3);
  std::filesystem::copy_file(dir / "first.bin", path, std::filesystem::copy_options::overwrite_existing);
  EXPECT_NE(message_of([&] { replay_stored_lights(path, s.mesh, lights, lines, 1, state, stats); })
                .find("not a lights-shot file"),
            std::string::npos);
  write_stored_lights(path, s.mesh, tracer, lights, lines, 1, 3);
  std::string bad = test::read_file(path);
  bad[bad.size() - 20] = static_cast<char>(bad[bad.size() - 20] ^ 0x10);
  test::write_file(path, bad);
  const std::string why = message_of([&] { replay_stored_lights(path, s.mesh, lights, lines, 1, state, stats); });
  EXPECT_NE(why.find("lights_shot.bin"), std::string::npos) << why;
  EXPECT_NE(why.find("run mpath-preprocess again"), std::string::npos) << why;
  EXPECT_EQ(state.phi, s.state.phi) << "nothing read";
}

// End to end: mpath-preprocess stores the lights' shot of a room lit by a
// point source and an IES luminaire, and a solve reads it: the same
// solution as one that traces it; a moved light is traced and says why, a damaged file makes the solve exit 1, and with
// first_shot.sequence = "random" no file is written.
TEST(StoredShot, TheSolveReadsThePreprocessorsLightsShot) {
  TempDir dir;
  std::filesystem::copy(std::string(MPATH_SOURCE_DIR) + "/configs/room", dir / "room",
                        std::filesystem::copy_options::recursive);
  test::write_file(dir / "downlight.ies",
                   "IESNA:LM-63-2002\nTILT=NONE\n1 1000 1 3 1 1 2 0.1 0.1 0\n1 1 50\n0 45 90\n0\n900 500 0\n");
  test::write_file(dir / "run.toml", "[scene]\nfile = \"room/room.obj\"\ntwo_sided = [\"lampshade\"]\n"
                                     "[scene.emitters]\nbulb = 0\n[mesh]\nmax_patch_area = 0.05\n"
                                     "[lines]\ntotal = 150000\n[solver]\nmethod = \"hierarchical\"\n"
                                     "[store]\ndir = \"store\"\nchunk_lines = 4096\n[output]\npng = false\nexr = false\n"
                                     "[[light]]\nname = \"bulb\"\nposition = [2.0, 2.0, 2.2]\nintensity_cd = 400\n"
                                     "[[light]]\nname = \"downlight\"\nposition = [3.5, 1.5, 2.6]\nies = \"downlight.ies\"\n");
  const std::string config = (dir / "run.toml").string();
  const auto path = dir / "store" / kStoredLightsFile;
  const auto solve = [&](const std::string& out, const std::string& more) {
    const test::RunResult r = test::run(test::solve_bin() + " -q " + config + " output.dir=" + (dir / out).string() + more);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return nlohmann::json::parse(test::read_file(dir / out / "report.json"));
  };
  ASSERT_EQ(test::run(test::program_bin("mpath-preprocess") + " -q " + config).exit_code, 0);
  ASSERT_TRUE(std::filesystem::exists(path));
  const auto stats = nlohmann::json::parse(test::read_file(dir / "store" / "preprocess.json"));
  EXPECT_EQ(stats["lights_shot_bytes"].get<uint64_t>(), std::filesystem::file_size(path));

  const nlohmann::json read = solve("read", "");
  EXPECT_TRUE(read["lights_shot"]["from_store"].get<bool>()) << read["lights_shot"];
  EXPECT_EQ(read["lights_shot"]["lines"].get<uint64_t>(), stats["lights_shot_lines"].get<uint64_t>());
  EXPECT_EQ(read["lights"][0]["first_shot_lines"].get<uint64_t>() + read["lights"][1]["first_shot_lines"].get<uint64_t>(),
            stats["lights_shot_lines"].get<uint64_t>());
  EXPECT_TRUE(read["second_shot"]["from_store"].get<bool>()) << "planned from the state the stored lights give";
  EXPECT_LT(std::abs(read["energy"]["relative_residual"].get<double>()), 1e-9);

  std::filesystem::rename(path, dir / "lights.kept");
  const nlohmann::json traced = solve("traced", "");
  EXPECT_FALSE(traced["lights_shot"]["from_store"].get<bool>());
  EXPECT_NE(traced["lights_shot"]["traced_because"].get<std::string>().find("has no lights_shot.bin"), std::string::npos);
  EXPECT_EQ(test::read_file(dir / "read" / "solution.ply"), test::read_file(dir / "traced" / "solution.ply"))
      << "the solutions agree to the last bit of their floats";
  std::filesystem::rename(dir / "lights.kept", path);

  // Another place for the bulb: its lines go elsewhere.
  std::string text = test::read_file(dir / "run.toml");
  text.replace(text.find("[2.0, 2.0, 2.2]"), 15, "[2.0, 2.1, 2.2]");
  test::write_file(dir / "run.toml", text);
  const nlohmann::json elsewhere = solve("elsewhere", "");
  EXPECT_FALSE(elsewhere["lights_shot"]["from_store"].get<bool>());
  EXPECT_NE(elsewhere["lights_shot"]["traced_because"].get<std::string>().find("moved"), std::string::npos)
      << elsewhere["lights_shot"];
  text.replace(text.find("[2.0, 2.1, 2.2]"), 15, "[2.0, 2.0, 2.2]");
  test::write_file(dir / "run.toml", text);

  const std::string good = test::read_file(path);
  std::string bad = good;
  bad[bad.size() - 20] = static_cast<char>(bad[bad.size() - 20] ^ 0x10);
  test::write_file(path, bad);
  const test::RunResult refused = test::run(test::solve_bin() + " -q " + config + " output.dir=" + (dir / "refused").string());
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.output.find("lights_shot.bin"), std::string::npos) << refused.output;
  ASSERT_EQ(test::run(test::program_bin("mpath-preprocess") + " -q " + config).exit_code, 0);
  EXPECT_EQ(test::read_file(path), good) << "written again, the same";
  ASSERT_EQ(test::run(test::program_bin("mpath-preprocess") + " -q " + config + " first_shot.sequence=\"random\"").exit_code, 0);
  EXPECT_FALSE(std::filesystem::exists(path)) << "a light's random points depend on the shards";
}

// Where every surface emits, first_shot.mode = "auto" leaves faces to the
// global lines by the store's crossing counts, which mpath-preprocess
// counts while tracing and the solve reads from the store: the plans agree
// and the solve reads the stored shot, on a hierarchy of transparent boxes
// (the default) and of the paper's boxes.
TEST(StoredShot, PreprocessAndSolvePlanAlikeWhenGlobalLinesTakeEmitters) {
  for (const std::string transport : {"lines", "transmittance"}) {
    TempDir dir;
    Scene scene = test::furnace_scene(0.5, 1.0);
    test::add_table(scene, 1.0, 0.5, 0, "table");
    test::write_obj(scene, dir / "furnace");
    test::write_file(dir / "run.toml", "[scene]\nfile = \"furnace.obj\"\n[mesh]\nmax_patch_area = 0.02\n"
                                       "[first_shot]\nlines = 570000\n[lines]\ntotal = 200000\n[solver]\nmethod = \"hierarchical\"\niterations = 4\n"
                                       "[hierarchy]\ntransport = \"" + transport + "\"\n"
                                       "[store]\ndir = \"store\"\n[output]\npng = false\nexr = false\n");
    const std::string config = (dir / "run.toml").string();
    ASSERT_EQ(test::run(test::program_bin("mpath-preprocess") + " -q " + config).exit_code, 0);
    const auto solve = [&](const std::string& out) {
      const test::RunResult r = test::run(test::solve_bin() + " -q " + config + " output.dir=" + (dir / out).string());
      EXPECT_EQ(r.exit_code, 0) << r.output;
      return nlohmann::json::parse(test::read_file(dir / out / "report.json"));
    };
    const nlohmann::json read = solve("read");
    EXPECT_TRUE(read["first_shot"]["from_store"].get<bool>()) << transport << ": " << read["first_shot"];
    // first_shot.lines where a face's local lines are about as many as its
    // crossings: the faces fall on both sides of the rule, so crossings
    // counted otherwise would move some.
    EXPECT_GT(read["first_shot"]["global_emitter_faces"].get<uint64_t>(), 100u) << transport;
    EXPECT_GT(read["first_shot"]["emitter_faces"].get<uint64_t>(), 600u) << transport << ": 200 (440) faces in contact and more";
    std::filesystem::remove(dir / "store" / kStoredShotFile);
    solve("traced");
    EXPECT_EQ(test::read_file(dir / "read" / "solution.ply"), test::read_file(dir / "traced" / "solution.ply")) << transport;
  }
}

}  // namespace
}  // namespace mpath
