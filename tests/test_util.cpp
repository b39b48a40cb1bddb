#include "test_util.h"

#include <unistd.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <sys/wait.h>

#include "sampling.h"

namespace mpath::test {

namespace fs = std::filesystem;

TempDir::TempDir() {
  std::string pattern = (fs::temp_directory_path() / "mpath-test-XXXXXX").string();
  if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
  path_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

void write_file(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

RunResult run(const std::string& command) {
  RunResult r;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buffer{};
  size_t n;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) r.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string solve_bin() { return MPATH_SOLVE_BIN; }
fs::path shared_scenes() { return MPATH_SHARED_SCENES; }

int add_material(Scene& scene, const std::string& name, double rho, double radiance, bool two_sided) {
  scene.materials.push_back(Material{name, {rho, rho, rho}, {radiance, radiance, radiance}, two_sided});
  return static_cast<int>(scene.materials.size()) - 1;
}

int add_object(Scene& scene, const std::string& name) {
  scene.objects.push_back({name});
  return static_cast<int>(scene.objects.size()) - 1;
}

void add_quad(Scene& scene, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, int material, int object) {
  scene.polygons.push_back(Polygon{{a, b, c, d}, material, object});
}

void add_box(Scene& scene, const Vec3& lo, const Vec3& hi, bool inward, int material, int object) {
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int high = 0; high < 2; ++high) {
      Vec3 c = lo;
      c[axis] = high ? hi[axis] : lo[axis];
      Vec3 du, dv;
      du[u] = hi[u] - lo[u];
      dv[v] = hi[v] - lo[v];
      // [c, c+du, c+du+dv, c+dv] faces +axis; outward on the high side.
      const bool flip = (high == 0) != inward;
      if (flip) add_quad(scene, c, c + dv, c + du + dv, c + du, material, object);
      else add_quad(scene, c, c + du, c + du + dv, c + dv, material, object);
    }
  }
}

Scene furnace_scene(double rho, double exitance) {
  Scene scene;
  scene.file = "furnace";
  const int m = add_material(scene, "grey", rho, exitance / std::numbers::pi);
  add_box(scene, {0, 0, 0}, {2, 1.5, 1}, true, m, add_object(scene, "room"));
  add_box(scene, {0.3, 0.4, 0.3}, {0.7, 0.8, 0.6}, false, m, add_object(scene, "floating cube"));
  add_box(scene, {1.2, 0.0, 0.2}, {1.7, 0.6, 0.5}, false, m, add_object(scene, "block on the floor"));
  // Floor to ceiling in a corner: in contact with four walls along their edges.
  add_box(scene, {0.0, 1.0, 0.0}, {0.3, 1.5, 1.0}, false, m, add_object(scene, "corner column"));
  return scene;
}

Options test_options(long long global_lines, long long local_lines, double max_patch_area) {
  Options o;
  o.lines.total = global_lines;
  o.first_shot.lines = local_lines;
  o.mesh.max_patch_area = max_patch_area;
  o.solver.method = "classic";
  o.solver.threads = 2;
  o.lines.sequence = "random";  // the noise model of the physics tests is for independent lines
  return o;
}

Solved solve_classic_in_memory(const Scene& scene, const Options& options) {
  Solved s;
  s.mesh = build_mesh(scene, options.mesh.max_patch_area);
  const Tracer tracer(s.mesh);
  s.state = make_state(scene, s.mesh);
  const std::vector<double> crossings_per_area = emitter_crossings(options, forecast_crossings(s.mesh, static_cast<double>(options.lines.total)));
  first_shot(s.mesh, tracer, s.state, options.first_shot.lines, options.lines.seed, options.solver.threads,
             crossings_per_area);
  s.log = solve_classic(options, s.mesh, tracer, s.state, options.solver.threads);
  return s;
}

}  // namespace mpath::test
