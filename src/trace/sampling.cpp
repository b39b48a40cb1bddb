#include "sampling.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

namespace mpath {

Rng make_rng(unsigned long long seed, unsigned purpose, unsigned long long shard) {
  // pcg's stream selector takes 63 bits; mix purpose and shard into it.
  const unsigned long long stream = (static_cast<unsigned long long>(purpose) << 40) ^ shard;
  return Rng(seed, stream);
}

Vec3 cosine_direction(const Vec3& n, Rng& rng) {
  const double u1 = uniform(rng), u2 = uniform(rng);
  return cosine_direction(n, u1, u2);
}

Vec3 cosine_direction(const Vec3& n, double u1, double u2) {
  Vec3 t, b;
  orthonormal_basis(n, t, b);
  return cosine_direction(t, b, n, u1, u2);
}

Vec3 cosine_direction(const Vec3& t, const Vec3& b, const Vec3& n, double u1, double u2) {
  const double r = std::sqrt(u1), phi = 2.0 * std::numbers::pi * u2;
  return t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * std::sqrt(std::max(0.0, 1.0 - u1));
}

namespace {
Vec3 triangle_point(const Vec3& a, const Vec3& b, const Vec3& c, double u, double v) {
  if (u + v > 1) {
    u = 1 - u;
    v = 1 - v;
  }
  return a + (b - a) * u + (c - a) * v;
}

Vec3 triangle_point(const Vec3& a, const Vec3& b, const Vec3& c, Rng& rng) {
  const double u = uniform(rng), v = uniform(rng);
  return triangle_point(a, b, c, u, v);
}

// The areas of quad v0 v1 v2 v3's two triangles, (v0, v1, v3) and (v2, v3, v1).
std::pair<double, double> quad_areas(const Vec3& v0, const Vec3& v1, const Vec3& v2, const Vec3& v3) {
  return {0.5 * length(cross(v1 - v0, v3 - v0)), 0.5 * length(cross(v3 - v2, v1 - v2))};
}

// The share of quad v0 v1 v2 v3's area in its first triangle.
double quad_split(const Vec3& v0, const Vec3& v1, const Vec3& v2, const Vec3& v3) {
  const auto [a1, a2] = quad_areas(v0, v1, v2, v3);
  return a1 / (a1 + a2);
}

// The point of quad v0 v1 v2 v3 that u1, u2 give, `c` its quad_split.
Vec3 quad_point(const Vec3& v0, const Vec3& v1, const Vec3& v2, const Vec3& v3, double c, double u1, double u2) {
  if (u1 < c) return triangle_point(v0, v1, v3, u1 / c, u2);
  return triangle_point(v2, v3, v1, std::min((u1 - c) / (1 - c), std::nextafter(1.0, 0.0)), u2);
}
}  // namespace

Vec3 uniform_point(const PatchMesh& mesh, const Patch& p, double u1, double u2) {
  const Vec3& v0 = mesh.vertices[p.v[0]];
  const Vec3& v1 = mesh.vertices[p.v[1]];
  const Vec3& v2 = mesh.vertices[p.v[2]];
  if (p.is_triangle()) return triangle_point(v0, v1, v2, u1, u2);
  const Vec3& v3 = mesh.vertices[p.v[3]];
  return quad_point(v0, v1, v2, v3, quad_split(v0, v1, v2, v3), u1, u2);
}

PatchSampler::PatchSampler(const PatchMesh& mesh, const Patch& patch, const Vec3& normal)
    : triangle_(patch.is_triangle()), n_(normal) {
  for (int k = 0; k < 4; ++k) v_[k] = mesh.vertices[patch.v[k]];
  if (!triangle_) split_ = quad_split(v_[0], v_[1], v_[2], v_[3]);
  orthonormal_basis(n_, t_, b_);
}

Vec3 PatchSampler::point(double u1, double u2) const {
  if (triangle_) return triangle_point(v_[0], v_[1], v_[2], u1, u2);
  return quad_point(v_[0], v_[1], v_[2], v_[3], split_, u1, u2);
}

Vec3 uniform_point(const PatchMesh& mesh, const Patch& p, Rng& rng) {
  const Vec3& v0 = mesh.vertices[p.v[0]];
  const Vec3& v1 = mesh.vertices[p.v[1]];
  const Vec3& v2 = mesh.vertices[p.v[2]];
  if (p.is_triangle()) return triangle_point(v0, v1, v2, rng);
  const Vec3& v3 = mesh.vertices[p.v[3]];
  const auto [a1, a2] = quad_areas(v0, v1, v2, v3);
  if (uniform(rng) * (a1 + a2) < a1) return triangle_point(v0, v1, v3, rng);
  return triangle_point(v2, v3, v1, rng);
}

namespace {

// Digits of `index` in base `base` mirrored about the radix point, one at a time.
double mirrored_digits(uint64_t index, unsigned base) {
  double f = 1.0 / base, result = 0;
  for (; index > 0; index /= base, f /= base) result += f * static_cast<double>(index % base);
  return result;
}

// The same, M digits at a time from a table of the B^M mirrored M-digit
// numbers: a line's four coordinates took 6 % of preprocessing one digit at a time.
template <unsigned B, unsigned M>
double radical_inverse_in(uint64_t index) {
  static constexpr uint64_t kBlock = [] {
    uint64_t n = 1;
    for (unsigned k = 0; k < M; ++k) n *= B;
    return n;
  }();
  static const std::vector<double> table = [] {
    std::vector<double> t(kBlock);
    for (uint64_t d = 0; d < kBlock; ++d) t[d] = mirrored_digits(d, B);
    return t;
  }();
  constexpr double inv = 1.0 / static_cast<double>(kBlock);
  double f = 1.0, result = 0;
  while (index > 0) {
    const uint64_t next = index / kBlock;
    result += f * table[index - next * kBlock];
    index = next;
    f *= inv;
  }
  return result;
}

// Base 2: the bits reversed, exact (the same value as the digit loop).
double radical_inverse_2(uint64_t v) {
  v = ((v >> 1) & 0x5555555555555555ull) | ((v & 0x5555555555555555ull) << 1);
  v = ((v >> 2) & 0x3333333333333333ull) | ((v & 0x3333333333333333ull) << 2);
  v = ((v >> 4) & 0x0F0F0F0F0F0F0F0Full) | ((v & 0x0F0F0F0F0F0F0F0Full) << 4);
  v = __builtin_bswap64(v);
  return std::min(static_cast<double>(v) * 0x1p-64, 0x1.fffffffffffffp-1);
}

}  // namespace

double radical_inverse(uint64_t index, unsigned base) {
  switch (base) {
    case 2: return radical_inverse_2(index);
    case 3: return radical_inverse_in<3, 7>(index);
    case 5: return radical_inverse_in<5, 5>(index);
    case 7: return radical_inverse_in<7, 4>(index);
    default: return mirrored_digits(index, base);
  }
}

ShiftedHalton::ShiftedHalton(Rng rng) {
  for (double& s : shift_) s = uniform(rng);
}

LineSequence::LineSequence(const std::string& kind, unsigned long long seed, unsigned pass)
    : halton_(kind == "halton"), points_(make_rng(seed, 4, pass)) {}

void LineSequence::point(uint64_t index, Rng& rng, double u[4]) const {
  if (!halton_) {
    for (int k = 0; k < 4; ++k) u[k] = uniform(rng);
    return;
  }
  points_.point(index, u);
}

void shifted_halton(uint64_t index, const double shift[4], double u[4]) {
  // The bases' functions called by name, not through radical_inverse's
  // switch: inlined, where the loop over the bases was a call each.
  const double x[4] = {radical_inverse_2(index), radical_inverse_in<3, 7>(index), radical_inverse_in<5, 5>(index),
                       radical_inverse_in<7, 4>(index)};
  for (int k = 0; k < 4; ++k) {
    const double y = x[k] + shift[k];
    u[k] = y >= 1.0 ? y - 1.0 : y;
  }
}

IndexPermutation::IndexPermutation(uint64_t n, Rng& rng) : n_(n) {
  unsigned bits = 0;
  while (bits < 64 && (uint64_t{1} << bits) < n) ++bits;
  low_bits_ = bits / 2;
  high_bits_ = bits - low_bits_;
  for (uint64_t& k : keys_) k = (static_cast<uint64_t>(rng()) << 32) | rng();
}

namespace {
// splitmix64's finaliser: every input bit moves every output bit.
uint64_t mix(uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
}  // namespace

unsigned long long derived_seed(unsigned long long seed, unsigned long long a, unsigned long long b) {
  return mix(mix(mix(seed) ^ a) ^ b);
}

uint64_t IndexPermutation::round_trip(uint64_t x) const {
  if (high_bits_ == 0) return x;  // n <= 1
  const uint64_t low_mask = (uint64_t{1} << low_bits_) - 1;
  const uint64_t high_mask = (uint64_t{1} << high_bits_) - 1;  // at most 32 bits
  uint64_t low = x & low_mask, high = (x >> low_bits_) & high_mask;
  // Each round changes one half by a function of the other: a bijection
  // whatever the function, so the four together are one too.
  for (int r = 0; r < 4; r += 2) {
    high = (high + mix(low ^ keys_[r])) & high_mask;
    low = (low + mix(high ^ keys_[r + 1])) & low_mask;
  }
  return (high << low_bits_) | low;
}

BoxLineSampler::BoxLineSampler(const Bounds& box) : box_(box) {
  const Vec3 s = box.size();
  const double areas[3] = {s.y * s.z, s.z * s.x, s.x * s.y};
  double sum = 0;
  for (int f = 0; f < 6; ++f) {
    sum += areas[f / 2];
    face_cdf_[f] = sum;
  }
  for (double& c : face_cdf_) c /= sum;
  for (int f = 0; f < 6; ++f) {
    Vec3 inward;
    inward[f / 2] = f % 2 == 1 ? -1.0 : 1.0;
    orthonormal_basis(inward, tangent_[f], bitangent_[f]);
  }
  hair_ = 1e-6 * box.diagonal();
}

GlobalLine BoxLineSampler::sample(Rng& rng) const {
  const double u[4] = {uniform(rng), uniform(rng), uniform(rng), uniform(rng)};
  return sample(u);
}

GlobalLine BoxLineSampler::sample(const double r[4]) const {
  int face = 0;
  while (face < 5 && r[0] >= face_cdf_[face]) ++face;
  const double below = face > 0 ? face_cdf_[face - 1] : 0.0;
  const double first = std::clamp((r[0] - below) / (face_cdf_[face] - below), 0.0, 1.0);
  const int axis = face / 2;
  const bool high = face % 2 == 1;
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  Vec3 p;
  p[axis] = high ? box_.hi[axis] : box_.lo[axis];
  p[u] = box_.lo[u] + first * (box_.hi[u] - box_.lo[u]);
  p[v] = box_.lo[v] + r[1] * (box_.hi[v] - box_.lo[v]);
  Vec3 inward;
  inward[axis] = high ? -1.0 : 1.0;
  const Vec3 dir = cosine_direction(tangent_[face], bitangent_[face], inward, r[2], r[3]);
  // Distance to the far wall (slab exit).
  double exit = INFINITY;
  for (int i = 0; i < 3; ++i) {
    if (dir[i] > 0) exit = std::min(exit, (box_.hi[i] - p[i]) / dir[i]);
    else if (dir[i] < 0) exit = std::min(exit, (box_.lo[i] - p[i]) / dir[i]);
  }
  return {p - dir * hair_, dir, exit + 2.0 * hair_};
}

}  // namespace mpath
