// libFuzzer target for the scene readers: one binary per format, chosen by
// MPATH_FUZZ_FORMAT at compile time (obj, mtl, ply, mgf). A reader may
// throw InputError on bad input; anything else (a crash, another exception,
// a sanitizer finding, a hang) is a defect. The scene that loads is checked
// as load_scene checks it.
#include <cmath>

#include "error.h"
#include "fuzz_common.h"
#include "scene_readers.h"

using namespace mpath;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string format = MPATH_FUZZ_FORMAT;
  SceneOptions options;
  if (format == "mtl") {
    fuzz::write_input("scene.mtl", data, size);
    const char obj[] = "mtllib scene.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n";
    options.file = fuzz::write_input("scene.obj", reinterpret_cast<const uint8_t*>(obj), sizeof obj - 1);
  } else {
    options.file = fuzz::write_input("scene." + format, data, size);
  }
  std::vector<std::string> warnings;
  try {
    const Scene scene = load_scene(options, 16, warnings);
    for (const Polygon& p : scene.polygons)
      for (const Vec3& v : p.vertices)
        if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) __builtin_trap();
  } catch (const InputError&) {
  }
  return 0;
}
