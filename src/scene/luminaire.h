// Point sources: a luminous intensity distribution (isotropic, or read from
// an IESNA LM-63 photometric file, type C), placed and aimed in the scene.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "vec3.h"

namespace mpath {

// A point source as the config gives it ([[light]]).
struct LightOptions {
  std::string name = "light";
  Vec3 position{0, 0, 0};
  double intensity_cd = 0;     // isotropic intensity (when no `ies`)
  std::filesystem::path ies;   // LM-63 file: its candela table
  double multiplier = 1.0;     // scales the intensity (dimming, a maintenance factor)
  Vec3 nadir{0, 0, -1};        // the luminaire's 0 degree vertical angle (photometric type C)
  Vec3 c0{1, 0, 0};            // the direction of its 0 degree horizontal plane
};

// Luminous intensity I (cd) over directions, binned at 1 degree for sampling.
class LightDistribution {
 public:
  // Isotropic: I everywhere.
  explicit LightDistribution(double candela);
  // Type C table: vertical angles (from nadir, degrees), horizontal angles
  // (degrees; the last 0, 90, 180 or 360 gives the symmetry), candela per
  // horizontal angle, then per vertical angle.
  LightDistribution(std::vector<double> vertical, std::vector<double> horizontal, std::vector<double> candela);

  // Intensity (cd) towards (theta from nadir, phi from the C0 plane), radians.
  double intensity(double theta, double phi) const;
  // Luminous flux (lm): the integral of I over the sphere (of the 1 degree bins).
  double flux() const { return flux_; }
  // A direction drawn in proportion to I (of the bins), from three uniform numbers.
  void sample(double u1, double u2, double u3, double& theta, double& phi) const;
  // A hash of what sample() draws from (the bins' cumulative intensity, as
  // read: a table scaled otherwise hashes otherwise); PointLight's
  // multiplier does not enter it.
  uint64_t sampling_hash() const;

 private:
  void bin();
  bool isotropic_ = false;
  double candela_ = 0;
  std::vector<double> vertical_, horizontal_, table_;
  std::vector<double> cdf_;  // per 1 x 1 degree bin, theta fastest
  double flux_ = 0;
};

// Reads an IESNA LM-63 file (1986, 1991, 1995, 2002): TILT=NONE or INCLUDE
// (the tilt table is read and ignored), photometric type C, candela times the
// multiplier, ballast factor and ballast-lamp factor. InputError naming the
// file on anything else.
LightDistribution read_ies(const std::filesystem::path& path);

// A light in the scene: its distribution, frame and radiant intensity.
struct PointLight {
  LightOptions options;
  LightDistribution distribution{0.0};
  Vec3 nadir, c0, c90;  // orthonormal frame
  // Radiant intensity (W/sr, equal-energy white) towards world direction `dir`.
  double radiant_intensity(const Vec3& dir) const;
  // Luminous flux (lm) and radiant power (W, flux / 179 lm/W) of the light.
  double flux() const { return options.multiplier * distribution.flux(); }
  double power() const;
  // A world direction drawn in proportion to the intensity.
  Vec3 sample(double u1, double u2, double u3) const;
  // A hash of where sample() sends lines from: the position, the frame and
  // the distribution's sampling_hash (not its power).
  uint64_t lines_hash() const;
};

PointLight make_light(const LightOptions& options);
// make_light of each of a config's [[light]]s, in order.
std::vector<PointLight> make_lights(const std::vector<LightOptions>& options);

}  // namespace mpath
