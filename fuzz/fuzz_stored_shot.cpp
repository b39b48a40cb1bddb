// libFuzzer target for the store's first shot (first_shot.bin). The input is
// read as the first shot of a small fixed scene (a closed room of 6 faces
// with a cube in it, every face emitting), with the plan the file itself
// records, so that its frames of lines are read too: anything but a file the
// writer made must end in InputError. Its bytes also choose a plan that is
// written and read back, which must give what tracing it gives.
#include <cmath>

#include "error.h"
#include "fuzz_common.h"
#include "progress.h"
#include "stored_shot.h"

using namespace mpath;

namespace {

void add_box(Scene& scene, const Vec3& lo, const Vec3& hi, bool inward, int material, int object) {
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int high = 0; high < 2; ++high) {
      Vec3 c = lo;
      c[axis] = high ? hi[axis] : lo[axis];
      Vec3 du, dv;
      du[u] = hi[u] - lo[u];
      dv[v] = hi[v] - lo[v];
      if ((high == 0) != inward) scene.polygons.push_back(Polygon{{c, c + dv, c + du + dv, c + du}, material, object});
      else scene.polygons.push_back(Polygon{{c, c + du, c + du + dv, c + dv}, material, object});
    }
  }
}

struct Fixed {
  Scene scene;
  PatchMesh mesh;
  Fixed() {
    Progress::set_enabled_default(false);
    scene.file = "fuzz room";
    scene.materials.push_back(Material{"grey", {0.5, 0.5, 0.5}, {1, 2, 3}, false});
    scene.objects.push_back({"room"});
    scene.objects.push_back({"cube"});
    add_box(scene, {0, 0, 0}, {1, 1, 1}, true, 0, 0);
    add_box(scene, {0.4, 0.4, 0.4}, {0.6, 0.6, 0.6}, false, 0, 1);
    mesh = build_mesh(scene, 10.0);
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
  for (size_t i = 0; i < traced.phi.size(); ++i)
    if (std::abs(traced.phi[i] - read.phi[i]) > 1e-12 * (1 + std::abs(traced.phi[i])) ||
        std::abs(traced.unshot[i] - read.unshot[i]) > 1e-12 * (1 + std::abs(traced.unshot[i])))
      __builtin_trap();
  return 0;
}
