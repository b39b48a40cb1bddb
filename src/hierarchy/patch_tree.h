#pragma once
// A bounding-volume tree over some patches of a mesh (those of one large
// object, in the hierarchy build), for questions about the patches near a
// box that would otherwise look at every patch.

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

#include "mesh.h"

namespace mpath {

// The patches of one large object in a bounding-volume tree, so that
// whether a box holds any of them costs the nodes near the box rather than
// every patch: a whole building read as one object is split into connected
// parts, and a storey's walls, floors and ceilings that share corners are
// one part of thousands of patches, which every group formed inside its
// bounds asked about (half of such a scene's build, in triangle tests).
class PatchTree {
 public:
  PatchTree(const PatchMesh& mesh, const std::vector<uint32_t>& patches) : patches_(patches) {
    bounds_.resize(patches_.size());
    for (size_t k = 0; k < patches_.size(); ++k)
      for (uint32_t v : mesh.patches[patches_[k]].v) bounds_[k].extend(mesh.vertices[v]);
    std::vector<uint32_t> order(patches_.size());
    std::iota(order.begin(), order.end(), 0u);
    nodes_.resize(1);
    build(order, 0, order.size(), 0);
    std::vector<uint32_t> sorted(order.size());
    std::vector<Bounds> sorted_bounds(order.size());
    for (size_t k = 0; k < order.size(); ++k) {
      sorted[k] = patches_[order[k]];
      sorted_bounds[k] = bounds_[order[k]];
    }
    patches_ = std::move(sorted);
    bounds_ = std::move(sorted_bounds);
  }

  // Whether f(patch) holds for some patch whose bounds do not lie clear of
  // `box` along an axis (bounds at most touching a side of it are clear,
  // as in the first test of triangle_meets_box); f is asked about no other
  // patch, so any_near(box, f) is any patch p with f(p) wherever f(p)
  // implies that p's bounds are not clear of box.
  template <typename F>
  bool any_near(const Bounds& box, const F& f) const {
    if (patches_.empty()) return false;
    auto clear = [&](const Bounds& b) {
      for (int i = 0; i < 3; ++i)
        if (b.hi[i] <= box.lo[i] || b.lo[i] >= box.hi[i]) return true;
      return false;
    };
    uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (clear(n.bounds)) continue;
      if (n.count > 0) {
        for (uint32_t k = n.first; k < n.first + n.count; ++k)
          if (!clear(bounds_[k]) && f(patches_[k])) return true;
        continue;
      }
      stack[top++] = n.first;
      stack[top++] = n.first + 1;
    }
    return false;
  }

 private:
  static constexpr size_t kLeaf = 8;
  struct Node {
    Bounds bounds;
    uint32_t first = 0;  // a leaf's first entry, or the first of two children
    uint32_t count = 0;  // entries of a leaf; 0: an inner node
  };

  // Fills node `slot` over order[lo, hi): a leaf of up to kLeaf entries, or
  // split at the median of the widest axis of the entries' centres into two
  // children side by side (depth at most log2 of the patches: the stack of
  // 64 holds it; every leaf holds at least one entry).
  void build(std::vector<uint32_t>& order, size_t lo, size_t hi, uint32_t slot) {
    Bounds b, centres;
    for (size_t k = lo; k < hi; ++k) {
      b.extend(bounds_[order[k]].lo);
      b.extend(bounds_[order[k]].hi);
      centres.extend(bounds_[order[k]].center());
    }
    nodes_[slot].bounds = b;
    if (hi - lo <= kLeaf) {
      nodes_[slot].first = static_cast<uint32_t>(lo);
      nodes_[slot].count = static_cast<uint32_t>(hi - lo);
      return;
    }
    const Vec3 s = centres.size();
    const int axis = s.x >= s.y && s.x >= s.z ? 0 : (s.y >= s.z ? 1 : 2);
    const size_t mid = lo + (hi - lo) / 2;
    std::nth_element(order.begin() + lo, order.begin() + mid, order.begin() + hi, [&](uint32_t x, uint32_t y) {
      return bounds_[x].center()[axis] < bounds_[y].center()[axis];
    });
    const uint32_t left = static_cast<uint32_t>(nodes_.size());
    nodes_.resize(nodes_.size() + 2);
    nodes_[slot].first = left;
    nodes_[slot].count = 0;
    build(order, lo, mid, left);
    build(order, mid, hi, left + 1);
  }

  std::vector<uint32_t> patches_;
  std::vector<Bounds> bounds_;  // per entry
  std::vector<Node> nodes_;
};

}  // namespace mpath
