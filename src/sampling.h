// Random numbers and the sampling of points, directions and global lines.
#pragma once

#include <pcg_random.hpp>

#include "mesh.h"

namespace mpath {

using Rng = pcg32;

// Independent stream for (seed, purpose, shard): same inputs, same numbers.
Rng make_rng(unsigned long long seed, unsigned purpose, unsigned long long shard);

inline double uniform(Rng& rng) { return std::ldexp(static_cast<double>(rng()), -32); }

// Cosine-distributed direction about unit normal n.
Vec3 cosine_direction(const Vec3& n, Rng& rng);

// Uniform point on a patch (a quad is split as Embree splits it).
Vec3 uniform_point(const PatchMesh& mesh, const Patch& patch, Rng& rng);

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
  const Bounds& box() const { return box_; }
  double surface_area() const { return box_.surface_area(); }

 private:
  Bounds box_;
  double face_cdf_[6];
  double hair_;
};

// Scene box enlarged so that no patch lies on its walls and flat scenes get volume.
Bounds line_box(const Bounds& scene_bounds);

}  // namespace mpath
