#include "report.h"

#include <numbers>

#include "process_memory.h"
#include "color.h"
#include "mpath_version.h"
#include "tracer.h"

namespace mpath {
namespace {

using json = nlohmann::json;

// Bytes the solver holds per AR of a box: In and Out per channel, the
// transmittance, two redirect targets, n_R, n_R^d and the associated patches.
size_t ar_bytes(const RadiosityState& s) {
  return 2 * s.channels * sizeof(double) + sizeof(double) + 4 * sizeof(uint32_t) +
         2 * linestore::BoxCounts::kAssociated * sizeof(uint32_t);
}

json hierarchy_json(const BoxStore& store, const RadiosityState& state, const std::vector<BoxPassStats>& last) {
  json boxes = json::array();
  size_t ar_memory = 0;
  for (size_t b = 0; b < store.box_count(); ++b) {
    const SceneBox& sb = store.hierarchy().boxes[b];
    const StoreBox& box = store.box(b);
    const size_t memory = sb.ar_count() * ar_bytes(state) + box.counts.child_crossings.size() * sizeof(uint32_t);
    ar_memory += memory;
    boxes.push_back({{"box", b}, {"parent", sb.parent}, {"depth", sb.depth}, {"children", sb.children},
                     {"objects", sb.objects_total}, {"polygons", sb.polygons_total}, {"patches_direct", sb.patches.size()},
                     {"quotient", sb.quotient}, {"vp_grid", sb.grid}, {"ars", sb.ar_count()},
                     {"lo", {sb.bounds.lo.x, sb.bounds.lo.y, sb.bounds.lo.z}},
                     {"hi", {sb.bounds.hi.x, sb.bounds.hi.y, sb.bounds.hi.z}},
                     {"lines", box.lines}, {"events", box.events}, {"store_bytes", box.bytes}, {"ar_memory_bytes", memory},
                     {"last_pass_seconds", b < last.size() ? last[b].seconds : 0.0}});
  }
  return {{"boxes", boxes}, {"count", store.box_count()}, {"depth", store.hierarchy().max_depth()},
          {"ars", store.ar_total()}, {"ar_memory_bytes", ar_memory}, {"store_bytes", store.bytes()}};
}

json energy_json(const RadiosityState& s) {
  const auto absorbed = s.rgb(s.energy.absorbed), escaped = s.rgb(s.energy.escaped), emitted = s.rgb(s.energy.emitted);
  const auto unshot_rgb = s.rgb(s.unshot_per_channel());
  std::array<double, 3> held{};
  for (size_t i = 0; i < s.ar_in.size(); ++i) held[i % s.channels] += s.ar_in[i] + s.ar_out[i];
  const auto held_rgb = s.rgb(held);
  auto sum = [](const std::array<double, 3>& v) { return v[0] + v[1] + v[2]; };
  const double residual = sum(emitted) - sum(absorbed) - sum(escaped) - sum(unshot_rgb) - sum(held_rgb);
  return {{"emitted", sum(emitted)},
          {"absorbed", sum(absorbed)},
          {"escaped", sum(escaped)},
          {"unshot", sum(unshot_rgb)},
          {"in_transit", sum(held_rgb)},
          {"residual", residual},
          {"relative_residual", sum(emitted) > 0 ? residual / sum(emitted) : 0.0},
          {"per_channel", {{"emitted", emitted}, {"absorbed", absorbed}, {"escaped", escaped}, {"unshot", unshot_rgb},
                            {"in_transit", held_rgb}}}};
}

// Per material: the area its faces cover (a two-sided surface counts both
// faces), and their area means of emitted exitance, radiosity (W/m2, per
// channel) and luminance (cd/m2; a diffuse surface's luminance is its
// radiosity's luminous exitance over pi).
json material_json(const PreparedScene& prepared, const RadiosityState& state) {
  const PatchMesh& mesh = prepared.mesh;
  const std::vector<SolutionFace> faces = state.solution_faces(mesh);
  const size_t n = prepared.scene.materials.size();
  std::vector<double> area(n, 0.0);
  std::vector<Rgb> emitted(n, Rgb{0, 0, 0}), radiosity(n, Rgb{0, 0, 0});
  for (size_t f = 0; f < faces.size(); ++f) {
    const int m = mesh.patches[mesh.face_patch[f]].material;
    const double a = mesh.face_area(static_cast<int>(f));
    area[m] += a;
    for (int c = 0; c < 3; ++c) {
      emitted[m][c] += a * faces[f].exitance[c];
      radiosity[m][c] += a * faces[f].radiosity[c];
    }
  }
  json out = json::array();
  for (size_t m = 0; m < n; ++m) {
    if (area[m] <= 0) continue;  // no face of it in the mesh
    Rgb e, b;
    for (int c = 0; c < 3; ++c) {
      e[c] = emitted[m][c] / area[m];
      b[c] = radiosity[m][c] / area[m];
    }
    out.push_back({{"name", prepared.scene.materials[m].name}, {"area_m2", area[m]},
                   {"exitance_W_m2", {e[0], e[1], e[2]}}, {"radiosity_W_m2", {b[0], b[1], b[2]}},
                   {"luminance_cd_m2", kWhiteEfficacy * luminance(b) / std::numbers::pi}});
  }
  return out;
}

}  // namespace

json solve_report(const Options& options, const PreparedScene& prepared, const RadiosityState& state,
                  const BoxStore* store, const SolveRecord& r) {
  json passes = json::array();
  for (const PassStats& p : r.iterations.passes)
    passes.push_back({{"pass", p.pass}, {"lines", p.lines}, {"hits", p.hits}, {"seconds", p.seconds},
                      {"unshot_fraction", p.unshot_fraction}});
  const PatchMesh& m = prepared.mesh;
  return {
      {"mpath", {{"version", MPATH_VERSION}, {"commit", MPATH_GIT_COMMIT}, {"embree", Tracer::embree_version()},
                 {"command", r.command_line}, {"threads", r.threads}, {"ranks", r.ranks},
                 {"transparent_huge_pages", transparent_huge_pages()},
                 {"malloc_huge_pages", malloc_asks_for_huge_pages()}}},
      {"config", json::parse(options_to_json(options))},
      {"scene", {{"file", options.scene.file.string()}, {"polygons", prepared.scene.polygons.size()},
                 {"objects", prepared.scene.objects.size()}, {"materials", prepared.scene.materials.size()},
                 {"dropped_polygons", m.dropped_polygons}, {"patches", m.patches.size()}, {"faces", m.face_count()},
                 {"max_patch_area", m.max_patch_area}, {"channels", state.channels}}},
      {"timings", {{"load", prepared.load_seconds}, {"mesh", prepared.mesh_seconds}, {"store", r.timings.store},
                   {"bvh", r.timings.bvh},
                   {"first_shot", r.shot.seconds}, {"iterations", r.timings.iterations}, {"outputs", r.timings.outputs},
                   {"total", r.timings.total}}},
      {"first_shot", {{"lines", r.shot.lines}, {"emitter_faces", r.shot.emitter_faces},
                      {"associated_hits", r.shot.associated_hits},
                      {"global_emitter_faces", r.shot.global_emitter_faces}, {"from_checkpoint", r.resumed},
                      {"from_store", r.shot.stored}, {"traced_because", r.shot.traced_because},
                      {"sequence", r.shot.halton ? "halton" : "random"},
                      {"lines_from", r.shot_lines_from}, {"pilot_share", r.shot_share},
                      {"pilot_seconds", r.pilot_seconds}}},
      {"second_shot", {{"lines", r.second_shot.lines}, {"faces", r.second_shot.faces},
                       {"power_share", r.second_shot.power_share}, {"seconds", r.second_shot.seconds},
                       {"sequence", r.second_shot.halton ? "halton" : "random"},
                       {"from_store", r.second_shot.stored}, {"traced_because", r.second_shot.traced_because}}},
      {"lights_shot", {{"lines", r.lights_shot.lines}, {"seconds", r.lights_shot.seconds},
                       {"from_store", r.lights_shot.stored}, {"traced_because", r.lights_shot.traced_because}}},
      {"lights", [&] {
         json lights = json::array();
         for (const SolveRecord::Light& l : r.lights)
           lights.push_back({{"name", l.name}, {"flux_lm", l.flux_lm}, {"power_W", l.power_W},
                             {"first_shot_lines", l.first_shot_lines}});
         return lights;
       }()},
      {"lines", {{"global", r.iterations.lines}, {"hits", r.iterations.hits}, {"local", r.shot.lines}, {"local_second_shot", r.second_shot.lines},
                 {"local_uncarried", r.uncarried_lines}}},
      {"iterations", {{"count", r.iterations.passes.size()}, {"converged", r.iterations.converged},
                      {"tolerance", options.solver.tolerance}, {"cap", options.solver.iterations},
                      {"unshot_fraction", state.unshot_total() / state.emitted_total()},
                      {"remaining_fraction", state.remaining_fraction()}, {"passes", passes}}},
      {"memory", {{"peak_rss_bytes", peak_rss_bytes()}}},
      {"store", store ? json{{"dir", options.store.dir.string()}, {"lines", store->lines()}, {"events", store->events()},
                             {"bytes", store->bytes()}, {"bytes_per_event", double(store->bytes()) / std::max<uint64_t>(1, store->events())},
                             {"events_per_second_per_thread", r.timings.iterations > 0 && !r.iterations.passes.empty()
                                  ? double(r.iterations.hits - r.hits_before) / r.timings.iterations / r.threads : 0.0}}
                      : json(nullptr)},
      {"hierarchy", store ? hierarchy_json(*store, state, r.box_stats) : json(nullptr)},
      {"energy", energy_json(state)},
      {"materials", material_json(prepared, state)},
      {"outputs", r.outputs},
      {"grids", r.grids},
      {"warnings", [&] {
         std::vector<std::string> all = prepared.warnings;
         all.insert(all.end(), r.warnings.begin(), r.warnings.end());
         return all;
       }()},
  };
}

}  // namespace mpath
