// libFuzzer target for the store's first, second and lights' shots
// (first_shot.bin, second_shot.bin, lights_shot.bin). The input is read as
// each of them for a small fixed scene (a closed room of 6 faces with a cube
// of 6 in it, every face emitting, and a point source above the cube), the
// face shots with the plan the file itself records and the lights' with the
// fixed light's (as its seed file was written), so that their frames of lines
// are read too: anything but a file the writer made must end in InputError.
// Its bytes also choose plans of all three that are written and read back,
// which must give what tracing them gives.
#include <cmath>
#include <cstring>

#include "error.h"
#include "fuzz_common.h"
#include "progress.h"
#include "scene_readers.h"
#include "stored_shot.h"

using namespace mpath;

namespace {

constexpr uint64_t kLightLines = 5000;
constexpr unsigned long long kLightSeed = 7;

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
  // The fixed light, its lines and seed: those of the seed file valid_lights.bin.
  static const std::vector<PointLight> lights = [] {
    LightOptions o;
    o.position = {0.5, 0.5, 0.8};
    o.intensity_cd = 10;
    return std::vector<PointLight>{make_light(o)};
  }();
  try {  // as the lights' shot
    RadiosityState state = fresh;
    LightsShotStats stats;
    (void)replay_stored_lights(path, mesh, lights, {kLightLines}, kLightSeed, state, stats);
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

  // The light's shot of as many lines.
  {
    const std::vector<uint64_t> light_lines{static_cast<uint64_t>(lines)};
    write_stored_lights(written, mesh, tracer, lights, light_lines, seed, 1);
    RadiosityState lit_traced = fresh, lit_read = fresh;
    Options o;
    o.lines.seed = seed;
    o.solver.shards = 1;
    shoot_lights(o, mesh, tracer, lit_traced, lights, {lines});
    LightsShotStats light_stats;
    if (!replay_stored_lights(written, mesh, lights, light_lines, seed, lit_read, light_stats).empty()) __builtin_trap();
    if (!same(lit_traced, lit_read)) __builtin_trap();
  }

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
