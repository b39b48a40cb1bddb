// The store end to end: mpath-preprocess then mpath-solve (multipath), against
// an in-memory solve over the same lines, across shards and interruptions,
// and with damaged or mismatched stores.
#include <gtest/gtest.h>
#include <unistd.h>

#include <nlohmann/json.hpp>
#include <algorithm>
#include <iterator>
#include <random>
#include <set>

#include "line_tracing.h"
#include "scene_readers.h"
#include "box_store.h"
#include "directory_lock.h"
#include "hash.h"
#include "hierarchical.h"
#include "test_util.h"
#include "transport.h"

namespace mpath {
namespace {

using test::RunResult;
using test::TempDir;

const std::string kCornell = std::string(MPATH_SOURCE_DIR) + "/configs/cornell_box.toml";
const std::string kSmall = " lines.total=150000 store.chunk_lines=4096 first_shot.lines=50000";

// Quiet unless the arguments ask for a log level.
std::string quiet(const std::string& args) { return args.find("--log-level") == std::string::npos ? " -q " + args : " " + args; }
RunResult preprocess(const std::string& args) {
  return test::run(test::program_bin("mpath-preprocess") + " " + kCornell + kSmall + " solver.method=multipath" + quiet(args));
}
RunResult solve(const std::string& args) {
  return test::run(test::solve_bin() + " " + kCornell + kSmall + " solver.method=multipath output.png=false" + quiet(args));
}

// A chunk's lines are stored in order of (first crossing, last crossing),
// ties in line order: the radix sort gives what sorting (key, line) pairs
// gives, on keys of few distinct values (many ties), of the stored form
// (patch ids up to 2^24 in both halves, 0 for an empty line), and of any 64 bits.
TEST(Store, LinesAreOrderedAsSortingKeyAndLinePairsOrdersThem) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 60; ++trial) {
    const size_t n = std::uniform_int_distribution<size_t>(0, 70'000)(rng) >> (trial % 4 * 4);
    std::vector<uint64_t> key(n);
    for (uint64_t& k : key) {
      const uint64_t first = rng() % (trial % 3 == 0 ? 5 : 1u << 24), last = rng() % (1u << 24);
      k = trial % 3 == 2 ? rng() : (rng() % 8 == 0 ? 0 : ((first + 1) << 32) | last);
    }
    std::vector<std::pair<uint64_t, uint32_t>> pairs(n);
    for (size_t i = 0; i < n; ++i) pairs[i] = {key[i], static_cast<uint32_t>(i)};
    std::sort(pairs.begin(), pairs.end());
    std::vector<uint32_t> order;
    order_by_key(key, order);
    ASSERT_EQ(order.size(), n);
    for (size_t i = 0; i < n; ++i) ASSERT_EQ(order[i], pairs[i].second) << "trial " << trial << ", place " << i;
  }
}

TEST(Store, StoredLineSolveEqualsAnInMemorySolveOverTheSameLines) {
  TempDir dir;
  Options o = test::test_options(150'000, 50'000, 0.002);
  o.scene.file = std::string(MPATH_SOURCE_DIR) + "/configs/cornell_box/cornell_box.obj";
  o.store.chunk_lines = 4096;
  o.store.dir = dir.path();
  o.solver.method = SolverMethod::multipath;
  o.solver.iterations = 3;
  ASSERT_EQ(preprocess("store.dir=" + dir.path().string() + " mesh.max_patch_area=0.002 solver.threads=2 lines.sequence=random").exit_code, 0);

  std::vector<std::string> warnings;
  const Scene scene = load_scene(o.scene, o.mesh.curve_segments, warnings);
  const PatchMesh mesh = build_mesh(scene, o.mesh.max_patch_area);
  const Tracer tracer(mesh);
  const BoxStore store(o, mesh);
  ASSERT_EQ(store.box_count(), 1u);

  // In memory: the same chunks traced again, the same shards, the same passes.
  const Hierarchy flat = build_hierarchy(mesh, o.hierarchy, true);
  const ChunkTracer chunks(o, mesh, flat, 0, static_cast<uint64_t>(o.lines.total));
  std::vector<linestore::DecodedChunk> records(chunks.chunk_count());
  TracedChunk traced;
  BoxTally tally = chunks.empty_tally();
  for (uint64_t c = 0; c < chunks.chunk_count(); ++c) {
    chunks.trace(c, traced, tally);
    records[c] = traced.stored();
  }
  // Counted here, independently of the store; patch k of the root is patch k of the mesh.
  std::vector<double> crossings(mesh.face_count(), 0.0);
  for (size_t p = 0; p < mesh.patches.size(); ++p)
    for (int face : mesh.patch_faces[p])
      if (face >= 0) crossings[face] = tally.counts.patch_crossings[p];
  EXPECT_EQ(crossings, store.face_crossings(mesh.face_count()));

  RadiosityState from_store = make_state(scene, mesh), in_memory = make_state(scene, mesh);
  first_shot(mesh, tracer, from_store, o.first_shot.lines, o.lines.seed, 2);
  first_shot(mesh, tracer, in_memory, o.first_shot.lines, o.lines.seed, 2);
  for (unsigned pass = 1; pass <= 3; ++pass) {
    hierarchical_iteration(store, from_store, pass, 2);
    const PassInputs in = PassInputs::start(in_memory, mesh, crossings);
    std::vector<ShardAccumulator> acc(2);
    for (int s = 0; s < 2; ++s) {
      acc[s].reset(mesh.face_count());
      std::vector<LineHit> hits;
      std::vector<uint32_t> order;
      for (uint64_t c = records.size() * s / 2; c < records.size() * (s + 1) / 2; ++c) {
        chunk_line_order(store.seed(), 2 * pass, 0, c, records[c].lines(), order);  // the root's pass of iteration p is rotation 2p
        for (uint32_t l : order) {
          hits.clear();
          for (uint32_t k = records[c].first[l]; k < records[c].first[l + 1]; ++k)
            hits.push_back({0.0, static_cast<int>(records[c].events[k].id), records[c].events[k].along});
          transport_line(in, hits, acc[s]);
        }
      }
    }
    merge_pass(in, acc, in_memory);
  }
  for (size_t i = 0; i < from_store.phi.size(); ++i) ASSERT_NEAR(from_store.phi[i], in_memory.phi[i], 1e-12 * std::fabs(in_memory.phi[i]));
  EXPECT_LT(std::fabs(from_store.energy_residual()) / from_store.emitted_total(), 1e-10);
}

// A box's randomised Halton lines: the box holds exactly the points 0..N-1
// of its sequence, but a chunk holds points from the whole sequence, not a
// run of neighbours (docs/algorithm.md, "Order of lines in a pass"). Lines
// are compared by what they meet (patch and direction, in order); with 8,466
// patches two lines rarely meet the same.
TEST(Store, AChunkOfHaltonLinesHoldsPointsFromTheWholeSequence) {
  Options o = test::test_options(16'384, 0, 0.002);
  o.scene.file = std::string(MPATH_SOURCE_DIR) + "/configs/cornell_box/cornell_box.obj";
  o.lines.sequence = "halton";
  o.store.chunk_lines = 1024;
  std::vector<std::string> warnings;
  const Scene scene = load_scene(o.scene, o.mesh.curve_segments, warnings);
  const PatchMesh mesh = build_mesh(scene, o.mesh.max_patch_area);
  const Hierarchy flat = build_hierarchy(mesh, o.hierarchy, true);
  const uint64_t total = static_cast<uint64_t>(o.lines.total);
  const ChunkTracer chunks(o, mesh, flat, 0, total);
  ASSERT_EQ(chunks.chunk_count(), 16u);

  using Met = std::vector<std::pair<uint32_t, bool>>;
  std::multiset<Met> stored, first_chunk;
  TracedChunk traced;
  BoxTally tally = chunks.empty_tally();
  for (uint64_t c = 0; c < chunks.chunk_count(); ++c) {
    chunks.trace(c, traced, tally);
    const linestore::DecodedChunk& l = traced.lines;
    for (size_t i = 0; i < l.lines(); ++i) {
      Met met;
      for (uint32_t k = l.first[i]; k < l.first[i + 1]; ++k) met.push_back({l.events[k].id, l.events[k].along});
      stored.insert(met);
      if (c == 0) first_chunk.insert(met);
    }
  }
  // The sequence's points by index, traced here as the preprocessor traces them.
  const Tracer tracer(mesh);
  const LineSequence points(o.lines.sequence, o.lines.seed, 0);
  const BoxLineSampler sampler(line_box(flat.boxes[0].bounds));
  Rng unused = make_rng(0, 0, 0);
  std::multiset<Met> sequence, first_points;
  std::vector<LineHit> hits;
  for (uint64_t i = 0; i < total; ++i) {
    double u[4];
    points.point(i, unused, u);
    const GlobalLine line = sampler.sample(u);
    tracer.all_hits(line.org, line.dir, line.length, hits);
    order_ties(mesh, tracer.tie_epsilon(), hits, tracer.live_faces());
    Met met;
    for (const LineHit& h : hits) met.push_back({static_cast<uint32_t>(h.patch), h.along});
    sequence.insert(met);
    if (i < 1024) first_points.insert(met);
  }
  EXPECT_TRUE(stored == sequence);
  // Chunk 0 against points 0..1023: drawn from all 16,384, about 1024 / 16 =
  // 64 of them are among those (a binomial count, standard deviation 8);
  // consecutive points would make all 1024 the same.
  std::vector<Met> common;
  std::set_intersection(first_chunk.begin(), first_chunk.end(), first_points.begin(), first_points.end(),
                        std::back_inserter(common));
  EXPECT_LT(common.size(), 128u);
}

TEST(Store, ShardedStoreEqualsOneMadeAtOnceAndRerunsSkipFinishedFiles) {
  TempDir dir;
  const std::string once = (dir / "once").string(), parts = (dir / "parts").string();
  ASSERT_EQ(preprocess("store.dir=" + once).exit_code, 0);
  RunResult r = preprocess("store.dir=" + parts + " --shard 2/3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "parts/manifest.json"));  // incomplete until every shard ran
  ASSERT_EQ(preprocess("store.dir=" + parts + " --shard 3/3").exit_code, 0);
  ASSERT_EQ(preprocess("store.dir=" + parts + " --shard 1/3").exit_code, 0);
  EXPECT_TRUE(std::filesystem::exists(dir / "parts/manifest.json"));
  r = preprocess("store.dir=" + parts + " --shard 2/3 --log-level info");
  EXPECT_NE(r.output.find("not traced again"), std::string::npos) << r.output;

  ASSERT_EQ(solve("store.dir=" + once + " output.dir=" + (dir / "a").string()).exit_code, 0);
  ASSERT_EQ(solve("store.dir=" + parts + " output.dir=" + (dir / "b").string()).exit_code, 0);
  EXPECT_EQ(test::read_file(dir / "a/solution.ply"), test::read_file(dir / "b/solution.ply"));
  const auto report = nlohmann::json::parse(test::read_file(dir / "b/report.json"));
  EXPECT_EQ(report["store"]["lines"], 150000);
  const auto& e = report["energy"];
  EXPECT_NEAR(e["emitted"].get<double>(), e["absorbed"].get<double>() + e["escaped"].get<double>() + e["unshot"].get<double>(),
              1e-9 * e["emitted"].get<double>());
}

// A store is made of the geometry and the line settings only: a reflectance
// changed in the scene file, or by scene.materials in the config, is solved
// on the kept store with exactly the answer of a fresh preprocess; moving a
// vertex is refused.
TEST(Store, MaterialsChangeWithoutRetracing) {
  TempDir dir;
  const std::string src = std::string(MPATH_SOURCE_DIR) + "/configs/cornell_box/cornell_box.";
  const std::string obj = test::read_file(src + "obj"), mtl = test::read_file(src + "mtl");
  test::write_file(dir / "cornell_box.obj", obj);
  test::write_file(dir / "cornell_box.mtl", mtl);
  const std::string scene = " scene.file=" + (dir / "cornell_box.obj").string();
  const std::string kept = scene + " store.dir=" + (dir / "kept").string();
  ASSERT_EQ(preprocess(kept).exit_code, 0);
  const size_t at = mtl.find("Kd 0.7377 0.7361 0.7373");
  ASSERT_NE(at, std::string::npos);
  test::write_file(dir / "cornell_box.mtl", std::string(mtl).replace(at, 23, "Kd 0.3 0.4 0.5"));
  RunResult r = solve(kept + " output.dir=" + (dir / "a").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string fresh = scene + " store.dir=" + (dir / "fresh").string();
  ASSERT_EQ(preprocess(fresh).exit_code, 0);
  ASSERT_EQ(solve(fresh + " output.dir=" + (dir / "b").string()).exit_code, 0);
  const std::string a = test::read_file(dir / "a/solution.ply");
  EXPECT_EQ(a, test::read_file(dir / "b/solution.ply"));
  // The same change made in the config, on the first file.
  test::write_file(dir / "cornell_box.mtl", mtl);
  r = solve(kept + " scene.materials.white=[0.3,0.4,0.5] output.dir=" + (dir / "c").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(a, test::read_file(dir / "c/solution.ply"));
  // And the change is seen: the file's own reflectance gives another answer.
  ASSERT_EQ(solve(kept + " output.dir=" + (dir / "e").string()).exit_code, 0);
  EXPECT_NE(a, test::read_file(dir / "e/solution.ply"));
  // Geometry is not a material: a moved vertex is another store.
  const size_t v = obj.find("v 0.5528 0.0000 0.0000");
  ASSERT_NE(v, std::string::npos);
  test::write_file(dir / "cornell_box.obj", std::string(obj).replace(v, 8, "v 0.5538"));
  r = solve(kept + " output.dir=" + (dir / "d").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("mesh.hash"), std::string::npos) << r.output;
}

TEST(Store, ResumeGivesTheUninterruptedResult) {
  TempDir dir;
  const std::string store = " store.dir=" + (dir / "store").string();
  ASSERT_EQ(preprocess(store).exit_code, 0);
  const std::string tol = " solver.tolerance=1e-9";
  ASSERT_EQ(solve(store + tol + " solver.iterations=4 output.dir=" + (dir / "straight").string()).exit_code, 0);
  ASSERT_EQ(solve(store + tol + " solver.iterations=2 output.dir=" + (dir / "resumed").string()).exit_code, 0);
  const RunResult r = solve(store + tol + " solver.iterations=4 --resume --log-level info output.dir=" + (dir / "resumed").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("after 2 finished pass(es)"), std::string::npos) << r.output;
  EXPECT_EQ(test::read_file(dir / "straight/solution.ply"), test::read_file(dir / "resumed/solution.ply"));
  // A checkpoint made with other settings is refused.
  const RunResult other = solve(store + tol + " solver.iterations=5 first_shot.lines=60000 --resume output.dir=" + (dir / "resumed").string());
  EXPECT_NE(other.exit_code, 0);
  EXPECT_NE(other.output.find("made with another scene, store or config"), std::string::npos) << other.output;
}

size_t count_of(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// solver.checkpoint_seconds = 0 writes a checkpoint after the first shot and
// every pass; a long interval only after the last pass, which --resume
// continues from all the same.
TEST(Store, CheckpointsFollowSolverCheckpointSeconds) {
  TempDir dir;
  const std::string store = " store.dir=" + (dir / "store").string();
  ASSERT_EQ(preprocess(store).exit_code, 0);
  const std::string run = store + " solver.tolerance=1e-12 solver.iterations=4 --log-level debug output.dir=";
  RunResult r = solve(run + (dir / "every").string() + " solver.checkpoint_seconds=0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (int passes = 0; passes <= 4; ++passes)
    EXPECT_EQ(count_of(r.output, fmt::format("checkpoint after {} pass(es) written", passes)), 1u) << r.output;
  r = solve(run + (dir / "ends").string() + " solver.checkpoint_seconds=1e6");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(count_of(r.output, "checkpoint after"), 1u) << r.output;
  EXPECT_EQ(count_of(r.output, "checkpoint after 4 pass(es) written"), 1u) << r.output;
  EXPECT_EQ(test::read_file(dir / "every/solution.ply"), test::read_file(dir / "ends/solution.ply"));
  r = solve(store + " solver.tolerance=1e-12 solver.iterations=6 --resume --log-level info output.dir=" +
            (dir / "ends").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("after 4 finished pass(es)"), std::string::npos) << r.output;
}

TEST(Store, ResumeAfterAKilledRunGivesTheUninterruptedResult) {
  TempDir dir;
  const std::string lines = " lines.total=1000000 store.chunk_lines=16384 first_shot.lines=400000";
  const std::string store = " store.dir=" + (dir / "store").string();
  ASSERT_EQ(preprocess(store + lines).exit_code, 0);
  const std::string tol = lines + " solver.tolerance=1e-12 solver.iterations=6" + store;
  ASSERT_EQ(solve(tol + " output.dir=" + (dir / "straight").string()).exit_code, 0);
  // Kill (SIGKILL: nothing gets to clean up) as soon as the first checkpoint
  // exists (after the first shot: every one is written with an interval of 0).
  const auto killed = dir / "killed";
  const std::string command = test::solve_bin() + " " + kCornell + kSmall + tol +
                              " solver.method=multipath solver.checkpoint_seconds=0 output.png=false -q output.dir=" +
                              killed.string();
  const RunResult k = test::run("bash -c '" + command + " & pid=$!; for i in $(seq 2000); do [ -f " +
                                (killed / "checkpoint.bin").string() + " ] && break; sleep 0.005; done; kill -9 $pid; wait $pid; echo killed $?'");
  ASSERT_NE(k.output.find("killed 137"), std::string::npos) << "the run finished before it could be killed: " << k.output;
  EXPECT_FALSE(std::filesystem::exists(killed / "solution.ply"));
  const RunResult r = solve(tol + " --resume output.dir=" + killed.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(test::read_file(dir / "straight/solution.ply"), test::read_file(killed / "solution.ply"));
}

bool has_hidden_temporaries(const std::filesystem::path& dir) {
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.find(".partial") != std::string::npos || name.find(".tmp.") != std::string::npos) return true;
  }
  return false;
}

TEST(Store, InterruptedProgramsRemoveTheirTemporariesAndSayWhatToDo) {
  TempDir dir;
  const auto store = dir / "store";
  // Interrupt preprocessing while it traces (the partial file exists).
  const std::string pre = test::program_bin("mpath-preprocess") + " " + kCornell + " -q lines.total=50000000 store.dir=" + store.string();
  RunResult r = test::run("bash -c '" + pre + " & pid=$!; for i in $(seq 2000); do [ -f " +
                          (store / ".box0000.lines.partial").string() +
                          " ] && break; sleep 0.005; done; sleep 0.2; kill -INT $pid; wait $pid; echo exit $?'");
  EXPECT_NE(r.output.find("mpath-preprocess: interrupted; finished shards are kept"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("exit 130"), std::string::npos) << r.output;
  EXPECT_FALSE(has_hidden_temporaries(store));
  EXPECT_FALSE(std::filesystem::exists(store / "manifest.json"));
  EXPECT_FALSE(std::filesystem::exists(store / "box0000.lines"));
}

// A run killed with SIGKILL while writing leaves `.NAME.tmp.PID`; the next
// run that writes NAME removes it once that process is gone, and leaves the
// temporaries of running processes alone.
TEST(Store, TemporariesOfKilledRunsAreRemovedByTheNextRun) {
  TempDir dir;
  const std::string store = " store.dir=" + (dir / "store").string();
  ASSERT_EQ(preprocess(store).exit_code, 0);
  const RunResult gone = test::run("bash -c 'echo $$'");
  const std::string dead_pid = gone.output.substr(0, gone.output.find_first_of("\r\n"));
  std::filesystem::create_directories(dir / "out");
  const auto stale = dir / "out" / (".report.json.tmp." + dead_pid);
  const auto live = dir / "out" / (".report.json.tmp." + std::to_string(getppid()));  // the test's parent runs on
  test::write_file(stale, "half a report");
  test::write_file(live, "being written");
  ASSERT_EQ(solve(store + " output.dir=" + (dir / "out").string()).exit_code, 0);
  EXPECT_FALSE(std::filesystem::exists(stale));
  EXPECT_TRUE(std::filesystem::exists(live));
  EXPECT_TRUE(std::filesystem::exists(dir / "out/report.json"));
}

// Runs that would mix their files are refused by name: the test holds the
// lock a run of each kind holds, and runs the real programs against it.
TEST(Store, RunsThatWouldMixTheirFilesAreRefusedByName) {
  TempDir dir;
  const std::filesystem::path store = dir / "store";
  const std::string at = "store.dir=" + store.string() + " output.dir=" + (dir / "out").string();
  ASSERT_EQ(preprocess(at).exit_code, 0);
  const std::string pid = "(process " + std::to_string(getpid()) + ")";
  auto refused = [&](const RunResult& r, const std::string& what) {
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(what + " is in use by another mpath run " + pid), std::string::npos) << r.output;
  };
  using Role = DirectoryLock::Role;
  {  // mpath-solve reading the store
    const DirectoryLock solving(store, kLockFile, Role::reader, "store.dir", "");
    refused(preprocess(at + " lines.seed=2"), "store.dir " + store.string());
    refused(preprocess(at + " lines.seed=2 --shard 1/2"), "store.dir " + store.string());
    const RunResult other_reader = solve(at);  // solves share a store
    EXPECT_EQ(other_reader.exit_code, 0) << other_reader.output;
  }
  {  // mpath-preprocess writing it
    const DirectoryLock writing(store, kLockFile, Role::writer, "store.dir", "");
    refused(solve(at + " output.dir=" + (dir / "out2").string()), "store.dir " + store.string());
    EXPECT_FALSE(std::filesystem::exists(dir / "out2/report.json"));
  }
  {  // shard 1 of 2 being traced: shard 2 runs beside it, shard 1 again does not
    const DirectoryLock shards(store, kLockFile, Role::shard, "store.dir", "");
    const DirectoryLock first(store, std::string(kLockFile) + ".part0001of0002", Role::writer, "", "");
    refused(preprocess(at + " --shard 1/2"), "shard 1/2 of store.dir " + store.string());
    const RunResult second = preprocess(at + " --shard 2/2");
    EXPECT_EQ(second.exit_code, 0) << second.output;
    refused(preprocess(at), "store.dir " + store.string());
    refused(solve(at), "store.dir " + store.string());
  }
  {  // mpath-solve writing the outputs
    const DirectoryLock writing(dir / "out", kLockFile, Role::writer, "output.dir", "");
    refused(solve(at + " solver.method=classic"), "output.dir " + (dir / "out").string());
  }
  // The locks went with their holders: shard 1 completes the store.
  ASSERT_EQ(preprocess(at + " --shard 1/2").exit_code, 0);
  const RunResult again = solve(at);
  EXPECT_EQ(again.exit_code, 0) << again.output;
}

// Faces no stored line crosses (a millimetre cube in a kilometre room at
// 100k lines) get only the first shot's light: report.json says so.
TEST(Store, FacesNoStoredLineCrossesAreAWarning) {
  TempDir dir;
  Scene scene;
  const int black = test::add_material(scene, "black", 0.0, 0.0);
  const int lamp = test::add_material(scene, "lamp", 0.5, 1.0);
  test::add_box(scene, {-500, -500, -500}, {500, 500, 500}, true, black, test::add_object(scene, "room"));
  test::add_box(scene, {3, 2, 1}, {3.001, 2.001, 1.001}, false, lamp, test::add_object(scene, "cube"));
  const auto obj = test::write_obj(scene, dir / "tiny");
  test::write_file(dir / "tiny.toml", "[scene]\nfile = \"" + obj.string() + "\"\n[mesh]\nmax_patch_area = 1e9\n");
  const std::string args = " -q solver.method=multipath lines.total=100000 first_shot.lines=10000 store.dir=" +
                           (dir / "store").string() + " output.dir=" + (dir / "out").string() + " output.png=false";
  ASSERT_EQ(test::run(test::program_bin("mpath-preprocess") + " " + (dir / "tiny.toml").string() + args).exit_code, 0);
  const RunResult r = test::run(test::solve_bin() + " " + (dir / "tiny.toml").string() + args);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto report = nlohmann::json::parse(test::read_file(dir / "out/report.json"));
  bool found = false;
  for (const auto& w : report["warnings"]) found |= w.get<std::string>().find("6 face(s)") == 0;
  EXPECT_TRUE(found) << report["warnings"].dump();
}

TEST(Store, DamagedOrMismatchedStoresAreRefusedByName) {
  TempDir dir;
  const std::string store = (dir / "store").string();
  ASSERT_EQ(preprocess("store.dir=" + store).exit_code, 0);
  const std::string out = " output.dir=" + (dir / "out").string();

  RunResult r = solve("store.dir=" + store + " lines.total=160000" + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("lines.total: the store was made with 150000, this run has 160000"), std::string::npos) << r.output;
  r = solve("store.dir=" + store + " mesh.max_patch_area=0.001" + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("the store does not match"), std::string::npos) << r.output;

  const auto file = dir / "store/box0000.lines";
  const std::string original = test::read_file(file);
  std::string flipped = original;
  flipped[flipped.size() / 3] = static_cast<char>(flipped[flipped.size() / 3] ^ 0x40);
  test::write_file(file, flipped);
  r = solve("store.dir=" + store + out);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("box0000.lines: its contents do not match the hash in"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out/checkpoint.bin"));  // found before any work
  // The files are hashed on another thread while the scene loads
  // (solve.cpp, StoreCheck): a scene's error, and a store made for another
  // config, are still named before the damage, on one thread or two.
  for (const std::string threads : {" solver.threads=1", " solver.threads=2"}) {
    r = solve("store.dir=" + store + " lines.total=160000" + threads + out);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.output.find("lines.total: the store was made with 150000"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("do not match the hash"), std::string::npos) << r.output;
    r = solve("store.dir=" + store + " scene.file=" + (dir / "none.obj").string() + threads + out);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.output.find("none.obj"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("do not match the hash"), std::string::npos) << r.output;
    r = solve("store.dir=" + store + threads + out);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.output.find("box0000.lines: its contents do not match the hash in"), std::string::npos) << r.output;
  }

  test::write_file(file, original.substr(0, original.size() - 1000));
  r = solve("store.dir=" + store + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("box0000.lines"), std::string::npos) << r.output;

  std::filesystem::remove(file);
  r = solve("store.dir=" + store + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("box0000.lines: missing"), std::string::npos) << r.output;

  r = solve("store.dir=" + (dir / "nothing").string() + " --dry-run" + out);
  EXPECT_NE(r.exit_code, 0);  // a dry run checks the store too
  r = solve("store.dir=" + (dir / "nothing").string() + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("manifest.json: missing; run mpath-preprocess"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out/solution.ply"));
}

// A finished store is not traced again. Under the pilot budget its boxes'
// lines were fitted to the materials the preprocess saw: a rerun with the
// lamp shade's reflectance changed would give the boxes other lines, keeps
// the store all the same (it stays valid) and says so; the solve uses the
// store's own boxes and closes its energy.
TEST(Store, AFinishedStoreIsKeptAndTheLogSaysWhenThisRunWouldMakeOtherBoxes) {
  TempDir dir;
  const std::string src = std::string(MPATH_SOURCE_DIR) + "/configs/room/room.";
  const std::string mtl = test::read_file(src + "mtl");
  test::write_file(dir / "room.obj", test::read_file(src + "obj"));
  test::write_file(dir / "room.mtl", mtl);
  const std::string room = std::string(MPATH_SOURCE_DIR) + "/configs/room.toml";
  const std::string args = " lines.total=200000 store.chunk_lines=8192 first_shot.lines=50000 output.png=false "
                           "output.exr=false scene.file=" + (dir / "room.obj").string() +
                           " store.dir=" + (dir / "store").string() + " output.dir=" + (dir / "out").string();
  const std::string preprocess = test::program_bin("mpath-preprocess") + " " + room + args;
  ASSERT_EQ(test::run(preprocess + " -q").exit_code, 0);
  const std::string manifest = test::read_file(dir / "store/manifest.json");
  RunResult r = test::run(preprocess + " --log-level info");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("not traced again"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("this run would make"), std::string::npos) << r.output;

  const size_t at = mtl.find("newmtl lampshade\nKd 0.75 0.7 0.6");
  ASSERT_NE(at, std::string::npos);
  test::write_file(dir / "room.mtl", std::string(mtl).replace(at, 32, "newmtl lampshade\nKd 0.05 0.05 0.05"));
  r = test::run(preprocess + " --log-level info");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("not traced again"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the store was made with 5 box(es) of"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("this run would make 5 box(es) of"), std::string::npos) << r.output;
  EXPECT_EQ(test::read_file(dir / "store/manifest.json"), manifest);
  r = test::run(test::solve_bin() + " " + room + args + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto report = nlohmann::json::parse(test::read_file(dir / "out/report.json"));
  const auto& e = report["energy"];
  EXPECT_NEAR(e["emitted"].get<double>(), e["absorbed"].get<double>() + e["escaped"].get<double>() + e["unshot"].get<double>(),
              1e-9 * e["emitted"].get<double>());
}

// Single bytes flipped anywhere in any file of a hierarchical store (the
// subscenes' files included): refused by name before the first shot, never
// a crash or another answer.
TEST(Store, DamageAnywhereInAHierarchicalStoreIsRefusedBeforeAnyWork) {
  TempDir dir;
  const std::string room = std::string(MPATH_SOURCE_DIR) + "/configs/room.toml";
  const std::string args = " -q lines.total=300000 store.chunk_lines=8192 first_shot.lines=50000 output.png=false "
                           "output.exr=false store.dir=" + (dir / "store").string() + " output.dir=" + (dir / "out").string();
  ASSERT_EQ(test::run(test::program_bin("mpath-preprocess") + " " + room + args).exit_code, 0);
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir / "store"))
    if (e.path().extension() == ".lines") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ASSERT_GE(files.size(), 2u);
  std::mt19937_64 rng(17);
  for (int trial = 0; trial < 12; ++trial) {
    const auto& file = files[trial % files.size()];
    const std::string original = test::read_file(file);
    std::string damaged = original;
    const size_t at = rng() % damaged.size();
    damaged[at] = static_cast<char>(damaged[at] ^ (1 + rng() % 255));
    test::write_file(file, damaged);
    const RunResult r = test::run(test::solve_bin() + " " + room + args);
    test::write_file(file, original);
    SCOPED_TRACE(file.filename().string() + " byte " + std::to_string(at));
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(file.filename().string() + ": its contents do not match the hash"), std::string::npos)
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "out/checkpoint.bin"));
    EXPECT_FALSE(std::filesystem::exists(dir / "out/solution.ply"));
  }
  EXPECT_EQ(test::run(test::solve_bin() + " " + room + args).exit_code, 0);  // restored, it solves
}

// Damage the whole-store check cannot see (the manifest's hash made to
// match): found while streaming, in whichever box of a depth it is, and an
// error naming the file and chunk, not a crash (boxes of one depth run at
// once; the others' passes end normally).
TEST(Store, DamageBehindAMatchingManifestIsFoundWhileStreaming) {
  TempDir dir;
  const std::string room = std::string(MPATH_SOURCE_DIR) + "/configs/room.toml";
  for (const std::string transport : {"transmittance", "lines"}) {
    const auto store = dir / transport;
    // (Shared by quotient, every box holds chunks for the damage to land in.)
    const std::string args = " -q lines.total=300000 store.chunk_lines=4096 first_shot.lines=50000 output.png=false "
                             "output.exr=false lines.box_budget=quotient hierarchy.transport=" + transport +
                             " store.dir=" + store.string() +
                             " output.dir=" + (dir / "out").string();
    ASSERT_EQ(test::run(test::program_bin("mpath-preprocess") + " " + room + args).exit_code, 0);
    for (const std::string name : {"box0001.lines", "box0003.lines"}) {
      const auto file = store / name;
      ASSERT_TRUE(std::filesystem::exists(file));
      const std::string original = test::read_file(file);
      std::string damaged = original;
      damaged[damaged.size() / 2] = static_cast<char>(damaged[damaged.size() / 2] ^ 0x10);
      test::write_file(file, damaged);
      const std::string manifest_text = test::read_file(store / "manifest.json");
      auto manifest = nlohmann::json::parse(manifest_text);
      for (auto& f : manifest["files"])
        if (f["name"] == name) f["hash"] = hash_file(file);
      test::write_file(store / "manifest.json", manifest.dump());
      const RunResult r = test::run(test::solve_bin() + " " + room + args);
      SCOPED_TRACE(transport + " " + name);
      EXPECT_EQ(r.exit_code, 1) << r.output;
      EXPECT_NE(r.output.find(name + ": chunk"), std::string::npos) << r.output;
      EXPECT_FALSE(std::filesystem::exists(dir / "out/solution.ply"));
      test::write_file(file, original);
      test::write_file(store / "manifest.json", manifest_text);
    }
  }
}

// Single bytes flipped anywhere in a checkpoint: --resume refuses it, and
// never resumes into another state.
TEST(Store, DamagedCheckpointsAreRefused) {
  TempDir dir;
  const std::string store = " store.dir=" + (dir / "store").string();
  ASSERT_EQ(preprocess(store).exit_code, 0);
  const std::string run = store + " solver.tolerance=1e-9 output.dir=" + (dir / "out").string();
  ASSERT_EQ(solve(run + " solver.iterations=2").exit_code, 0);
  const auto checkpoint = dir / "out/checkpoint.bin";
  const std::string original = test::read_file(checkpoint);
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 16; ++trial) {
    std::string damaged = original;
    const size_t at = trial == 0 ? damaged.size() - 1 : rng() % damaged.size();
    damaged[at] = static_cast<char>(damaged[at] ^ (1 + rng() % 255));
    test::write_file(checkpoint, damaged);
    const RunResult r = solve(run + " solver.iterations=4 --resume");
    EXPECT_EQ(r.exit_code, 1) << "byte " << at << ": " << r.output;
    EXPECT_NE(r.output.find("damaged checkpoint (checksum mismatch)"), std::string::npos) << "byte " << at << ": " << r.output;
  }
  test::write_file(checkpoint, original.substr(0, original.size() / 2));
  RunResult r = solve(run + " solver.iterations=4 --resume");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("damaged checkpoint"), std::string::npos) << r.output;
  test::write_file(checkpoint, original);
  r = solve(run + " solver.iterations=4 --resume");
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

// Shards run with different configs cannot make one store: the shard that
// finds the other says which key differs, and no manifest is written; when
// that shard has run again with the same config, the store is complete.
TEST(Store, ShardsOfDifferentConfigsSayWhichKeyDiffers) {
  TempDir dir;
  const std::string store = " store.dir=" + (dir / "store").string();
  ASSERT_EQ(preprocess(store + " --shard 1/2").exit_code, 0);
  const RunResult r = preprocess(store + " lines.total=160000 --shard 2/2 --log-level warn");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("part0001of0002.json: shard 1 of 2 was made with another scene or config (lines.total: the "
                          "store was made with 150000, this run has 160000); the store is complete once that shard has run again"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "store/manifest.json"));
  ASSERT_EQ(preprocess(store + " lines.total=160000 --shard 1/2").exit_code, 0);
  EXPECT_TRUE(std::filesystem::exists(dir / "store/manifest.json"));
}

TEST(Store, ShardOptionIsChecked) {
  const RunResult r = preprocess("--shard 4/3");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--shard: expected i/n with 1 <= i <= n, got '4/3'"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace mpath
