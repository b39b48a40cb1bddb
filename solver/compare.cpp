#include "compare.h"
#include "directory_lock.h"

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>

#include "atomic_file.h"
#include "error.h"
#include "json_text.h"
#include "mpath_version.h"
#include "png_writer.h"
#include "prepared_scene.h"
#include "render.h"
#include "solution_ply.h"
#include "tracer.h"

namespace mpath {
namespace {

// A viridis-like perceptual map, dark (no error) to yellow (scale and above).
constexpr std::array<std::array<double, 3>, 5> kColourMap = {{{0.267, 0.005, 0.329},
                                                               {0.229, 0.322, 0.546},
                                                               {0.128, 0.567, 0.551},
                                                               {0.369, 0.789, 0.383},
                                                               {0.993, 0.906, 0.144}}};

std::array<double, 3> colour(double t) {
  t = std::clamp(t, 0.0, 1.0) * (kColourMap.size() - 1);
  const size_t i = std::min(static_cast<size_t>(t), kColourMap.size() - 2);
  const double f = t - i;
  std::array<double, 3> c;
  for (int k = 0; k < 3; ++k) c[k] = kColourMap[i][k] * (1 - f) + kColourMap[i + 1][k] * f;
  return c;
}

double weighted_quantile(const std::vector<std::pair<double, double>>& values, double total, double q) {
  double sum = 0;
  for (const auto& [v, w] : values) {
    sum += w;
    if (sum >= q * total) return v;
  }
  return values.empty() ? 0.0 : values.back().first;
}

}  // namespace


Comparison compare_solutions(const SolutionFaces& result, const SolutionFaces& reference) {
  const size_t n = reference.area.size();
  if (result.area.size() != n)
    throw InputError(fmt::format("the solutions have different faces ({} and {}): not the same mesh", result.area.size(), n));
  Comparison c;
  c.faces = n;
  c.relative.assign(n, -1.0);
  // Faces far darker than the scene's mean (hidden contact faces, the
  // insides of stacks) have no meaningful relative error: left out.
  double mean_y = 0, total_area = 0;
  for (size_t f = 0; f < n; ++f) {
    for (int k = 0; k < 3; ++k) mean_y += reference.area[f] * (reference.radiosity[f][k] - reference.exitance[f][k]) / 3;
    total_area += reference.area[f];
  }
  const double dark = total_area > 0 ? kDarkFraction * mean_y / total_area : 0.0;
  double sq = 0, ref_sq = 0, ref_total_sq = 0, rel_area = 0;
  std::vector<std::pair<double, double>> rel;  // (relative error, area)
  rel.reserve(n);
  for (size_t f = 0; f < n; ++f) {
    const double a = reference.area[f];
    if (std::abs(result.area[f] - a) > 1e-5 * std::max(1e-30, std::abs(static_cast<double>(a))))
      throw InputError(fmt::format("face {} has area {} in one solution and {} in the other: not the same mesh", f,
                                   result.area[f], a));
    double y = 0, y_ref = 0;
    for (int k = 0; k < 3; ++k) {
      // Emission is the same input in both: errors are of the reflected part.
      const double e = reference.exitance[f][k];
      const double b = result.radiosity[f][k] - e, r = reference.radiosity[f][k] - e;
      if (!std::isfinite(b)) throw InputError(fmt::format("face {} has a radiosity that is not a number", f));
      sq += a * (b - r) * (b - r);
      ref_sq += a * r * r;
      ref_total_sq += a * (r + e) * (r + e);
      y += b / 3;
      y_ref += r / 3;
    }
    c.area += a;
    if (y_ref > dark && y_ref > 0) {
      c.relative[f] = std::abs(y - y_ref) / y_ref;
      c.mean_relative += a * c.relative[f];
      rel_area += a;
      rel.emplace_back(c.relative[f], a);
    }
  }
  c.mse = c.area > 0 ? sq / c.area / 3 : 0.0;
  c.rel_rms = ref_sq > 0 ? std::sqrt(sq / ref_sq) : 0.0;
  c.rel_rms_total = ref_total_sq > 0 ? std::sqrt(sq / ref_total_sq) : 0.0;
  if (rel_area > 0) {
    c.mean_relative /= rel_area;
    std::sort(rel.begin(), rel.end());
    c.p50 = weighted_quantile(rel, rel_area, 0.5);
    c.p90 = weighted_quantile(rel, rel_area, 0.9);
    c.p99 = weighted_quantile(rel, rel_area, 0.99);
  }
  return c;
}

void run_compare(const Options& options, const CompareFlags& flags) {
  auto solution_path = [](const std::filesystem::path& p) {
    return std::filesystem::is_directory(p) ? p / "solution.ply" : p;
  };
  const auto result_path = solution_path(flags.result), reference_path = solution_path(flags.reference);
  const SolutionFaces result = read_solution_ply(result_path), reference = read_solution_ply(reference_path);
  Comparison c = compare_solutions(result, reference);
  spdlog::info("{} against {}: {} faces, MSE {:.6g}, relative RMS {:.4g}, per-face relative error mean {:.4g}, "
               "median {:.4g}, 90 % {:.4g}, 99 % {:.4g}",
               result_path.string(), reference_path.string(), c.faces, c.mse, c.rel_rms, c.mean_relative, c.p50, c.p90,
               c.p99);
  create_folder(flags.out, "--out");
  nlohmann::json images = nlohmann::json::array();
  if (flags.images && !options.cameras.empty()) {
    const PreparedScene prepared = prepare_scene(options);
    const PatchMesh& mesh = prepared.mesh;
    if (mesh.face_count() != c.faces)
      throw InputError(fmt::format("{} with this config meshes to {} faces but the solutions have {}: not the config "
                                   "the solutions were made with",
                                   options.scene.file.string(), mesh.face_count(), c.faces));
    for (size_t f = 0; f < c.faces; ++f)
      if (std::abs(mesh.face_area(static_cast<int>(f)) - reference.area[f]) > 1e-4 * mesh.face_area(static_cast<int>(f)))
        throw InputError(fmt::format("face {} of {} has area {} but the config's mesh gives {}: not the config the "
                                     "solutions were made with",
                                     f, reference_path.string(), reference.area[f], mesh.face_area(static_cast<int>(f))));
    const Tracer tracer(mesh);
    for (const CameraOptions& cam : options.cameras) {
      // Flat per patch face: the error of each patch as the solver sees it.
      // One pass gathers per pixel the error summed over samples that see a
      // measured face, the share of such samples and the share seeing a
      // face dark in the reference (the rest see nothing or a black back).
      const Image sums = render_camera(
          cam, mesh, tracer,
          [&](int patch, int side, const Vec3&) {
            const double e = c.relative[mesh.patch_faces[patch][side]];
            return e >= 0 ? std::array<double, 3>{e, 1, 0} : std::array<double, 3>{0, 0, 1};
          },
          options.lines.seed);
      Image value{sums.width, sums.height, std::vector<float>(sums.rgb.size())};
      std::vector<uint8_t> rgb(sums.rgb.size());
      for (size_t i = 0; i < rgb.size() / 3; ++i) {
        const double measured = sums.rgb[3 * i + 1], dark = sums.rgb[3 * i + 2];
        const double v = measured > 0 ? sums.rgb[3 * i] / measured : dark > 0 ? -1.0 : 0.0;
        const std::array<double, 3> col = colour(std::max(v, 0.0) / flags.scale);
        for (int k = 0; k < 3; ++k) {
          value.rgb[3 * i + k] = static_cast<float>(v);
          // The colour map, grey where the reference is dark, white where nothing is seen.
          const double mixed = col[k] * measured + 0.5 * dark + (1 - measured - dark);
          rgb[3 * i + k] = static_cast<uint8_t>(std::lround(255 * std::clamp(mixed, 0.0, 1.0)));
        }
      }
      std::vector<float> error(static_cast<size_t>(value.width) * value.height);
      for (size_t i = 0; i < error.size(); ++i) error[i] = value.rgb[3 * i];
      write_scalar_exr(flags.out / (cam.name + "_error.exr"), value.width, value.height, std::move(error),
                {{"mpathVersion", MPATH_VERSION},
                 {"mpathUnits", "relative error |Y - Y_ref| / Y_ref of the patches seen, Y the mean of R, G, B of "
                                "B - E; -1 where only faces dark in the reference (below 1e-3 of the mean) are seen"},
                 {"mpathResult", result_path.string()},
                 {"mpathReference", reference_path.string()}});
      write_png_rgb8(flags.out / (cam.name + "_error.png"), value.width, value.height, rgb);
      images.push_back({{"camera", cam.name}, {"exr", cam.name + "_error.exr"}, {"png", cam.name + "_error.png"}});
    }
  }
  nlohmann::json map = nlohmann::json::array();
  for (const auto& k : kColourMap) map.push_back(k);
  const nlohmann::json out = {
      {"mpath", {{"version", MPATH_VERSION}, {"commit", MPATH_GIT_COMMIT}}},
      {"result", result_path.string()},
      {"reference", reference_path.string()},
      {"faces", c.faces},
      {"area", c.area},
      {"mse", c.mse},
      {"rel_rms", c.rel_rms},
      {"rel_rms_total", c.rel_rms_total},
      {"relative_error", {{"mean", c.mean_relative}, {"p50", c.p50}, {"p90", c.p90}, {"p99", c.p99}}},
      {"images", images},
      {"colour_map", {{"scale", flags.scale}, {"colours", map}}}};
  write_text_file(flags.out / "compare.json", json_text(out));
}

}  // namespace mpath
