#include "test_util.h"
#include "second_shot.h"

#include "prepared_scene.h"

#include "accelerated_shot.h"
#include "box_store.h"
#include "hierarchical.h"
#include "preprocess.h"
#include "scene_readers.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

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

SampleStats sample_stats(const std::vector<double>& x) {
  SampleStats s;
  if (x.size() < 2) throw std::invalid_argument("sample_stats: fewer than two samples");
  for (const double v : x) s.mean += v;
  s.mean /= static_cast<double>(x.size());
  for (const double v : x) s.variance += (v - s.mean) * (v - s.mean);
  s.variance /= static_cast<double>(x.size() - 1);
  return s;
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
std::string program_bin(const std::string& name) { return (fs::path(solve_bin()).parent_path() / name).string(); }
fs::path shared_scenes() { return MPATH_SHARED_SCENES; }

fs::path shared_scene(const std::string& relative) {
  const fs::path path = shared_scenes() / relative;
  if (fs::exists(path)) return path;
  ADD_FAILURE() << path.string() << " is missing: this test needs the public scenes in shared/scenes beside the "
                << "project's folder (clone mpath next to its shared/ folder, as CI does)";
  return {};
}

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

void add_table(Scene& scene, double x, double y, int material, const std::string& name) {
  add_box(scene, {x, y, 0.70}, {x + 0.8, y + 0.6, 0.75}, false, material, add_object(scene, name + " top"));
  for (int i = 0; i < 4; ++i) {
    const double lx = x + (i % 2 ? 0.68 : 0.07), ly = y + (i / 2 ? 0.48 : 0.07);
    add_box(scene, {lx, ly, 0.0}, {lx + 0.05, ly + 0.05, 0.70}, false, material,
            add_object(scene, fmt::format("{} leg {}", name, i + 1)));
  }
}

std::filesystem::path write_obj(const Scene& scene, const std::filesystem::path& stem) {
  std::string mtl, obj = fmt::format("mtllib {}.mtl\n", stem.filename().string());
  for (const Material& m : scene.materials)
    mtl += fmt::format("newmtl {}\nKd {:.17g} {:.17g} {:.17g}\nKe {:.17g} {:.17g} {:.17g}\n", m.name, m.rho[0], m.rho[1],
                       m.rho[2], m.emission[0], m.emission[1], m.emission[2]);
  size_t v = 0;
  int object = -1, material = -1;
  for (const Polygon& p : scene.polygons) {
    if (p.object != object) obj += fmt::format("o {}\n", scene.objects[object = p.object].name);
    if (p.material != material) obj += fmt::format("usemtl {}\n", scene.materials[material = p.material].name);
    for (const Vec3& x : p.vertices) obj += fmt::format("v {:.17g} {:.17g} {:.17g}\n", x.x, x.y, x.z);
    obj += "f";
    for (size_t i = 0; i < p.vertices.size(); ++i) obj += fmt::format(" {}", ++v);
    obj += "\n";
  }
  std::filesystem::path path = stem;
  path += ".obj";
  std::filesystem::path mtl_path = stem;
  mtl_path += ".mtl";
  write_file(mtl_path, mtl);
  write_file(path, obj);
  return path;
}

StoredSolve solve_stored(const Options& options, const std::function<void(const RadiosityState&)>& after_each) {
  run_preprocess(options, ShardSpec{});
  StoredSolve s;
  PreparedScene prepared = prepare_scene(options);
  const Scene& scene = prepared.scene;
  s.mesh = std::move(prepared.mesh);
  const BoxStore store(options, s.mesh);
  s.boxes = store.box_count();
  s.depth = store.hierarchy().max_depth();
  const TracerOnDemand tracer(s.mesh);
  s.state = make_state(scene, s.mesh);
  add_ar_state(store, s.state);
  std::unique_ptr<SubsceneNearest> accelerated;
  if (options.first_shot.accelerate && !store.line_sets())
    accelerated = std::make_unique<SubsceneNearest>(s.mesh, store);
  first_shot(s.mesh, tracer.get(), s.state, first_shot_lines(options), options.lines.seed, options.solver.shards,
             emitter_crossings(options, store.face_crossings(s.mesh.face_count())), accelerated.get());
  if (const FirstShotPlan second = plan_run_second_shot(options, s.mesh, s.state, &store); !second.emitters.empty())
    second_shot(s.mesh, tracer.get(), s.state, second, options.lines.seed, options.solver.shards);
  iterate(options, s.state, s.log, [&](unsigned pass) {
    const PassStats p = stored_iteration(options, s.mesh, tracer, store, s.state, s.log, pass, options.solver.shards);
    if (after_each) after_each(s.state);
    return p;
  });
  return s;
}

Options test_options(long long global_lines, long long local_lines, double max_patch_area) {
  Options o;
  o.lines.total = global_lines;
  o.first_shot.lines = local_lines;
  o.mesh.max_patch_area = max_patch_area;
  o.solver.method = SolverMethod::classic;
  o.solver.threads = 2;
  o.lines.sequence = "random";  // the noise model of the physics tests is for independent lines
  return o;
}

Solved solve_classic_in_memory(const Scene& scene, const Options& options, bool contacts) {
  Solved s;
  s.mesh = build_mesh(scene, options.mesh.max_patch_area);
  if (!contacts) s.mesh.contact_plane.clear();
  const Tracer tracer(s.mesh);
  s.state = make_state(scene, s.mesh);
  const std::vector<double> crossings_per_area = emitter_crossings(options, forecast_crossings(s.mesh, static_cast<double>(options.lines.total)));
  first_shot(s.mesh, tracer, s.state, first_shot_lines(options), options.lines.seed, options.solver.shards,
             crossings_per_area);
  if (const FirstShotPlan second = plan_run_second_shot(options, s.mesh, s.state, nullptr); !second.emitters.empty())
    second_shot(s.mesh, tracer, s.state, second, options.lines.seed, options.solver.shards);
  s.log = solve_classic(options, s.mesh, tracer, s.state, options.solver.shards);
  return s;
}

}  // namespace mpath::test
