// Surfaces pressed against each other (src/scene/contact.h): the split of
// polygons at their contacts, checked against analytic overlap areas over
// random layouts, and what the split is for: a frame on a wall, at any mesh
// size, has a back side that sees only the wall under it, so in a room lit
// from elsewhere it stays dark; the furnace stays exact.
#include "contact.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include <fmt/format.h>

#include "mesh.h"
#include "scene_readers.h"
#include "test_util.h"

namespace mpath {
namespace {

double area_of(const Polygon& p) { return polygon_area(p.vertices); }

// A wall x = 0 facing +x, 4 x 3, and boxes pressed against it (their backs
// on x = 0 facing -x), each given as its (y, z) rectangle.
struct Rect {
  double y0, z0, y1, z1;
};

Scene wall_with(const std::vector<Rect>& rects) {
  Scene s;
  s.file = "wall";
  const int m = test::add_material(s, "m", 0.5, 0.0);
  test::add_quad(s, {0, 0, 0}, {0, 4, 0}, {0, 4, 3}, {0, 0, 3}, m, test::add_object(s, "wall"));
  for (const Rect& r : rects)
    test::add_box(s, {0, r.y0, r.z0}, {0.05, r.y1, r.z1}, false, m, test::add_object(s, "frame"));
  return s;
}

// Of the wall's polygons after a split (those at x = 0 facing +x), the area
// inside rectangle r and outside every rectangle.
struct WallAreas {
  double total = 0, inside_any = 0;
  size_t pieces = 0;
};

WallAreas wall_areas(const Scene& s, const std::vector<Rect>& rects) {
  WallAreas a;
  for (const Polygon& p : s.polygons) {
    const Vec3 n = newell_normal(p.vertices);
    bool on_wall = n.x > 0;
    for (const Vec3& v : p.vertices) on_wall &= std::fabs(v.x) < 1e-12;
    if (!on_wall) continue;
    ++a.pieces;
    a.total += area_of(p);
    Vec3 c{0, 0, 0};
    for (const Vec3& v : p.vertices) c = c + v * (1.0 / static_cast<double>(p.vertices.size()));
    for (const Rect& r : rects)
      if (c.y > r.y0 && c.y < r.y1 && c.z > r.z0 && c.z < r.z1) {
        a.inside_any += area_of(p);
        break;
      }
  }
  return a;
}

TEST(Contact, AFrameOnAWallSplitsTheWallWhereItTouches) {
  const std::vector<Rect> frame{{1.0, 1.0, 2.0, 1.8}};
  Scene s = wall_with(frame);
  const size_t before = s.polygons.size();
  const ContactSplit c = split_contacts(s);
  EXPECT_EQ(c.pairs, 1u);
  EXPECT_EQ(c.split, 1u);  // the wall; the frame's back lies wholly on it
  EXPECT_EQ(c.skipped, 0u);
  const WallAreas a = wall_areas(s, frame);
  EXPECT_NEAR(a.total, 12.0, 1e-12);
  EXPECT_NEAR(a.inside_any, 0.8, 1e-12);
  EXPECT_EQ(a.pieces, c.pieces);
  EXPECT_EQ(s.polygons.size(), before - 1 + c.pieces);
  // Splitting again finds the contact but has nothing left to split.
  const ContactSplit again = split_contacts(s);
  EXPECT_EQ(again.split, 0u);
  // A contact of at most min_area (0.8 here) is left whole.
  Scene small = wall_with(frame);
  EXPECT_EQ(split_contacts(small, 0.81).pairs, 0u);
  EXPECT_EQ(small.polygons.size(), before);
  EXPECT_EQ(split_contacts(small, 0.79).pairs, 1u);
  // Or when it covers more than min_share of the smaller object: the frame's
  // back is 0.8 of its 1.78 m2.
  Scene share = wall_with(frame);
  EXPECT_EQ(split_contacts(share, 1.0, 0.5).pairs, 0u);
  EXPECT_EQ(split_contacts(share, 1.0, kContactMinShare).pairs, 1u);
}

TEST(Contact, SurfacesApartOrFacingTheSameWayAreLeftWhole) {
  Scene s = wall_with({});
  const int m = 0;
  // A box 1 mm off the wall, and a poster lying on the wall facing the room.
  test::add_box(s, {0.001, 1, 1}, {0.05, 2, 2}, false, m, test::add_object(s, "off the wall"));
  test::add_quad(s, {0, 2.5, 1}, {0, 3.5, 1}, {0, 3.5, 2}, {0, 2.5, 2}, m, test::add_object(s, "poster"));
  const size_t before = s.polygons.size();
  EXPECT_EQ(split_contacts(s).pairs, 0u);
  EXPECT_EQ(s.polygons.size(), before);
}

// Random frames on the wall, overlapping it in part at its edges too: the
// pieces keep the wall's area, and its part in contact is the area the
// rectangles cover (computed independently on a fine grid of the wall).
TEST(Contact, RandomFramesSplitTheWallIntoWhatTheyCoverAndTheRest) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> y(-0.5, 4.0), z(-0.5, 3.0), size(0.1, 1.2);
    std::vector<Rect> rects;
    const int count = 1 + static_cast<int>(seed % 5);
    while (static_cast<int>(rects.size()) < count) {
      Rect r{y(rng), z(rng), 0, 0};
      r.y1 = r.y0 + size(rng);
      r.z1 = r.z0 + size(rng);
      bool apart = true;  // frames do not overlap each other
      for (const Rect& o : rects) apart &= r.y1 <= o.y0 || o.y1 <= r.y0 || r.z1 <= o.z0 || o.z1 <= r.z0;
      if (apart && r.y1 > 0 && r.y0 < 4 && r.z1 > 0 && r.z0 < 3) rects.push_back(r);
    }
    Scene s = wall_with(rects);
    split_contacts(s);
    const WallAreas a = wall_areas(s, rects);
    double covered = 0;
    for (const Rect& r : rects)
      covered += std::max(0.0, std::min(r.y1, 4.0) - std::max(r.y0, 0.0)) *
                 std::max(0.0, std::min(r.z1, 3.0) - std::max(r.z0, 0.0));
    SCOPED_TRACE("seed " + std::to_string(seed));
    EXPECT_NEAR(a.total, 12.0, 1e-9);
    EXPECT_NEAR(a.inside_any, covered, 1e-9);
    // Frames larger than the wall's edge are split too: their part off the wall stays apart.
    double frame_backs = 0;
    for (const Polygon& p : s.polygons)
      if (newell_normal(p.vertices).x < 0 && std::fabs(p.vertices[0].x) < 1e-12) frame_backs += area_of(p);
    double backs = 0;
    for (const Rect& r : rects) backs += (r.y1 - r.y0) * (r.z1 - r.z0);
    EXPECT_NEAR(frame_backs, backs, 1e-9);
  }
}

// A closed grey room 4 x 4 x 3 (rho 0.6) lit by a patch of its ceiling;
// returns the grey material.
int lit_room(Scene& s) {
  s.file = "room";
  const int grey = test::add_material(s, "grey", 0.6, 0.0);
  const int lamp = test::add_material(s, "lamp", 0.0, 10.0);
  test::add_box(s, {0, 0, 0}, {4, 4, 3}, true, grey, test::add_object(s, "room"));
  test::add_quad(s, {1.5, 1.5, 2.999}, {1.5, 2.5, 2.999}, {2.5, 2.5, 2.999}, {2.5, 1.5, 2.999}, lamp,
                 test::add_object(s, "lamp"));
  return grey;
}

// A closed room lit by a patch of its ceiling, a frame pressed against a wall.
// The frame's back and the wall under it see only each other: no light
// reaches them, so the back stays dark, with the wall's patches straddling
// the frame or not, split or not. With the mesh made to forget that the two
// touch, a coarse wall patch lights the back with the radiosity of its lit
// part, which shows the check can fail.
double frame_back_radiosity(bool split, double max_patch_area, bool contacts = true) {
  Scene s;
  const int grey = lit_room(s);
  test::add_box(s, {0, 1.3, 1.1}, {0.04, 2.1, 1.7}, false, grey, test::add_object(s, "frame"));
  if (split) {
    EXPECT_EQ(split_contacts(s).pairs, 1u);
  }
  Options o = test::test_options(400'000, 200'000, max_patch_area);
  o.solver.iterations = 30;
  o.solver.tolerance = 1e-4;
  const test::Solved r = test::solve_classic_in_memory(s, o, contacts);
  EXPECT_TRUE(r.log.converged);
  EXPECT_LT(std::fabs(r.state.energy_residual()) / r.state.emitted_total(), 1e-10);
  double power = 0, area = 0, room = 0, room_area = 0;
  for (size_t f = 0; f < r.state.faces; ++f) {
    const Patch& p = r.mesh.patches[r.mesh.face_patch[f]];
    const double a = r.mesh.face_area(static_cast<int>(f));
    const double b = r.state.radiosity(r.mesh, f)[0];
    if (p.object == 2 && p.normal.x < -0.5) {  // the frame's back
      power += b * a;
      area += a;
    } else if (p.object == 0) {
      room += b * a;
      room_area += a;
    }
  }
  EXPECT_GT(room / room_area, 0.5);  // the room is lit
  return power / area / (room / room_area);
}

TEST(Contact, AFramesBackSeesOnlyTheWallUnderItAtAnyMeshSize) {
  for (const double area : {2.0, 0.3, 0.02})
    for (const bool split : {false, true}) {
      SCOPED_TRACE("max patch area " + std::to_string(area) + (split ? ", split" : ""));
      EXPECT_EQ(frame_back_radiosity(split, area), 0.0);
    }
  // Touching surfaces not told apart, a wall patch wider than the frame lights its back.
  EXPECT_GT(frame_back_radiosity(false, 2.0, false), 0.2);
}

// Random rooms: frames on the walls and blocks on the floor and on a shelf,
// at random places and sizes (straddling the wall's patches or not), lit by
// a lamp in the ceiling. In every method, unsplit, the sides pressed against
// something stay dark and no power is lost or made; and the room's
// mean radiosity agrees with the split scene's (where the covered parts are
// patches of their own) within the noise of two seeds.
struct RandomRoom {
  Scene scene;
  std::vector<int> covered_objects;  // objects whose side facing -x (frames) or -z (blocks) touches
};

RandomRoom random_room(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  RandomRoom r;
  Scene& s = r.scene;
  const int grey = lit_room(s);
  for (int k = 0; k < 3; ++k) {  // frames on the wall x = 0, apart along y
    const double y0 = 0.2 + 1.25 * k + 0.3 * u(rng), w = 0.2 + 0.6 * u(rng), z0 = 0.5 + u(rng), h = 0.2 + u(rng);
    r.covered_objects.push_back(test::add_object(s, "frame"));
    test::add_box(s, {0, y0, z0}, {0.03 + 0.03 * u(rng), y0 + w, z0 + h}, false, grey, r.covered_objects.back());
  }
  for (int k = 0; k < 3; ++k) {  // blocks on the floor, apart along x
    const double x0 = 0.6 + 1.1 * k + 0.3 * u(rng), y0 = 0.3 + 2.5 * u(rng), w = 0.2 + 0.5 * u(rng);
    r.covered_objects.push_back(test::add_object(s, "block"));
    test::add_box(s, {x0, y0, 0}, {x0 + w, y0 + w, 0.1 + 0.5 * u(rng)}, false, grey, r.covered_objects.back());
  }
  return r;
}

bool covered_face(const RandomRoom& room, const PatchMesh& mesh, size_t f) {
  const Patch& p = mesh.patches[mesh.face_patch[f]];
  const Vec3 n = mesh.face_normal(static_cast<int>(f));
  const bool listed =
      std::find(room.covered_objects.begin(), room.covered_objects.end(), p.object) != room.covered_objects.end();
  const Vec3& corner = mesh.vertices[p.v[0]];
  return listed && ((n.x < -0.5 && std::fabs(corner.x) < 1e-9) || (n.z < -0.5 && std::fabs(corner.z) < 1e-9));
}

// Area-weighted mean radiosity of the room's own faces, and the largest
// radiosity of a covered face over the room's mean.
std::pair<double, double> room_and_covered(const RandomRoom& room, const PatchMesh& mesh, const RadiosityState& state) {
  double sum = 0, area = 0, covered = 0;
  for (size_t f = 0; f < state.faces; ++f) {
    const double b = state.radiosity(mesh, f)[0];
    if (mesh.patches[mesh.face_patch[f]].object == 0) {
      sum += b * mesh.face_area(static_cast<int>(f));
      area += mesh.face_area(static_cast<int>(f));
    }
    if (covered_face(room, mesh, f)) covered = std::max(covered, b);
  }
  return {sum / area, covered / (sum / area)};
}

TEST(Contact, RandomRoomsKeepTheirTouchingSidesDarkInEveryMethod) {
  test::TempDir dir;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const RandomRoom room = random_room(seed);
    const auto path = test::write_obj(room.scene, dir / ("room" + std::to_string(seed)));
    std::vector<double> means;
    for (const auto method : {SolverMethod::classic, SolverMethod::multipath, SolverMethod::hierarchical}) {
      for (const unsigned lines_seed : {1u, 2u}) {
        SCOPED_TRACE(fmt::format("method {}, lines seed {}", static_cast<int>(method), lines_seed));
        Options o = test::test_options(300'000, 300'000, 0.5);
        o.scene.file = path;
        o.solver.method = method;
        o.solver.iterations = 40;
        o.solver.tolerance = 1e-4;
        o.lines.seed = lines_seed;
        o.store.dir = dir / fmt::format("s{}-{}-{}", seed, static_cast<int>(method), lines_seed);
        RadiosityState state;
        PatchMesh mesh;
        if (method == SolverMethod::classic) {
          test::Solved r = test::solve_classic_in_memory(room.scene, o);
          EXPECT_TRUE(r.log.converged);
          state = std::move(r.state);
          mesh = std::move(r.mesh);
        } else {
          test::StoredSolve r = test::solve_stored(o);
          EXPECT_TRUE(r.log.converged);
          state = std::move(r.state);
          mesh = std::move(r.mesh);
        }
        EXPECT_LT(std::fabs(state.energy_residual()) / state.emitted_total(), 1e-10);
        const auto [mean, covered] = room_and_covered(room, mesh, state);
        // Dark but for a line through a touching edge, within the tie
        // distance of it (seen once: a frame's back lit at 1.6e-4 of the
        // room's mean through the corner where its bottom meets the wall).
        EXPECT_LT(covered, 1e-3);
        means.push_back(mean);
      }
    }
    // The same room split at its contacts, two seeds: both are area means
    // over the same surfaces, so the methods' means agree with it within 4
    // times the spread its two seeds show (plus 1 %, a floor for a spread
    // small by chance).
    double split_mean = 0, spread = 0;
    for (const unsigned lines_seed : {1u, 2u}) {
      Scene s = room.scene;
      split_contacts(s);
      Options o = test::test_options(300'000, 300'000, 0.5);
      o.solver.iterations = 40;
      o.solver.tolerance = 1e-4;
      o.lines.seed = lines_seed;
      const test::Solved r = test::solve_classic_in_memory(s, o);
      const double m = room_and_covered(room, r.mesh, r.state).first;
      spread = lines_seed == 1 ? m : std::fabs(spread - m);
      split_mean += m / 2;
    }
    for (const double m : means) EXPECT_NEAR(m, split_mean, 4 * spread + 0.01 * split_mean);
  }
}

// An emitting box (reflectance rho1, exitance E on every face) standing on a
// grey tile (rho2) of exactly its footprint, in a black room: the box's
// bottom and the tile see only each other, so the bottom's emission bounces
// between them until absorbed, B_bottom = E / (1 - rho1 rho2) and B_tile =
// rho2 E / (1 - rho1 rho2), exactly (the first shot's closed form; the two
// rectangles mesh alike, so each bottom patch lies on one tile patch). All
// of it is absorbed, none reaches the room.
TEST(Contact, AnEmitterOnATileLightsItInClosedForm) {
  const double rho1 = 0.6, rho2 = 0.8, radiance = 2.0, e = std::numbers::pi * radiance;
  Scene s;
  s.file = "tile";
  const int black = test::add_material(s, "black", 0.0, 0.0);
  const int grey = test::add_material(s, "grey", rho2, 0.0);
  const int lamp = test::add_material(s, "lamp", rho1, radiance);
  test::add_box(s, {0, 0, 0}, {4, 4, 3}, true, black, test::add_object(s, "room"));
  const int tile = test::add_object(s, "tile");
  test::add_quad(s, {1.5, 1.5, 1}, {2.1, 1.5, 1}, {2.1, 1.9, 1}, {1.5, 1.9, 1}, grey, tile);
  const int box = test::add_object(s, "box");
  test::add_box(s, {1.5, 1.5, 1}, {2.1, 1.9, 1.3}, false, lamp, box);
  Options o = test::test_options(200'000, 200'000, 0.02);
  o.solver.iterations = 10;
  o.solver.tolerance = 1e-6;
  const test::Solved r = test::solve_classic_in_memory(s, o);
  EXPECT_LT(std::fabs(r.state.energy_residual()) / r.state.emitted_total(), 1e-10);
  double tile_power = 0;
  int tile_faces = 0, bottom_faces = 0;
  for (size_t f = 0; f < r.state.faces; ++f) {
    const Patch& p = r.mesh.patches[r.mesh.face_patch[f]];
    const double b = r.state.radiosity(r.mesh, f)[0];
    if (p.object == tile) {
      EXPECT_NEAR(b, rho2 * e / (1 - rho1 * rho2), 1e-9 * e) << "tile face " << f;
      tile_power += b * r.mesh.face_area(static_cast<int>(f));
      ++tile_faces;
    } else if (p.object == box && p.normal.z < -0.5) {
      EXPECT_NEAR(b, e / (1 - rho1 * rho2), 1e-9 * e) << "bottom face " << f;
      ++bottom_faces;
    }
  }
  EXPECT_GT(tile_faces, 4);
  EXPECT_EQ(tile_faces, bottom_faces);
  EXPECT_NEAR(tile_power, rho2 * e * 0.6 * 0.4 / (1 - rho1 * rho2), 1e-9 * e);
}

// A furnace with furniture pressed on the floor and on each other stays
// exact when split: the covered sides form closed cavities of their own.
TEST(Contact, AFurnaceWithContactsStaysExactWhenSplit) {
  const double rho = 0.5, exitance = 1.0;
  Scene s = test::furnace_scene(rho, exitance);
  test::add_table(s, 0.9, 0.7, 0, "table");
  const ContactSplit c = split_contacts(s);
  EXPECT_GE(c.pairs, 6u);  // the block and the four legs on the floor, the column on the floor and ceiling
  Options o = test::test_options(1'000'000, 200'000, 0.05);
  o.solver.iterations = 40;
  o.solver.tolerance = 1e-4;
  const test::Solved r = test::solve_classic_in_memory(s, o);
  ASSERT_TRUE(r.log.converged);
  double mean = 0, area = 0;
  for (size_t f = 0; f < r.state.faces; ++f) {
    const double a = r.mesh.face_area(static_cast<int>(f));
    mean += a * (r.state.radiosity(r.mesh, f)[0] * (1 - rho) / exitance - 1);
    area += a;
  }
  EXPECT_NEAR(mean / area, 0.0, 2e-3);
}

}  // namespace
}  // namespace mpath

namespace mpath {
namespace {

// A wall given twice facing the same way (RenderPark's hospital repeats half
// its polygons): load_scene keeps one copy, and the solve converges. With
// both copies the lines meet one of them every time, and the other is black
// in the solution (the power the first shot left on it, which no global line
// moved before classic passes shot it with local lines, is now sent on, and
// that solve converges too).
TEST(Duplicates, ARepeatedWallIsOneSurface) {
  Scene s;
  s.file = "room";
  const int grey = test::add_material(s, "grey", 0.6, 0.0);
  const int lamp = test::add_material(s, "lamp", 0.0, 10.0);
  test::add_box(s, {0, 0, 0}, {4, 4, 3}, true, grey, test::add_object(s, "room"));
  for (int k = 0; k < 6; ++k) s.polygons.push_back(s.polygons[static_cast<size_t>(k)]);  // every wall twice
  test::add_quad(s, {1.5, 1.5, 2.999}, {1.5, 2.5, 2.999}, {2.5, 2.5, 2.999}, {2.5, 1.5, 2.999}, lamp,
                 test::add_object(s, "lamp"));
  test::TempDir dir;
  SceneOptions so;
  so.file = test::write_obj(s, dir / "room");
  std::vector<std::string> warnings;
  const Scene loaded = load_scene(so, 16, warnings);
  EXPECT_EQ(loaded.polygons.size(), 7u);
  Options o = test::test_options(400'000, 200'000, 0.5);
  o.solver.iterations = 40;
  o.solver.tolerance = 1e-4;
  const test::Solved one = test::solve_classic_in_memory(loaded, o);
  EXPECT_TRUE(one.log.converged);
  const test::Solved both = test::solve_classic_in_memory(s, o);
  EXPECT_TRUE(both.log.converged) << "unshot " << both.state.remaining_fraction();
  const auto wall_radiosity = [](const test::Solved& r, int polygon) {
    double power = 0, area = 0;
    for (size_t f = 0; f < r.state.faces; ++f) {
      if (r.mesh.patches[r.mesh.face_patch[f]].polygon != polygon) continue;
      power += r.state.radiosity(r.mesh, f)[0] * r.mesh.face_area(static_cast<int>(f));
      area += r.mesh.face_area(static_cast<int>(f));
    }
    return power / area;
  };
  for (int k = 0; k < 6; ++k) {
    const double kept = wall_radiosity(one, k);
    EXPECT_LT(std::min(wall_radiosity(both, k), wall_radiosity(both, k + 6)), 0.01 * kept) << "wall " << k;
  }
}

}  // namespace
}  // namespace mpath
