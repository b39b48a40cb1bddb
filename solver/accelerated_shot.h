// The first shot accelerated with associated patches (paper 3.4,
// first_shot.accelerate): a local line is followed box by box; when it enters
// a subscene through an AR, it is tested against that AR's associated patches
// (those the box's own lines met first most often entering there) before the
// subscene's interior, which is searched only when it misses all of them.
// The first associated patch hit is taken as the nearest: the acceleration
// is an approximation (docs/algorithm.md measures its time and error).
#pragma once

#include <array>
#include <atomic>
#include <memory>
#include <vector>

#include "box_store.h"
#include "tracer.h"

namespace mpath {

class SubsceneNearest {
 public:
  SubsceneNearest(const PatchMesh& mesh, const BoxStore& store);
  // Nearest patch met by the line leaving patch `from` at `org` along `dir`.
  NearestHit nearest_from(int from, const Vec3& org, const Vec3& dir) const;
  uint64_t shortcuts() const { return shortcuts_; }  // lines ended on an associated patch

 private:
  double hit_patch(int patch, const Vec3& org, const Vec3& dir) const;  // distance, or infinity

  const PatchMesh& mesh_;
  const Hierarchy& hierarchy_;
  std::vector<std::unique_ptr<Tracer>> tracers_;              // per box: its own patches
  std::vector<std::vector<std::array<int, 4>>> associated_;   // per box, per wall AR: mesh patches (-1: none)
  mutable std::atomic<uint64_t> shortcuts_{0};
};

}  // namespace mpath
