// The nearest of a fixed set of points to a query point, for sets that
// spread along a plane or a line (the centres of one polygon's patches).
#pragma once

#include <algorithm>
#include <compare>
#include <cmath>
#include <utility>
#include <vector>

#include "vec3.h"

namespace mpath {

// The points are sorted along the axis where they spread most; a query
// walks out both ways from its own place on that axis and stops on a side
// once the gap along the axis alone is more than the best distance found
// (a point's squared distance is never less than its squared gap on one
// axis, in floating point too: the sum of non-negative terms rounds to no
// less than any of them). On a polygon's patches that visits about the
// square root of them instead of all.
//
// The answer is exactly a linear scan's: of the points `accept` takes, the
// first in the set's own order among those at the least squared distance
// dot(p - q, p - q); -1 where it takes none (or every distance is NaN).
class NearestPoint {
 public:
  explicit NearestPoint(std::vector<Vec3> points) : points_(std::move(points)) {
    Bounds b;
    for (const Vec3& p : points_) b.extend(p);
    double widest = -1;
    for (int a = 0; a < 3; ++a)
      if (b.hi[a] - b.lo[a] > widest) {
        widest = b.hi[a] - b.lo[a];
        axis_ = a;
      }
    sorted_.reserve(points_.size());
    for (size_t i = 0; i < points_.size(); ++i) sorted_.emplace_back(points_[i][axis_], static_cast<int>(i));
    // A total order (NaN coordinates sort to the ends, where the walk, whose
    // stopping test is false on NaN, passes them without stopping).
    std::sort(sorted_.begin(), sorted_.end(), [](const Key& a, const Key& b) {
      const auto o = std::strong_order(a.first, b.first);
      return o != 0 ? o < 0 : a.second < b.second;
    });
  }

  size_t size() const { return points_.size(); }

  template <typename Accept>
  int nearest(const Vec3& q, const Accept& accept) const {
    const double at = q[axis_];
    const auto split = std::lower_bound(sorted_.begin(), sorted_.end(), at, [](const Key& k, double v) {
      return std::strong_order(k.first, v) < 0;
    });
    double best = INFINITY;
    int found = -1;
    const auto consider = [&](int i) {
      if (!accept(i)) return;
      const Vec3 d = points_[static_cast<size_t>(i)] - q;
      const double d2 = dot(d, d);
      if (d2 < best || (d2 == best && i < found)) {
        best = d2;
        found = i;
      }
    };
    const auto beyond = [&](double coordinate) {
      const double gap = coordinate - at;
      return gap * gap > best;
    };
    auto up = split;
    auto down = split;
    bool up_open = up != sorted_.end(), down_open = down != sorted_.begin();
    while (up_open || down_open) {
      if (up_open) {
        if (beyond(up->first)) {
          up_open = false;
        } else {
          consider(up->second);
          up_open = ++up != sorted_.end();
        }
      }
      if (down_open) {
        if (beyond(std::prev(down)->first)) {
          down_open = false;
        } else {
          --down;
          consider(down->second);
          down_open = down != sorted_.begin();
        }
      }
    }
    return found;
  }

 private:
  using Key = std::pair<double, int>;
  std::vector<Vec3> points_;
  int axis_ = 0;
  std::vector<Key> sorted_;  // (coordinate on the axis, index)
};

}  // namespace mpath
