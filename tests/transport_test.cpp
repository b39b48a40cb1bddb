#include "transport.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "test_util.h"

namespace mpath {
namespace {

// Floor (faces +y, y = 0), a block bottom on it (faces -y, y = 0), the
// block's top (faces +y, y = 1) and a ceiling (faces -y, y = 2); one-sided.
struct Column {
  Scene scene;
  PatchMesh mesh;
  Column() {
    const int m = test::add_material(scene, "m", 0.5, 0.0);
    const int o = test::add_object(scene, "o");
    auto horizontal = [&](double y, bool up) {
      if (up) test::add_quad(scene, {0, y, 0}, {0, y, 1}, {1, y, 1}, {1, y, 0}, m, o);
      else test::add_quad(scene, {0, y, 0}, {1, y, 0}, {1, y, 1}, {0, y, 1}, m, o);
    };
    horizontal(0, true);   // 0 floor
    horizontal(0, false);  // 1 block bottom
    horizontal(1, true);   // 2 block top
    horizontal(2, false);  // 3 ceiling
    mesh = build_mesh(scene, 10.0);
  }
};

// Crossings of the column by a vertical line, `along` set from the patch normals.
std::vector<LineHit> crossings(const PatchMesh& mesh, const Vec3& dir, std::vector<std::pair<double, int>> list) {
  std::vector<LineHit> hits;
  for (auto [t, patch] : list) hits.push_back({t, patch, dot(mesh.patches[patch].normal, dir) > 0});
  return hits;
}

TEST(OrderTies, PutsTheFloorBeforeTheBlockOnItWhicheverWayTheLineRuns) {
  const Column c;
  const Vec3 up{0, 1, 0};
  std::vector<LineHit> hits = crossings(c.mesh, up, {{0.0, 1}, {0.0, 0}, {1.0, 2}, {2.0, 3}});
  order_ties(c.mesh, 1e-9, hits);
  EXPECT_EQ(hits[0].patch, 0);  // floor top faces the block bottom
  EXPECT_EQ(hits[1].patch, 1);
  std::vector<LineHit> down = crossings(c.mesh, -up, {{0.0, 3}, {1.0, 2}, {2.0, 0}, {2.0, 1}});
  order_ties(c.mesh, 1e-9, down);
  EXPECT_EQ(down[2].patch, 1);  // coming down: block bottom, then the floor
  EXPECT_EQ(down[3].patch, 0);
}

TEST(OrderTies, KeepsLiveFacesInsideWhenALineOnlyCrossesTwoContacts) {
  // A column stands on the floor against a wall (x = 0). A line enters through
  // the wall where the column touches it and leaves through the floor under
  // the column: both ends must show the walls' black backs to empty space.
  Scene s;
  const int m = test::add_material(s, "m", 0.5, 0.0);
  test::add_quad(s, {0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}, m, test::add_object(s, "wall"));   // faces +x
  test::add_quad(s, {0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}, m, test::add_object(s, "floor"));  // faces +y
  ASSERT_GT(newell_normal(s.polygons[0].vertices).x, 0);
  ASSERT_GT(newell_normal(s.polygons[1].vertices).y, 0);
  test::add_box(s, {0, 0, 0.2}, {0.4, 0.8, 0.6}, false, m, test::add_object(s, "column"));
  const PatchMesh mesh = build_mesh(s, 10.0);
  const Tracer tracer(mesh);
  std::vector<LineHit> hits;
  const Vec3 dir = normalize(Vec3{0.3, -0.5, 0.05});
  tracer.all_hits(Vec3{0.1, 0.4, 0.4} - dir * 2.0, dir, 4.0, hits);
  ASSERT_EQ(hits.size(), 4u);  // two contact pairs and nothing between them
  order_ties(mesh, 1e-9, hits);
  auto live_forward = [&](const LineHit& h) { return mesh.patch_faces[h.patch][h.along ? 0 : 1] >= 0; };
  auto live_backward = [&](const LineHit& h) { return mesh.patch_faces[h.patch][h.along ? 1 : 0] >= 0; };
  EXPECT_FALSE(live_backward(hits.front()));
  EXPECT_FALSE(live_forward(hits.back()));
  for (size_t i = 0; i + 1 < hits.size(); ++i) EXPECT_EQ(live_forward(hits[i]), live_backward(hits[i + 1])) << i;
}

// Random lines through random patches (live, black or invisible backs), with
// groups of one to five crossings at equal distance: order_ties must keep
// each group's crossings in its place, reach the least number of live/black
// pairs that any order of the groups reaches (found by trying every one),
// and give the same order whatever order the crossings were reported in, and
// whether the faces' liveness comes from the mesh or a tracer's table.
TEST(OrderTies, FindsTheLeastLiveBlackPairsOnRandomLines) {
  Rng rng = make_rng(20261204, 0, 0);
  PatchMesh mesh;
  for (int p = 0; p < 40; ++p) {
    const double u = uniform(rng);
    const int back = u < 0.4 ? 2 * p + 1 : u < 0.8 ? kBlackSide : kInvisibleSide;
    mesh.patch_faces.push_back({2 * p, back});
  }
  // The same faces as a tracer's table of live faces (Tracer::live_faces),
  // over every patch and over a subset numbered in another order.
  std::vector<uint8_t> live_by_patch, live_by_traced(40);
  std::vector<int> traced_of(40);
  for (int p = 0; p < 40; ++p) traced_of[static_cast<size_t>(p)] = (7 * p + 3) % 40;
  for (int p = 0; p < 40; ++p) {
    const auto& f = mesh.patch_faces[static_cast<size_t>(p)];
    live_by_patch.push_back(static_cast<uint8_t>((f[0] >= 0 ? 1 : 0) | (f[1] >= 0 ? 2 : 0)));
    live_by_traced[static_cast<size_t>(traced_of[static_cast<size_t>(p)])] = live_by_patch.back();
  }
  const auto live_forward = [&](const LineHit& h) { return facing(mesh, h).forward >= 0; };
  const auto live_backward = [&](const LineHit& h) { return facing(mesh, h).backward >= 0; };
  // Live/black pairs on the line, empty space (black) beyond both ends.
  const auto cost = [&](const std::vector<LineHit>& hits) {
    int c = 0;
    bool before = false;
    for (const LineHit& h : hits) {
      c += before != live_backward(h);
      before = live_forward(h);
    }
    return c + (before ? 1 : 0);
  };
  int lines_with_ties = 0, improved = 0;
  for (int line = 0; line < 3000; ++line) {
    std::vector<LineHit> hits;
    std::vector<std::pair<size_t, size_t>> groups;
    size_t combinations = 1;
    std::vector<int> patches(40);
    for (int p = 0; p < 40; ++p) patches[static_cast<size_t>(p)] = p;
    std::shuffle(patches.begin(), patches.end(), rng);
    size_t next_patch = 0;
    const int group_count = 1 + static_cast<int>(uniform(rng) * 4);
    for (int g = 0; g < group_count; ++g) {
      const size_t n = 1 + static_cast<size_t>(uniform(rng) * uniform(rng) * 5);
      size_t f = 1;
      for (size_t k = 2; k <= n; ++k) f *= k;
      if (combinations * f > 20000) break;
      combinations *= f;
      groups.push_back({hits.size(), n});
      for (size_t k = 0; k < n; ++k)
        hits.push_back({1.0 + g + 1e-12 * static_cast<double>(k), patches[next_patch++], uniform(rng) < 0.5});
    }
    lines_with_ties += hits.size() > groups.size();
    // The least cost over every order of every group.
    const auto by_patch = [](const LineHit& a, const LineHit& b) { return a.patch < b.patch; };
    std::vector<LineHit> trial = hits;
    for (auto [lo, n] : groups)
      std::sort(trial.begin() + static_cast<long>(lo), trial.begin() + static_cast<long>(lo + n), by_patch);
    int least = cost(trial);
    const auto advance = [&] {  // the next combination of group orders; false after the last
      for (auto [lo, n] : groups)
        if (std::next_permutation(trial.begin() + static_cast<long>(lo), trial.begin() + static_cast<long>(lo + n), by_patch))
          return true;
      return false;
    };
    while (advance()) least = std::min(least, cost(trial));

    std::vector<LineHit> ordered = hits;
    order_ties(mesh, 1e-9, ordered);
    ASSERT_EQ(cost(ordered), least) << "line " << line;
    improved += cost(ordered) < cost(hits);
    for (auto [lo, n] : groups) {
      std::vector<int> a, b;
      for (size_t k = lo; k < lo + n; ++k) {
        a.push_back(hits[k].patch);
        b.push_back(ordered[k].patch);
      }
      std::sort(a.begin(), a.end());
      std::sort(b.begin(), b.end());
      ASSERT_EQ(a, b) << "line " << line;
    }
    // From a tracer's table, the same order.
    std::vector<LineHit> from_table = hits, from_subset = hits;
    order_ties(mesh, 1e-9, from_table, live_by_patch.data());
    for (LineHit& h : from_subset) h.traced = traced_of[static_cast<size_t>(h.patch)];
    order_ties(mesh, 1e-9, from_subset, live_by_traced.data());
    for (size_t k = 0; k < hits.size(); ++k) {
      ASSERT_EQ(from_table[k].patch, ordered[k].patch) << "line " << line;
      ASSERT_EQ(from_table[k].along, ordered[k].along) << "line " << line;
      ASSERT_EQ(from_subset[k].patch, ordered[k].patch) << "line " << line;
      ASSERT_EQ(from_subset[k].along, ordered[k].along) << "line " << line;
    }
    std::vector<LineHit> shuffled = hits;
    for (auto [lo, n] : groups)
      std::shuffle(shuffled.begin() + static_cast<long>(lo), shuffled.begin() + static_cast<long>(lo + n), rng);
    order_ties(mesh, 1e-9, shuffled);
    for (size_t k = 0; k < hits.size(); ++k) {
      ASSERT_EQ(shuffled[k].patch, ordered[k].patch) << "line " << line;
      ASSERT_EQ(shuffled[k].along, ordered[k].along) << "line " << line;
    }
  }
  // The cases must be ones where the order matters.
  EXPECT_GT(lines_with_ties, 1500);
  EXPECT_GT(improved, 500);
}

// A pass over the column with nothing to send yet and `share` per crossing.
struct ColumnPass {
  Column c;
  RadiosityState state;
  PassInputs in;
  ShardAccumulator acc;
  explicit ColumnPass(double share) : state(make_state(c.scene, c.mesh)) {
    in = PassInputs::start(state, c.mesh, std::vector<double>(state.faces, 1.0 / share));
    acc.reset(state.faces);
  }
};

TEST(Transport, ConservesPowerAlongALineAndAbsorbsAtBlackBacks) {
  ColumnPass pass(0.25);
  const Column& c = pass.c;
  PassInputs& in = pass.in;
  ShardAccumulator& acc = pass.acc;
  in.faces[2].quota[0] = 8.0;  // the block top has 8 W to send, 2 W per crossing
  in.faces[3].quota[0] = 4.0;  // the ceiling 4 W, 1 W per crossing
  const Vec3 up{0, 1, 0};
  const std::vector<LineHit> hits = crossings(c.mesh, up, {{0.0, 0}, {0.0, 1}, {1.0, 2}, {2.0, 3}});
  transport_line(in, hits, acc);
  // The top sends 2 W up to the ceiling, which keeps rho = 0.5 of it; the
  // ceiling sends 1 W down to the top, which keeps 0.5 W. Both backs are black.
  EXPECT_DOUBLE_EQ(acc.faces[3].phi_gain[0], 1.0);
  EXPECT_DOUBLE_EQ(acc.faces[2].phi_gain[0], 0.5);
  EXPECT_DOUBLE_EQ(acc.faces[3].gathered[0], 1.0);
  EXPECT_DOUBLE_EQ(acc.absorbed[0], 1.5);
  EXPECT_DOUBLE_EQ(acc.escaped[0], 0.0);
  // Sends come before receives: the top's gathered 0.5 W was not sent back.
  EXPECT_DOUBLE_EQ(acc.faces[2].quota_used, 0.25);
  // A second line sends the top's gathered power along with its share.
  transport_line(in, hits, acc);
  EXPECT_DOUBLE_EQ(acc.faces[3].phi_gain[0], 1.0 + 0.5 * 2.5);
  double sent = 0;
  for (int f : {2, 3}) sent += in.faces[f].quota[0] * acc.faces[f].quota_used;
  double held = 0;
  for (const FaceAccumulator& a : acc.faces) held += a.gathered[0];
  EXPECT_DOUBLE_EQ(sent, acc.absorbed[0] + acc.escaped[0] + held);
}

TEST(Transport, PowerLeavingTheEndsOfALineEscapes) {
  ColumnPass pass(1.0);
  PassInputs& in = pass.in;
  ShardAccumulator& acc = pass.acc;
  in.faces[2].quota[0] = 3.0;
  const std::vector<LineHit> top = crossings(pass.c.mesh, {0, 1, 0}, {{1.0, 2}});  // only the block top on this line
  transport_line(in, top, acc);
  EXPECT_DOUBLE_EQ(acc.escaped[0], 3.0);
  // A shard never sends more than its allowance of a quota.
  acc.allowance = 1.0;
  transport_line(in, top, acc);
  EXPECT_DOUBLE_EQ(acc.escaped[0], 3.0);
}

// A floor (faces +y, y = 0), a one-sided sheet with an invisible back above
// it (faces +y, y = 1) and a ceiling (faces -y, y = 2).
struct Veil {
  Scene scene;
  PatchMesh mesh;
  Veil() {
    const int m = test::add_material(scene, "m", 0.5, 0.0);
    const int v = test::add_material(scene, "veil", 0.5, 0.0);
    scene.materials[v].invisible_back = true;
    const int o = test::add_object(scene, "o");
    test::add_quad(scene, {0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}, m, o);
    test::add_quad(scene, {0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}, v, o);
    test::add_quad(scene, {0, 2, 0}, {1, 2, 0}, {1, 2, 1}, {0, 2, 1}, m, o);
    mesh = build_mesh(scene, 10.0);
  }
};

TEST(Transport, PowerPassesAnInvisibleBackToTheNextSurface) {
  const Veil v;
  ASSERT_EQ(v.mesh.patch_faces[1][1], kInvisibleSide);
  ASSERT_EQ(v.mesh.patch_faces[0][1], kBlackSide);
  RadiosityState state = make_state(v.scene, v.mesh);
  PassInputs in = PassInputs::start(state, v.mesh, std::vector<double>(state.faces, 1.0));
  ShardAccumulator acc;
  acc.reset(state.faces);
  in.faces[0].quota[0] = 2.0;  // the floor sends 2 W up
  in.faces[2].quota[0] = 4.0;  // the ceiling 4 W down
  in.faces[1].quota[0] = 8.0;  // the sheet 8 W up, from its front
  const std::vector<LineHit> up = crossings(v.mesh, {0, 1, 0}, {{0.0, 0}, {1.0, 1}, {2.0, 2}});
  transport_line(in, up, acc);
  // The floor's 2 W pass the sheet's back and reach the ceiling, as do the
  // sheet's 8 W; the ceiling's 4 W stop at the sheet's front.
  EXPECT_DOUBLE_EQ(acc.faces[2].phi_gain[0], 0.5 * 10.0);
  EXPECT_DOUBLE_EQ(acc.faces[1].phi_gain[0], 0.5 * 4.0);
  EXPECT_DOUBLE_EQ(acc.faces[0].phi_gain[0], 0.0);
  EXPECT_DOUBLE_EQ(acc.absorbed[0], 0.5 * 14.0);
  EXPECT_DOUBLE_EQ(acc.escaped[0], 0.0);

  // Rays do the same: up from the floor the ceiling, down from the ceiling the sheet.
  const Tracer tracer(v.mesh);
  EXPECT_EQ(tracer.nearest({0.5, 0.5, 0.5}, {0, 1, 0}, 0.0, 10.0).patch, 2);
  EXPECT_EQ(tracer.nearest({0.5, 1.5, 0.5}, {0, -1, 0}, 0.0, 10.0).patch, 1);
  EXPECT_EQ(tracer.nearest_from(0, {0.5, 0.0, 0.5}, {0, 1, 0}, 10.0).patch, 2);
  EXPECT_EQ(tracer.nearest_from(2, {0.5, 2.0, 0.5}, {0, -1, 0}, 10.0).patch, 1);
  // Every crossing is reported along a line; transport lets the back pass.
  std::vector<LineHit> all;
  tracer.all_hits({0.5, -1, 0.5}, {0, 1, 0}, 10.0, all);
  EXPECT_EQ(all.size(), 3u);
}

}  // namespace
}  // namespace mpath
