// libFuzzer target for the store's first and second shots (first_shot.bin,
// second_shot.bin). The input is read as each of them for a small fixed
// scene (a closed room of 6 faces with a cube of 6 in it, every face
// emitting), with the plan the file itself records, so that its frames of
// lines are read too: anything but a file the writer made must end in
// InputError. Its bytes also choose plans of both shots that are written and
// read back, which must give what tracing them gives.
#include <cmath>
#include <cstring>

#include "error.h"
#include "fuzz_common.h"
#include "progress.h"
#include "scene_readers.h"
#include "stored_shot.h"

using namespace mpath;

namespace {

// A closed unit room (faces inward) and a cube in it (faces outward), all
// of one grey that emits.
constexpr const char* kMtl = "newmtl grey\nKd 0.5 0.5 0.5\nKe 1 2 3\n";
constexpr const char* kObj =
    "mtllib room.mtl\nusemtl grey\n"
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    "v .4 .4 .4\nv .6 .4 .4\nv .6 .6 .4\nv .4 .6 .4\nv .4 .4 .6\nv .6 .4 .6\nv .6 .6 .6\nv .4 .6 .6\n"
    "o room\nf 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n"
    "o cube\nf 9 12 11 10\nf 13 14 15 16\nf 9 10 14 13\nf 10 11 15 14\nf 11 12 16 15\nf 12 9 13 16\n";

struct Fixed {
  Scene scene;
  PatchMesh mesh;
  Fixed() {
    Progress::set_enabled_default(false);
    fuzz::write_input("room.mtl", reinterpret_cast<const uint8_t*>(kMtl), std::strlen(kMtl));
    scene = read_obj(fuzz::write_input("room.obj", reinterpret_cast<const uint8_t*>(kObj), std::strlen(kObj)));
    mesh = build_mesh(scene, 10.0);
    if (mesh.face_count() != 12) __builtin_trap();  // the seed file's plan is for 12 faces
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const Fixed fixed;
  static const Tracer tracer(fixed.mesh);
  const PatchMesh& mesh = fixed.mesh;
  const RadiosityState fresh = make_state(fixed.scene, mesh);
  const auto path = fuzz::write_input(kStoredShotFile, data, size);
  try {
    unsigned long long seed = 0;
    const FirstShotPlan plan = read_stored_plan(path, mesh.face_count(), seed);
    RadiosityState state = fresh;
    FirstShotStats stats;
    (void)replay_stored_shot(path, mesh, plan, seed, state, stats);
  } catch (const InputError&) {
  }
  try {  // as a second shot, after a first shot
    static const RadiosityState after = [&] {
      RadiosityState state = fresh;
      first_shot(mesh, tracer, state, plan_first_shot(mesh, fresh, 500, {}), 1, 1);
      return state;
    }();
    unsigned long long seed = 0;
    const FirstShotPlan plan = read_stored_plan(path, mesh.face_count(), seed, ShotKind::second);
    RadiosityState state = after;
    SecondShotStats stats;
    (void)replay_stored_second_shot(path, mesh, plan, seed, state, stats);
  } catch (const InputError&) {
  }

  // A plan of the input's bytes, written and read back.
  const long long lines = size > 1 ? 1 + (data[0] | data[1] << 8) % 3000 : 1;
  std::vector<double> crossings;
  if (size > 2 && data[2] % 2) {
    crossings.assign(mesh.face_count(), 0.0);
    for (size_t f = 0; f < crossings.size(); ++f) crossings[f] = size > 3 + f && data[3 + f] % 3 == 0 ? 1e9 : 0.0;
  }
  const unsigned long long seed = size > 3 ? data[size - 1] : 7;
  const FirstShotPlan plan = plan_first_shot(mesh, fresh, lines, crossings);
  const auto written = fuzz::folder() / "written.bin";
  write_stored_shot(written, mesh, tracer, plan, seed, 1);
  RadiosityState traced = fresh, read = fresh;
  first_shot(mesh, tracer, traced, plan, seed, 1);
  FirstShotStats stats;
  if (!replay_stored_shot(written, mesh, plan, seed, read, stats).empty()) __builtin_trap();
  const auto same = [](const RadiosityState& a, const RadiosityState& b) {
    for (size_t i = 0; i < a.phi.size(); ++i)
      if (std::abs(a.phi[i] - b.phi[i]) > 1e-12 * (1 + std::abs(a.phi[i])) ||
          std::abs(a.unshot[i] - b.unshot[i]) > 1e-12 * (1 + std::abs(a.unshot[i])))
        return false;
    return true;
  };
  if (!same(traced, read)) __builtin_trap();

  // The second shot that follows, of as many lines, every face taking part
  // (no crossings) or those the input's crossings leave.
  const FirstShotPlan second = plan_second_shot(traced, lines, crossings, size > 4 && data[4] % 2 == 0);
  if (second.emitters.empty()) return 0;
  write_stored_shot(written, mesh, tracer, second, seed, 1, ShotKind::second);
  RadiosityState traced2 = traced;
  second_shot(mesh, tracer, traced2, second, seed, 1);
  SecondShotStats second_stats;
  if (!replay_stored_second_shot(written, mesh, second, seed, traced, second_stats).empty()) __builtin_trap();
  if (!same(traced2, traced)) __builtin_trap();
  return 0;
}
