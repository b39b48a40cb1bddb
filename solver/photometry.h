// Photometric results of a solution: grids of illuminance sensors on work
// planes ([[grid]] in the config), gathered from the solved radiosities.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "config.h"
#include "luminaire.h"
#include "radiosity_state.h"
#include "tracer.h"

namespace mpath {

struct GridPoint {
  Vec3 position;
  Rgb irradiance{};  // W/m2 per channel
  double illuminance = 0;  // lux
  bool covered = false;    // most of its rays meet a black back: it lies inside or under an object
};

struct GridResult {
  GridOptions options;
  Vec3 normal;
  std::vector<GridPoint> points;  // row j = 0 .. nv - 1, each i = 0 .. nu - 1
  // Over the points not covered (over all of them if every point is).
  double min_lux = 0, mean_lux = 0, max_lux = 0;
  double mean_irradiance = 0;  // W/m2, mean of the channels
  size_t covered = 0;
  // min / mean, as EN 12464 asks (0 for a dark grid).
  double uniformity() const { return mean_lux > 0 ? min_lux / mean_lux : 0.0; }
};

// Irradiance at every point of the grid, gathered from the solution: the
// radiosity of the faces met by `samples` cosine-distributed rays about the
// grid's normal (E = pi times the mean radiance seen; a black back or the
// outside counts 0), with the emitters' own light also sampled from
// `samples` points on the emitting faces (picked by power, where nothing is
// in between) and the two estimates of it weighed by the balance heuristic. Illuminance is 179 lm/W times its
// luminance. A point most of whose rays meet a black back is covered (in or
// under an object: a book on the desk) and left out of the figures.
// Point sources add their direct light, I cos / r^2 where nothing is in between.
GridResult measure_grid(const GridOptions& grid, const PatchMesh& mesh, const Tracer& tracer,
                        const RadiosityState& state, const std::vector<PointLight>& lights, unsigned long long seed);

// NAME.csv (one row per point), NAME.png (false colour with a legend in lux).
void write_grid_csv(const std::filesystem::path& path, const GridResult& grid);
void write_grid_png(const std::filesystem::path& path, const GridResult& grid);

// Its figures for report.json: min, mean, max, uniformity min / mean (EN 12464).
nlohmann::json grid_json(const GridResult& grid);

}  // namespace mpath
