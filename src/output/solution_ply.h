// solution.ply, mpath's result file: one face per patch face with the
// properties listed in docs/user-guide.md (binary little-endian). The one
// writer and reader of it in mpath.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "mesh.h"

namespace mpath {

// What solution.ply holds of a patch face beside its geometry (W/m2).
struct SolutionFace {
  Rgb rho, exitance, radiosity;
};

// The sRGB byte of a linear value in [0, 1] (clamped) that solution.ply's
// colours use: round(255 * sRGB transfer(v)).
uint8_t display_srgb8(double linear);

// `faces` in mesh face order.
void write_solution_ply(const std::filesystem::path& path, const PatchMesh& mesh, const std::vector<SolutionFace>& faces);

// The per-face values of a solution.ply that a comparison needs.
struct SolutionFaces {
  std::vector<float> area;
  std::vector<std::array<float, 3>> radiosity;
  std::vector<std::array<float, 3>> exitance;  // emitted; zero when the file has no emit_* properties
};

// Reads mpath's solution.ply (binary little-endian, any order of face
// properties as long as area, B_r, B_g, B_b are there); InputError naming the
// file when it is not one or is cut short.
SolutionFaces read_solution_ply(const std::filesystem::path& path);

}  // namespace mpath
