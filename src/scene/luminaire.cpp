#include "luminaire.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "color.h"
#include "error.h"
#include "hash.h"
#include "text_tokenizer.h"

namespace mpath {
namespace {

constexpr int kThetaBins = 180, kPhiBins = 360;
constexpr double kDeg = std::numbers::pi / 180.0;

// Linear interpolation in a sorted table of angles; 0 outside it.
double lerp_index(const std::vector<double>& angles, double a, size_t& i0, double& t) {
  if (angles.size() == 1) {
    i0 = 0;
    t = 0;
    return 1;
  }
  if (a < angles.front() - 1e-9 || a > angles.back() + 1e-9) return 0;
  a = std::clamp(a, angles.front(), angles.back());
  i0 = static_cast<size_t>(std::upper_bound(angles.begin(), angles.end(), a) - angles.begin());
  i0 = std::min(std::max<size_t>(i0, 1), angles.size() - 1) - 1;
  const double span = angles[i0 + 1] - angles[i0];
  t = span > 0 ? (a - angles[i0]) / span : 0.0;
  return 1;
}

}  // namespace

LightDistribution::LightDistribution(double candela) : isotropic_(true), candela_(candela) { bin(); }

LightDistribution::LightDistribution(std::vector<double> vertical, std::vector<double> horizontal,
                                     std::vector<double> candela)
    : vertical_(std::move(vertical)), horizontal_(std::move(horizontal)), table_(std::move(candela)) {
  bin();
}

double LightDistribution::intensity(double theta, double phi) const {
  if (isotropic_) return candela_;
  const double v = theta / kDeg;
  double h = std::fmod(phi / kDeg, 360.0);
  if (h < 0) h += 360;
  const double last = horizontal_.back();
  if (horizontal_.size() == 1 || last == 0) h = 0;  // rotationally symmetric
  else if (last == 90) {                           // the same in each quadrant
    h = std::fmod(h, 180.0);
    if (h > 90) h = 180 - h;
  } else if (last == 180 && h > 180) {  // symmetric about the 0-180 plane
    h = 360 - h;
  }
  size_t vi, hi;
  double vt, ht;
  if (!lerp_index(vertical_, v, vi, vt) || !lerp_index(horizontal_, h, hi, ht)) return 0;
  const size_t nv = vertical_.size();
  const auto at = [&](size_t hh, size_t vv) { return table_[hh * nv + vv]; };
  const size_t v1 = std::min(vi + 1, nv - 1), h1 = std::min(hi + 1, horizontal_.size() - 1);
  const double lo = at(hi, vi) * (1 - vt) + at(hi, v1) * vt;
  const double up = at(h1, vi) * (1 - vt) + at(h1, v1) * vt;
  return lo * (1 - ht) + up * ht;
}

void LightDistribution::bin() {
  cdf_.resize(static_cast<size_t>(kThetaBins) * kPhiBins);
  double sum = 0;
  for (int p = 0; p < kPhiBins; ++p)
    for (int t = 0; t < kThetaBins; ++t) {
      const double solid = (std::cos(t * kDeg) - std::cos((t + 1) * kDeg)) * kDeg;
      sum += intensity((t + 0.5) * kDeg, (p + 0.5) * kDeg) * solid;
      cdf_[static_cast<size_t>(p) * kThetaBins + t] = sum;
    }
  flux_ = sum;
}

void LightDistribution::sample(double u1, double u2, double u3, double& theta, double& phi) const {
  const auto it = std::upper_bound(cdf_.begin(), cdf_.end(), u1 * flux_);
  const size_t k = std::min(static_cast<size_t>(it - cdf_.begin()), cdf_.size() - 1);
  const int t = static_cast<int>(k % kThetaBins), p = static_cast<int>(k / kThetaBins);
  const double c0 = std::cos(t * kDeg), c1 = std::cos((t + 1) * kDeg);
  theta = std::acos(std::clamp(c0 + (c1 - c0) * u2, -1.0, 1.0));  // uniform in solid angle within the bin
  phi = (p + u3) * kDeg;
}

uint64_t LightDistribution::sampling_hash() const {
  Fnv1a h;
  h.add(&isotropic_, sizeof isotropic_);
  h.add(&flux_, sizeof flux_);
  h.add(cdf_.data(), cdf_.size() * sizeof(double));
  return h.value();
}

LightDistribution read_ies(const std::filesystem::path& path) {
  require_scene_file(path);
  std::ifstream in(path);
  if (!in) throw InputError(fmt::format("{}: cannot open the IES file", path.string()));
  const auto fail = [&](const std::string& why) {
    return InputError(fmt::format("{}: not an IESNA LM-63 photometric file mpath reads: {}", path.string(), why));
  };
  std::string line, tilt;
  for (int n = 0; std::getline(in, line) && n < 10000; ++n)
    if (line.rfind("TILT=", 0) == 0) {
      tilt = line.substr(5);
      break;
    }
  while (!tilt.empty() && std::isspace(static_cast<unsigned char>(tilt.back()))) tilt.pop_back();
  if (tilt.empty()) throw fail("no TILT= line");
  std::vector<double> v;
  for (std::string word; in >> word;) {
    double x = 0;
    try {
      size_t used = 0;
      x = std::stod(word, &used);
      if (used != word.size()) throw std::invalid_argument(word);
    } catch (const std::exception&) {
      throw fail(fmt::format("'{}' is not a number", word));
    }
    if (!std::isfinite(x)) throw fail(fmt::format("'{}' is not a finite number", word));
    v.push_back(x);
    if (v.size() > 10'000'000) throw fail("more than 1e7 numbers");
  }
  size_t at = 0;
  const auto next = [&](const char* what) {
    if (at >= v.size()) throw fail(fmt::format("the file ends before {}", what));
    return v[at++];
  };
  const auto count = [&](const char* what, double most) {
    const double n = next(what);
    if (!(n >= 1 && n <= most) || n != std::floor(n)) throw fail(fmt::format("{} {} is not a count from 1 to {}", what, n, most));
    return static_cast<size_t>(n);
  };
  if (tilt == "INCLUDE") {  // lamp-to-luminaire geometry, then angles and multipliers: read, not used
    next("the tilt geometry");
    const size_t n = count("the number of tilt angles", 1e4);
    for (size_t k = 0; k < 2 * n; ++k) next("the tilt table");
  } else if (tilt != "NONE") {
    throw fail(fmt::format("TILT={} (a tilt file) is not read; give the tilt table inline or TILT=NONE", tilt));
  }
  next("the number of lamps");
  next("the lumens per lamp");
  const double multiplier = next("the candela multiplier");
  const size_t nv = count("the number of vertical angles", 1e4), nh = count("the number of horizontal angles", 1e4);
  const double type = next("the photometric type");
  if (type != 1) throw fail(fmt::format("photometric type {} (only type C, 1, is read)", type));
  for (const char* what : {"the units", "the width", "the length", "the height"}) next(what);
  const double ballast = next("the ballast factor"), lamp_factor = next("the ballast-lamp factor");
  next("the input watts");
  std::vector<double> vertical(nv), horizontal(nh), candela(nv * nh);
  for (double& a : vertical) a = next("the vertical angles");
  for (double& a : horizontal) a = next("the horizontal angles");
  for (double& c : candela) c = next("the candela values") * multiplier * ballast * lamp_factor;
  if (at != v.size()) throw fail(fmt::format("{} numbers after the candela table", v.size() - at));
  for (size_t k = 1; k < nv; ++k)
    if (!(vertical[k] > vertical[k - 1])) throw fail("the vertical angles do not increase");
  for (size_t k = 1; k < nh; ++k)
    if (!(horizontal[k] > horizontal[k - 1])) throw fail("the horizontal angles do not increase");
  if (vertical.front() < 0 || vertical.back() > 180) throw fail("vertical angles outside 0 to 180 degrees");
  if (horizontal.front() != 0 || !(horizontal.back() == 0 || horizontal.back() == 90 || horizontal.back() == 180 ||
                                   horizontal.back() == 360))
    throw fail("horizontal angles must run from 0 to 0, 90, 180 or 360 degrees");
  for (double c : candela)
    if (c < 0) throw fail("a negative candela value");
  return LightDistribution(std::move(vertical), std::move(horizontal), std::move(candela));
}

double PointLight::radiant_intensity(const Vec3& dir) const {
  const double theta = std::acos(std::clamp(dot(dir, nadir), -1.0, 1.0));
  const double phi = std::atan2(dot(dir, c90), dot(dir, c0));
  return options.multiplier * distribution.intensity(theta, phi) / kWhiteEfficacy;
}

double PointLight::power() const { return flux() / kWhiteEfficacy; }

Vec3 PointLight::sample(double u1, double u2, double u3) const {
  double theta, phi;
  distribution.sample(u1, u2, u3, theta, phi);
  return normalize(nadir * std::cos(theta) + (c0 * std::cos(phi) + c90 * std::sin(phi)) * std::sin(theta));
}

uint64_t PointLight::lines_hash() const {
  Fnv1a h;
  for (const Vec3* v : {&options.position, &nadir, &c0, &c90}) h.add(v, sizeof *v);
  const uint64_t shape = distribution.sampling_hash();
  h.add(&shape, sizeof shape);
  return h.value();
}

std::vector<PointLight> make_lights(const std::vector<LightOptions>& options) {
  std::vector<PointLight> lights;
  for (const LightOptions& l : options) lights.push_back(make_light(l));
  return lights;
}

PointLight make_light(const LightOptions& options) {
  PointLight light;
  light.options = options;
  light.distribution = options.ies.empty() ? LightDistribution(options.intensity_cd) : read_ies(options.ies);
  light.nadir = normalize(options.nadir);
  light.c0 = normalize(options.c0 - light.nadir * dot(options.c0, light.nadir));
  light.c90 = cross(light.nadir, light.c0);
  return light;
}

}  // namespace mpath
