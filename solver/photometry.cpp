#include "photometry.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include "atomic_file.h"
#include "color.h"
#include "error.h"
#include "png_writer.h"
#include "sampling.h"

namespace mpath {
namespace {

constexpr unsigned kGridStream = 5;  // random stream of the gathering rays

// A perceptual ramp (dark blue, teal, green, yellow) for the false colours.
std::array<uint8_t, 3> ramp(double s) {
  static const double stops[5][3] = {{0.27, 0.00, 0.33}, {0.23, 0.32, 0.55}, {0.13, 0.57, 0.55},
                                     {0.37, 0.79, 0.38}, {0.99, 0.91, 0.14}};
  s = std::clamp(s, 0.0, 1.0) * 4;
  const int k = std::min(3, static_cast<int>(s));
  const double f = s - k;
  std::array<uint8_t, 3> out{};
  for (int c = 0; c < 3; ++c)
    out[c] = static_cast<uint8_t>(std::lround(255 * (stops[k][c] * (1 - f) + stops[k + 1][c] * f)));
  return out;
}

// 3 x 5 pixel glyphs for the legend's numbers: each row three bits, high bit left.
const std::map<char, std::array<uint8_t, 5>>& glyphs() {
  static const std::map<char, std::array<uint8_t, 5>> g = {
      {'0', {7, 5, 5, 5, 7}}, {'1', {2, 6, 2, 2, 7}}, {'2', {7, 1, 7, 4, 7}}, {'3', {7, 1, 7, 1, 7}},
      {'4', {5, 5, 7, 1, 1}}, {'5', {7, 4, 7, 1, 7}}, {'6', {7, 4, 7, 5, 7}}, {'7', {7, 1, 1, 1, 1}},
      {'8', {7, 5, 7, 5, 7}}, {'9', {7, 5, 7, 1, 7}}, {'.', {0, 0, 0, 0, 2}}, {'-', {0, 0, 7, 0, 0}},
      {'e', {0, 7, 7, 4, 7}}, {'+', {0, 2, 7, 2, 0}}, {'l', {4, 4, 4, 4, 6}}, {'x', {0, 5, 2, 5, 0}},
      {' ', {0, 0, 0, 0, 0}}};
  return g;
}

struct Canvas {
  int width, height;
  std::vector<uint8_t> rgb;
  void set(int x, int y, const std::array<uint8_t, 3>& c) {
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    for (int k = 0; k < 3; ++k) rgb[(static_cast<size_t>(y) * width + x) * 3 + k] = c[k];
  }
  // Text at (x, y), the top left, `scale` pixels per glyph pixel.
  void text(int x, int y, const std::string& s, int scale) {
    for (char ch : s) {
      const auto it = glyphs().find(ch);
      if (it != glyphs().end())
        for (int r = 0; r < 5; ++r)
          for (int c = 0; c < 3; ++c)
            if (it->second[r] & (4 >> c))
              for (int dy = 0; dy < scale; ++dy)
                for (int dx = 0; dx < scale; ++dx) set(x + c * scale + dx, y + r * scale + dy, {0, 0, 0});
      x += 4 * scale;
    }
  }
};

std::string lux_label(double v) { return v >= 100 ? fmt::format("{:.0f}", v) : fmt::format("{:.3g}", v); }

}  // namespace

GridResult measure_grid(const GridOptions& grid, const PatchMesh& mesh, const Tracer& tracer,
                        const RadiosityState& state, const std::vector<PointLight>& lights, unsigned long long seed) {
  GridResult out;
  out.options = grid;
  out.normal = length(grid.normal) > 0 ? normalize(grid.normal) : normalize(cross(grid.u, grid.v));
  const int n = grid.nu * grid.nv;
  out.points.resize(static_cast<size_t>(n));
  // Rays leave a hair above the point along the normal, so that a sensor on a
  // surface (a floor, a desk) does not see that surface at distance 0.
  const double lift = 1e-6 * mesh.bounds.diagonal();
  const int strata = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(grid.samples))));
  // The emitting faces, to be picked in proportion to their power: the
  // direct light is sampled both on them and by the cosine rays, the two
  // weighed by the balance heuristic (a small lamp is met by few cosine rays,
  // a large emitter close by is sampled badly by its points).
  std::vector<int> emitters;
  std::vector<double> cdf, area_pdf(mesh.face_count(), 0.0);  // per face: the pdf per unit area of its points
  double emitted = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const auto e = state.face_exitance(f);
    const double power = (e[0] + e[1] + e[2]) * mesh.face_area(static_cast<int>(f));
    if (!(power > 0)) continue;
    emitters.push_back(static_cast<int>(f));
    cdf.push_back(emitted += power);
  }
  for (size_t e = 0; e < emitters.size(); ++e)
    area_pdf[static_cast<size_t>(emitters[e])] =
        (cdf[e] - (e > 0 ? cdf[e - 1] : 0.0)) / emitted / mesh.face_area(emitters[e]);
  // The solid-angle pdf of the emitter sampling for a point of `face` at
  // distance r, seen at cos_there.
  const auto light_pdf = [&](int face, double r, double cos_there) {
    return area_pdf[static_cast<size_t>(face)] * r * r / cos_there;
  };
  tbb::parallel_for(0, n, [&](int k) {
    const int i = k % grid.nu, j = k / grid.nu;
    GridPoint& point = out.points[static_cast<size_t>(k)];
    point.position = grid.origin + grid.u * ((i + 0.5) / grid.nu) + grid.v * ((j + 0.5) / grid.nv);
    const double tfar = 1e3 * (mesh.bounds.diagonal() + length(point.position - mesh.bounds.center()));
    Rng rng = make_rng(seed, kGridStream, static_cast<unsigned long long>(k));
    Rgb sum{};
    int backs = 0;
    const Vec3 from = point.position + out.normal * lift;
    // Direct light sampled on the emitters: a point on an emitting face picked
    // by power, where nothing is in between, its radiance times cos over the
    // two strategies' summed pdfs.
    for (int s = 0; s < grid.samples && !emitters.empty(); ++s) {
      const size_t e = static_cast<size_t>(std::upper_bound(cdf.begin(), cdf.end(), uniform(rng) * emitted) - cdf.begin());
      const int face = emitters[std::min(e, emitters.size() - 1)];
      const int patch = mesh.face_patch[static_cast<size_t>(face)];
      const Vec3 facing = mesh.face_normal(face);
      const Vec3 d = uniform_point(mesh, mesh.patches[patch], rng) - from;
      const double r = length(d);
      if (!(r > lift)) continue;
      const Vec3 dir = d / r;
      const double cos_here = dot(out.normal, dir), cos_there = -dot(facing, dir);
      if (cos_here <= 0 || cos_there <= 0) continue;
      const NearestHit hit = tracer.nearest(from, dir, 0.0, r * (1 - 1e-9));
      if (hit.patch >= 0 && hit.patch != patch && hit.t < r * (1 - 1e-6)) continue;  // in shadow
      const auto exitance = state.face_exitance(static_cast<size_t>(face));
      // (radiance M / pi) cos / (p_cos + p_light): the balance heuristic's share of this strategy.
      const double g = cos_here / (cos_here / std::numbers::pi + light_pdf(face, r, cos_there));
      for (int c = 0; c < 3; ++c) sum[c] += exitance[c] / std::numbers::pi * g / grid.samples;
    }
    // Point sources: exact at the point, where nothing is in between (seen
    // from the lifted point).
    for (const PointLight& light : lights) {
      const Vec3 d = light.options.position - point.position;
      const double r = length(d);
      const double cos_here = r > 0 ? dot(out.normal, d) / r : 0.0;
      if (cos_here <= 0) continue;
      const Vec3 to = light.options.position - from;
      const NearestHit hit = tracer.nearest(from, normalize(to), 0.0, length(to) * (1 - 1e-9));
      if (hit.patch >= 0) continue;
      const double e = light.radiant_intensity(-d / r) * cos_here / (r * r);
      for (int c = 0; c < 3; ++c) sum[c] += e;
    }
    // Cosine rays: the radiosity of what they meet, its emission weighed
    // against the emitter sampling.
    for (int s = 0; s < grid.samples; ++s) {
      // Jittered strata of the unit square (the rest of the samples at random).
      const int cell = s % (strata * strata);
      const double u1 = s < strata * strata ? (cell % strata + uniform(rng)) / strata : uniform(rng);
      const double u2 = s < strata * strata ? (cell / strata + uniform(rng)) / strata : uniform(rng);
      const Vec3 dir = cosine_direction(out.normal, u1, u2);
      const NearestHit hit = tracer.nearest(from, dir, 0.0, tfar);
      if (hit.patch < 0) continue;
      const int face = mesh.face_met(hit.patch, dir);
      if (face < 0) {  // the black back of a one-sided patch
        ++backs;
        continue;
      }
      const auto radiosity = state.radiosity(mesh, static_cast<size_t>(face));
      const auto exitance = state.face_exitance(static_cast<size_t>(face));
      const double cos_here = dot(out.normal, dir), cos_there = std::fabs(dot(mesh.patches[hit.patch].normal, dir));
      const double p_cos = cos_here / std::numbers::pi;
      const double w = area_pdf[static_cast<size_t>(face)] > 0 && cos_there > 0
                           ? p_cos / (p_cos + light_pdf(face, hit.t, cos_there))
                           : 1.0;
      for (int c = 0; c < 3; ++c) sum[c] += (radiosity[c] - exitance[c] + w * exitance[c]) / grid.samples;
    }
    point.irradiance = sum;
    point.illuminance = kWhiteEfficacy * luminance(point.irradiance);
    point.covered = 2 * backs > grid.samples;
  });
  for (const GridPoint& p : out.points) out.covered += p.covered;
  const bool all = out.covered == out.points.size();
  const double counted = static_cast<double>(all ? out.points.size() : out.points.size() - out.covered);
  out.min_lux = INFINITY;
  out.max_lux = -INFINITY;
  for (const GridPoint& p : out.points) {
    if (p.covered && !all) continue;
    out.min_lux = std::min(out.min_lux, p.illuminance);
    out.max_lux = std::max(out.max_lux, p.illuminance);
    out.mean_lux += p.illuminance / counted;
    out.mean_irradiance += (p.irradiance[0] + p.irradiance[1] + p.irradiance[2]) / 3 / counted;
  }
  return out;
}

void write_grid_csv(const std::filesystem::path& path, const GridResult& grid) {
  AtomicFile file(path);
  std::ostream& out = file.stream();
  out << "i,j,x,y,z,irradiance_W_m2,irradiance_r_W_m2,irradiance_g_W_m2,irradiance_b_W_m2,illuminance_lux,covered\n";
  for (size_t k = 0; k < grid.points.size(); ++k) {
    const GridPoint& p = grid.points[k];
    out << fmt::format("{},{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{}\n", k % grid.options.nu,
                       k / grid.options.nu, p.position.x, p.position.y, p.position.z,
                       (p.irradiance[0] + p.irradiance[1] + p.irradiance[2]) / 3, p.irradiance[0], p.irradiance[1],
                       p.irradiance[2], p.illuminance, p.covered ? 1 : 0);
  }
  file.commit();
}

void write_grid_png(const std::filesystem::path& path, const GridResult& grid) {
  const int nu = grid.options.nu, nv = grid.options.nv;
  const int cell = std::max(1, 480 / std::max(nu, nv));
  const int map_w = nu * cell, map_h = nv * cell;
  const int legend_w = 110, bar_w = 20, margin = 10;
  Canvas canvas{map_w + legend_w + 2 * margin, std::max(map_h, 160) + 2 * margin, {}};
  canvas.rgb.assign(static_cast<size_t>(canvas.width) * canvas.height * 3, 255);
  const double lo = grid.min_lux, hi = grid.max_lux, span = hi > lo ? hi - lo : 1.0;
  for (int k = 0; k < nu * nv; ++k) {
    const int i = k % nu, j = k / nu;
    const GridPoint& p = grid.points[static_cast<size_t>(k)];
    // Covered points (in or under an object) are grey: they are not in the figures.
    const auto c = p.covered && grid.covered < grid.points.size() ? std::array<uint8_t, 3>{160, 160, 160}
                                                                  : ramp((p.illuminance - lo) / span);
    for (int y = 0; y < cell; ++y)
      for (int x = 0; x < cell; ++x) canvas.set(margin + i * cell + x, margin + (nv - 1 - j) * cell + y, c);  // v up
  }
  // The legend: a bar from min (bottom) to max (top), labelled in lux.
  const int bar_x = margin + map_w + margin, bar_h = std::max(map_h, 160) - 20, bar_y = margin + 14;
  for (int y = 0; y < bar_h; ++y)
    for (int x = 0; x < bar_w; ++x) canvas.set(bar_x + x, bar_y + y, ramp(1.0 - double(y) / (bar_h - 1)));
  canvas.text(bar_x, margin, "lx", 2);
  for (int tick = 0; tick <= 4; ++tick) {
    const double value = hi - (hi - lo) * tick / 4.0;
    const int y = bar_y + (bar_h - 1) * tick / 4;
    for (int x = 0; x < 4; ++x) canvas.set(bar_x + bar_w + x, y, {0, 0, 0});
    canvas.text(bar_x + bar_w + 6, std::max(0, y - 5), lux_label(value), 2);
  }
  write_png_rgb8(path, canvas.width, canvas.height, canvas.rgb);
}

nlohmann::json grid_json(const GridResult& grid) {
  return {{"name", grid.options.name},
          {"points", grid.points.size()},
          {"covered_points", grid.covered},
          {"nu", grid.options.nu},
          {"nv", grid.options.nv},
          {"samples", grid.options.samples},
          {"normal", {grid.normal.x, grid.normal.y, grid.normal.z}},
          {"illuminance_lux", {{"min", grid.min_lux}, {"mean", grid.mean_lux}, {"max", grid.max_lux}}},
          {"uniformity", grid.uniformity()},
          {"mean_irradiance_W_m2", grid.mean_irradiance},
          {"csv", grid.options.name + ".csv"},
          {"png", grid.options.name + ".png"}};
}

}  // namespace mpath
