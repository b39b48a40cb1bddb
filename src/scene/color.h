// Colour conversions: CIE 1931 colour matching functions (the multi-lobe
// Gaussian fit of Wyman, Sloan and Shirley, JCGT 2013), spectra and colour
// temperatures to chromaticity, and CIE xyY to mpath's linear RGB.
//
// mpath's RGB has the Rec. 709 / sRGB primaries, white-balanced to the
// equal-energy white (CIE x = y = 1/3, MGF's default colour): a colour with
// x = y = 1/3 and luminance Y maps to (Y, Y, Y). See docs/colour.md.
#pragma once

#include <vector>

#include "vec3.h"

namespace mpath {

struct Chromaticity {
  double x = 1.0 / 3.0;
  double y = 1.0 / 3.0;
};

struct Xyz {
  double X = 0, Y = 0, Z = 0;
};

Xyz cie_cmf(double wavelength_nm);

// Chromaticity of a spectrum sampled evenly from lo_nm to hi_nm.
Chromaticity spectrum_chromaticity(double lo_nm, double hi_nm, const std::vector<double>& samples);

// Chromaticity of a black body at `kelvin`.
Chromaticity blackbody_chromaticity(double kelvin);

// xyY to linear RGB (see the file comment). Components may leave [0, 1] for
// saturated colours; callers decide what to do with them.
Rgb xyY_to_rgb(Chromaticity c, double Y);

// Luminance Y of one of mpath's linear RGB values (the inverse of xyY_to_rgb
// for Y): (1, 1, 1) has Y = 1.
double luminance(const Rgb& rgb);

// Luminous efficacy of mpath's white (equal-energy, 179 lm/W, Radiance's):
// MGF's photometric emittance (lm/m2) over it is radiometric exitance (W/m2),
// and a radiometric Y times it is photometric (W/m2 -> lux, W/sr/m2 -> cd/m2).
// RenderPark's MGF reader uses 183.07 (docs/colour.md).
inline constexpr double kWhiteEfficacy = 179.0;

}  // namespace mpath
