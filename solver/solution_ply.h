// solution.ply: one face per patch face with the properties of design.md
// section 10 (binary little-endian).
#pragma once

#include <filesystem>

#include "radiosity_state.h"

namespace mpath {

void write_solution_ply(const std::filesystem::path& path, const PatchMesh& mesh, const RadiosityState& state);

}  // namespace mpath
