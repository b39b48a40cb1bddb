// mpath-compare: the error of one radiosity solution against another on the
// same mesh (area-weighted MSE and relative RMS over patch faces, the
// distribution of per-face relative errors) and per-patch relative-error
// images through the config's cameras.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "config.h"
#include "solution_ply.h"

namespace mpath {

inline constexpr double kDarkFraction = 1e-3;

struct Comparison {
  size_t faces = 0;
  double area = 0;
  // Errors are of radiosity B; emission E is input, the same in both, so the
  // relative errors are of the reflected part B - E (emitters' large B would
  // otherwise hide the error everywhere else).
  double mse = 0;            // area-weighted over faces, mean of the three channels
  double rel_rms = 0;        // sqrt(sum a |B - B_ref|^2 / sum a |B_ref - E|^2)
  double rel_rms_total = 0;  // sqrt(sum a |B - B_ref|^2 / sum a |B_ref|^2)
  // Per-face relative error of the reflected mean channel, Y = mean(B - E),
  // |Y - Y_ref| / Y_ref, over
  // faces with Y_ref above kDarkFraction of the area-weighted mean:
  // area-weighted mean and quantiles.
  double mean_relative = 0, p50 = 0, p90 = 0, p99 = 0;
  std::vector<double> relative;  // per face; negative where the reference is dark
};

// InputError when the two are not solutions on the same mesh.
Comparison compare_solutions(const SolutionFaces& result, const SolutionFaces& reference);

struct CompareFlags {
  std::filesystem::path result, reference, out;
  double scale = 0.2;  // relative error shown at the top of the colour map
  bool images = true;
};

// Loads and meshes the config's scene (which must be the solutions' mesh),
// compares, writes OUT/compare.json and, per camera, OUT/<camera>_error.exr
// (relative error per pixel) and OUT/<camera>_error.png (colour-mapped).
void run_compare(const Options& options, const CompareFlags& flags);

}  // namespace mpath
