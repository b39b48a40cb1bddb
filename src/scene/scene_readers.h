// Scene file readers. Each throws InputError with file:line on malformed input.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "luminaire.h"
#include "scene.h"

namespace mpath {

// `warnings` (if given) gets what was skipped or assumed.
Scene read_obj(const std::filesystem::path& path, std::vector<std::string>* warnings = nullptr);
Scene read_ply(const std::filesystem::path& path);
// Bytes of a PLY scalar type ("uchar", "float32", ...); 0 for an unknown one.
size_t ply_type_size(const std::string& type);
// `default_sides`: sides of a material without a `sides` entity. `warnings`
// receives notes on colours clamped into the RGB gamut.
Scene read_mgf(const std::filesystem::path& path, int curve_segments, int default_sides,
               std::vector<std::string>* warnings);

// What the config says of the scene (section [scene]).
struct SceneOptions {
  std::filesystem::path file;
  std::map<std::string, Rgb> emitters;   // material -> emitted radiance, W/sr/m2
  std::map<std::string, Rgb> materials;  // material -> diffuse reflectance
  std::vector<LightOptions> lights;      // point sources ([[light]])
  std::vector<std::string> two_sided;
  int mgf_default_sides = 2;  // sides of MGF materials without a `sides` entity (the MGF default)
};

// Reads the scene `options.file` (format by extension; MGF curves with
// `curve_segments` segments around a circle), applies the emitters and
// two-sided materials named in `options`, and checks the result. Notes worth
// a user's attention are appended to `warnings`.
Scene load_scene(const SceneOptions& options, int curve_segments, std::vector<std::string>& warnings);

}  // namespace mpath
