// Random numbers and the sampling of points, directions and global lines.
#pragma once

#include <pcg_random.hpp>
#include <string>

#include "box_geometry.h"
#include "mesh.h"

namespace mpath {

using Rng = pcg32;

// Independent stream for (seed, purpose, shard): same inputs, same numbers.
Rng make_rng(unsigned long long seed, unsigned purpose, unsigned long long shard);

// A seed of its own for (seed, a, b), for streams named by more numbers than
// make_rng's purpose and shard hold: distinct seeds give distinct results
// for the same a and b (each step is a bijection of 64 bits).
unsigned long long derived_seed(unsigned long long seed, unsigned long long a, unsigned long long b);

// rng() * 2^-32: exact, as std::ldexp(rng(), -32) was, without its call.
inline double uniform(Rng& rng) { return static_cast<double>(rng()) * 0x1p-32; }

// Cosine-distributed direction about unit normal n.
Vec3 cosine_direction(const Vec3& n, Rng& rng);
Vec3 cosine_direction(const Vec3& n, double u1, double u2);
// The same about n with its orthonormal_basis t, b found beforehand.
Vec3 cosine_direction(const Vec3& t, const Vec3& b, const Vec3& n, double u1, double u2);

// Uniform point on a patch (a quad is split as Embree splits it).
Vec3 uniform_point(const PatchMesh& mesh, const Patch& patch, Rng& rng);
// The same from two numbers in [0, 1): the first picks a quad's triangle by
// area and is stretched back to [0, 1), so stratified numbers give
// stratified points.
Vec3 uniform_point(const PatchMesh& mesh, const Patch& patch, double u1, double u2);

// uniform_point(mesh, patch, u1, u2) and cosine_direction(normal, u3, u4)
// for the many lines of one patch, with what depends on the patch alone (the
// split of a quad into its triangles, the basis about the normal) computed
// once: the same points and directions.
class PatchSampler {
 public:
  PatchSampler(const PatchMesh& mesh, const Patch& patch, const Vec3& normal);
  Vec3 point(double u1, double u2) const;
  Vec3 direction(double u1, double u2) const { return cosine_direction(t_, b_, n_, u1, u2); }
  const Vec3& normal() const { return n_; }

 private:
  Vec3 v_[4];
  bool triangle_;
  double split_ = 1;  // the share of a quad's area in its first triangle
  Vec3 n_, t_, b_;
};

// A segment of a uniformly distributed line through a box: starts a hair
// outside the box and ends a hair past the far side.
struct GlobalLine {
  Vec3 org;
  Vec3 dir;
  double length;
};

class BoxLineSampler {
 public:
  explicit BoxLineSampler(const Bounds& box);
  GlobalLine sample(Rng& rng) const;
  // The line of a point of [0,1)^4: u[0] picks the face and one coordinate on
  // it, u[1] the other, u[2] and u[3] the cosine-distributed direction.
  GlobalLine sample(const double u[4]) const;
  const Bounds& box() const { return box_; }
  double surface_area() const { return box_.surface_area(); }

 private:
  Bounds box_;
  double face_cdf_[6];
  Vec3 tangent_[6], bitangent_[6];  // the orthonormal_basis of each face's inward normal
  double hair_;
};

double radical_inverse(uint64_t index, unsigned base);
// Point `index` of the Halton sequence in bases 2, 3, 5 and 7, each
// coordinate shifted by shift[k] modulo 1 (a Cranley-Patterson rotation).
void shifted_halton(uint64_t index, const double shift[4], double u[4]);

// The Halton points of shifted_halton with a shift of four numbers drawn from
// `rng`: each point is uniform in [0, 1)^4, and the points of one shift
// cover it evenly.
class ShiftedHalton {
 public:
  explicit ShiftedHalton(Rng rng);
  void point(uint64_t index, double u[4]) const { shifted_halton(index, shift_, u); }

 private:
  double shift_[4];
};

// Where the 4D points of a set of global lines come from: independent random
// numbers, or a randomised Halton sequence (bases 2, 3, 5, 7, shifted modulo 1
// by a random vector per pass: Cranley-Patterson rotation), whose lines cover
// the box more evenly, so faces get crossing counts closer to their expectation.
class LineSequence {
 public:
  LineSequence(const std::string& kind, unsigned long long seed, unsigned pass);
  void point(uint64_t index, Rng& rng, double u[4]) const;

 private:
  bool halton_ = false;
  ShiftedHalton points_;
};

// A pseudo-random bijection of [0, n), computed index by index in constant
// memory: a four-round Feistel network on the smallest power of two at
// least n (each round adds to one half of the bits a mix of the other half
// and a key drawn from `rng`), walked again from its own output until it
// lands below n (fewer than two walks on average). Passes take randomised
// Halton lines in such an order, and stores hold them so: consecutive
// indices of the sequence are tied to one another, and power a face gathers
// during a pass leaves on the next line crossing it (docs/algorithm.md,
// "Order of lines in a pass").
class IndexPermutation {
 public:
  IndexPermutation(uint64_t n, Rng& rng);
  uint64_t operator()(uint64_t i) const {
    do i = round_trip(i);
    while (i >= n_);
    return i;
  }

 private:
  uint64_t round_trip(uint64_t x) const;
  uint64_t n_;
  unsigned low_bits_ = 0, high_bits_ = 0;
  uint64_t keys_[4] = {};
};

}  // namespace mpath
