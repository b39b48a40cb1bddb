#include "color.h"

#include <cmath>

namespace mpath {
namespace {

double lobe(double x, double mu, double sigma_lo, double sigma_hi) {
  const double t = (x - mu) / (x < mu ? sigma_lo : sigma_hi);
  return std::exp(-0.5 * t * t);
}

Chromaticity chromaticity(const Xyz& c) {
  const double sum = c.X + c.Y + c.Z;
  if (sum <= 0) return {};
  return {c.X / sum, c.Y / sum};
}

// XYZ to linear Rec. 709 RGB (D65), IEC 61966-2-1.
Rgb xyz_to_709(const Xyz& c) {
  return {3.2404542 * c.X - 1.5371385 * c.Y - 0.4985314 * c.Z,
          -0.9692660 * c.X + 1.8760108 * c.Y + 0.0415560 * c.Z,
          0.0556434 * c.X - 0.2040259 * c.Y + 1.0572252 * c.Z};
}

}  // namespace

Xyz cie_cmf(double l) {
  return {1.056 * lobe(l, 599.8, 37.9, 31.0) + 0.362 * lobe(l, 442.0, 16.0, 26.7) -
              0.065 * lobe(l, 501.1, 20.4, 26.2),
          0.821 * lobe(l, 568.8, 46.9, 40.5) + 0.286 * lobe(l, 530.9, 16.3, 31.1),
          1.217 * lobe(l, 437.0, 11.8, 36.0) + 0.681 * lobe(l, 459.0, 26.0, 13.8)};
}

Chromaticity spectrum_chromaticity(double lo, double hi, const std::vector<double>& s) {
  Xyz sum;
  if (s.size() < 2 || !(hi > lo)) return {};
  // Integrate the piecewise-linear spectrum at 1 nm steps where the observer sees (360 to 830 nm).
  const double a = std::max(lo, 360.0), b = std::min(hi, 830.0);
  if (!(b > a)) return {};
  const int steps = std::max(1, static_cast<int>(std::ceil(b - a)));
  for (int i = 0; i <= steps; ++i) {
    const double l = a + (b - a) * i / steps;
    const double u = (l - lo) / (hi - lo) * static_cast<double>(s.size() - 1);
    const size_t k = std::min(static_cast<size_t>(u), s.size() - 2);
    const double v = s[k] + (s[k + 1] - s[k]) * (u - static_cast<double>(k));
    const Xyz c = cie_cmf(l);
    sum.X += v * c.X;
    sum.Y += v * c.Y;
    sum.Z += v * c.Z;
  }
  return chromaticity(sum);
}

Chromaticity blackbody_chromaticity(double kelvin) {
  Xyz sum;
  for (double l = 360; l <= 830; l += 1.0) {
    const double m = l * 1e-9;
    // Planck's law up to a constant factor (only the chromaticity is wanted).
    const double b = 1.0 / (m * m * m * m * m * (std::exp(1.4387769e-2 / (m * kelvin)) - 1.0));
    const Xyz c = cie_cmf(l);
    sum.X += b * c.X;
    sum.Y += b * c.Y;
    sum.Z += b * c.Z;
  }
  return chromaticity(sum);
}

double luminance(const Rgb& rgb) {
  // Y = (the Y row of the Rec. 709 XYZ matrix) . (rgb scaled back by the white balance).
  // Normalised so that white (1, 1, 1) is 1 to rounding (the published
  // coefficients of the two matrices agree to 1e-7 only).
  static const std::array<double, 3> w = [] {
    const Rgb white = xyz_to_709({1.0, 1.0, 1.0});
    std::array<double, 3> k{0.2126729 * white[0], 0.7151522 * white[1], 0.0721750 * white[2]};
    const double sum = k[0] + k[1] + k[2];
    for (double& x : k) x /= sum;
    return k;
  }();
  return w[0] * rgb[0] + w[1] * rgb[1] + w[2] * rgb[2];
}

Rgb xyY_to_rgb(Chromaticity c, double Y) {
  if (c.y <= 0 || Y == 0) return {0, 0, 0};
  const Xyz xyz{c.x / c.y * Y, Y, (1.0 - c.x - c.y) / c.y * Y};
  static const Rgb white = xyz_to_709({1.0, 1.0, 1.0});
  const Rgb rgb = xyz_to_709(xyz);
  return {rgb[0] / white[0], rgb[1] / white[1], rgb[2] / white[2]};
}

}  // namespace mpath
