#include "color.h"

#include <gtest/gtest.h>

namespace mpath {
namespace {

TEST(Color, EqualEnergyWhiteIsGreyWithItsLuminance) {
  const Rgb rgb = xyY_to_rgb({1.0 / 3.0, 1.0 / 3.0}, 0.42);
  for (double c : rgb) EXPECT_NEAR(c, 0.42, 1e-12);
}

// Luminance undoes xyY_to_rgb for Y, for any chromaticity in the gamut
// (lux and cd/m2 are 179 lm/W times it).
TEST(Color, LuminanceOfAColourIsItsY) {
  EXPECT_NEAR(luminance({1, 1, 1}), 1.0, 1e-6);
  for (const Chromaticity c : {Chromaticity{0.3127, 0.3290}, Chromaticity{0.45, 0.41}, Chromaticity{0.25, 0.3},
                               Chromaticity{0.6, 0.33}})
    for (const double Y : {0.01, 0.5, 3.0}) EXPECT_NEAR(luminance(xyY_to_rgb(c, Y)), Y, 1e-6 * Y) << c.x << ", " << c.y;
}

TEST(Color, SaturatedPrimariesKeepTheirHue) {
  const Rgb red = xyY_to_rgb({0.64, 0.33}, 0.2);
  EXPECT_GT(red[0], 5 * red[1]);
  EXPECT_GT(red[0], 5 * red[2]);
  const Rgb green = xyY_to_rgb({0.30, 0.60}, 0.2);
  EXPECT_GT(green[1], green[0]);
  EXPECT_GT(green[1], green[2]);
}

// The Gaussian fit of the CIE functions is good to about 1% of their peaks,
// so chromaticities computed with it are good to a few thousandths.
TEST(Color, BlackbodyAt6504KelvinIsNearD65) {
  const Chromaticity c = blackbody_chromaticity(6504);
  EXPECT_NEAR(c.x, 0.3135, 0.004);
  EXPECT_NEAR(c.y, 0.3237, 0.004);
}

TEST(Color, FlatSpectrumIsNearEqualEnergyWhite) {
  const Chromaticity c = spectrum_chromaticity(360, 830, {1.0, 1.0});
  EXPECT_NEAR(c.x, 1.0 / 3.0, 0.004);
  EXPECT_NEAR(c.y, 1.0 / 3.0, 0.004);
}

TEST(Color, MatchingFunctionsPeakWhereTheCieTablesDo) {
  EXPECT_NEAR(cie_cmf(555).Y, 1.0, 0.02);
  EXPECT_GT(cie_cmf(600).X, cie_cmf(500).X);
  EXPECT_GT(cie_cmf(445).Z, 1.7);
}

}  // namespace
}  // namespace mpath
