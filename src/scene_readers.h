// Scene file readers. Each throws InputError with file:line on malformed input.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "config.h"
#include "scene.h"

namespace mpath {

Scene read_obj(const std::filesystem::path& path);
Scene read_ply(const std::filesystem::path& path);
// Bytes of a PLY scalar type ("uchar", "float32", ...); 0 for an unknown one.
size_t ply_type_size(const std::string& type);
// `default_sides`: sides of a material without a `sides` entity. `warnings`
// receives notes on colours clamped into the RGB gamut.
Scene read_mgf(const std::filesystem::path& path, int curve_segments, int default_sides,
               std::vector<std::string>* warnings);

// Reads the scene named by options.scene.file (format by extension), applies
// the config's emitters and two-sided materials, and checks the result.
// Notes worth a user's attention are appended to `warnings`.
Scene load_scene(const Options& options, std::vector<std::string>& warnings);

}  // namespace mpath
