#include "line_order.h"

#include <algorithm>
#include <array>

namespace mpath {
namespace {

// Orders of one group of crossings at equal distance and what they cost.
struct GroupOrder {
  std::array<uint8_t, 5> perm{};  // offsets into the group
  bool first_back_live = false;   // the first crossing's face towards the line start
  bool last_forward_live = false; // the last crossing's face towards the line end
  int inner = 0;                  // live/black pairs inside the group
};

constexpr size_t kMaxTieGroup = 5;

// Whether a crossing's faces are live, looked up once per crossing: bit 0 the
// face towards the line end, bit 1 the one towards its start.
constexpr uint8_t kForwardLive = 1, kBackwardLive = 2;

uint8_t live_sides(const PatchMesh& mesh, const uint8_t* live_faces, const LineHit& h) {
  const uint8_t faces = live_faces ? live_faces[h.traced >= 0 ? h.traced : h.patch] : mesh.live_face_bits(h.patch);
  // Along the line face 0 turns towards its end, against it face 1.
  return h.along ? faces : static_cast<uint8_t>(((faces & 1) << 1) | (faces >> 1));
}

// Appends the orders of the group of n crossings from lo to `out`.
void group_orders(const std::vector<LineHit>& hits, const uint8_t* live, size_t lo, size_t n,
                  std::vector<GroupOrder>& out) {
  // Each order is written in its place in `out`: one built aside and copied
  // in was read back as whole words just after its bytes were stored, which
  // the core cannot forward (a stall of some 20 cycles per group).
  if (n == 1) {
    GroupOrder& g = out.emplace_back();
    g.first_back_live = live[lo] & kBackwardLive;
    g.last_forward_live = live[lo] & kForwardLive;
    return;
  }
  std::array<uint8_t, 5> perm{};
  for (size_t k = 0; k < n; ++k) perm[k] = static_cast<uint8_t>(k);
  // Start from the order of patch indices so that ties between equal costs
  // resolve the same way whatever order Embree reported the hits in.
  const auto by_patch = [&](uint8_t a, uint8_t b) { return hits[lo + a].patch < hits[lo + b].patch; };
  std::sort(perm.begin(), perm.begin() + n, by_patch);
  do {
    GroupOrder& g = out.emplace_back();
    g.perm = perm;
    g.first_back_live = live[lo + perm[0]] & kBackwardLive;
    g.last_forward_live = live[lo + perm[n - 1]] & kForwardLive;
    for (size_t k = 0; k + 1 < n; ++k)
      g.inner += static_cast<bool>(live[lo + perm[k]] & kForwardLive) != static_cast<bool>(live[lo + perm[k + 1]] & kBackwardLive);
  } while (std::next_permutation(perm.begin(), perm.begin() + n, by_patch));
}

}  // namespace

void order_ties(const PatchMesh& mesh, double epsilon, std::vector<LineHit>& hits, const uint8_t* live_faces) {
  // Groups of crossings within epsilon of the group's first one.
  thread_local std::vector<std::pair<size_t, size_t>> groups;  // (start, size)
  groups.clear();
  bool any_tie = false;
  for (size_t i = 0; i < hits.size();) {
    size_t j = i + 1;
    while (j < hits.size() && hits[j].t - hits[i].t <= epsilon) ++j;
    groups.push_back({i, j - i});
    any_tie |= j - i > 1;
    i = j;
  }
  if (!any_tie) return;
  // Every crossing's faces once: the costs below look at each many times.
  thread_local std::vector<uint8_t> live;
  live.resize(hits.size());
  for (size_t i = 0; i < hits.size(); ++i) live[i] = live_sides(mesh, live_faces, hits[i]);

  // Dynamic programme over the groups; the state is whether the face that the
  // last crossing so far turns towards the line end is live. Beyond both ends
  // of the line is empty space, which counts as a black side.
  constexpr int kInf = 1 << 29;
  struct Cell {
    int cost = kInf;
    int order = -1;       // index into `orders`
    int previous = 0;     // state before this group
  };
  // Every group's orders in one list (each group's after the one before),
  // kept with the table from line to line: allocating them afresh for every line with a
  // tie was a tenth of the preprocess's time, in malloc.
  thread_local std::vector<GroupOrder> orders;
  thread_local std::vector<std::array<Cell, 2>> dp;
  orders.clear();
  dp.assign(groups.size(), {});
  std::array<int, 2> before{0, kInf};
  for (size_t g = 0; g < groups.size(); ++g) {
    const auto [lo, n] = groups[g];
    const size_t first = orders.size();
    if (n <= kMaxTieGroup) {
      group_orders(hits, live.data(), lo, n, orders);
    } else {  // too many to permute: keep the reported order
      GroupOrder keep;
      for (size_t k = 0; k < kMaxTieGroup; ++k) keep.perm[k] = static_cast<uint8_t>(k);
      keep.first_back_live = live[lo] & kBackwardLive;
      keep.last_forward_live = live[lo + n - 1] & kForwardLive;
      orders.push_back(keep);
    }
    for (size_t o = first; o < orders.size(); ++o) {
      const GroupOrder& go = orders[o];
      for (int s = 0; s < 2; ++s) {
        if (before[s] >= kInf) continue;
        const int cost = before[s] + (s != static_cast<int>(go.first_back_live)) + go.inner;
        Cell& cell = dp[g][go.last_forward_live];
        if (cost < cell.cost) cell = {cost, static_cast<int>(o), s};
      }
    }
    before = {dp[g][0].cost, dp[g][1].cost};
  }
  int state = before[0] <= before[1] + 1 ? 0 : 1;
  thread_local std::vector<LineHit> scratch;
  for (size_t g = groups.size(); g-- > 0;) {
    const Cell& cell = dp[g][state];
    const auto [lo, n] = groups[g];
    if (n > 1 && n <= kMaxTieGroup) {
      scratch.assign(hits.begin() + lo, hits.begin() + lo + n);
      for (size_t k = 0; k < n; ++k) hits[lo + k] = scratch[orders[static_cast<size_t>(cell.order)].perm[k]];
    }
    state = cell.previous;
  }
}

}  // namespace mpath
