#include "transport.h"

#include <algorithm>

namespace mpath {

void ShardAccumulator::reset(size_t faces, int channels) {
  gathered.assign(faces * channels, 0.0);
  phi_gain.assign(faces * channels, 0.0);
  quota_used.assign(faces, 0.0);
  absorbed = {};
  escaped = {};
  lines = hits = 0;
}

void receive(const RadiosityState& s, int face, const double* power, ShardAccumulator& acc) {
  const int ch = s.channels;
  if (face < 0) {
    for (int c = 0; c < ch; ++c) acc.absorbed[c] += power[c];
    return;
  }
  const size_t base = static_cast<size_t>(face) * ch;
  for (int c = 0; c < ch; ++c) {
    const double kept = s.rho[base + c] * power[c];
    acc.phi_gain[base + c] += kept;
    acc.gathered[base + c] += kept;
    acc.absorbed[c] += power[c] - kept;
  }
}

namespace {

// Faces of a crossing: the one facing along the line and the one facing back.
struct Facing {
  int forward;
  int backward;
};

Facing facing(const PatchMesh& mesh, const LineHit& h) {
  const auto& f = mesh.patch_faces[h.patch];
  return h.along ? Facing{f[0], f[1]} : Facing{f[1], f[0]};
}

// Orders of one group of crossings at equal distance and what they cost.
struct GroupOrder {
  std::array<uint8_t, 5> perm{};  // offsets into the group
  bool first_back_live = false;   // the first crossing's face towards the line start
  bool last_forward_live = false; // the last crossing's face towards the line end
  int inner = 0;                  // live/black pairs inside the group
};

constexpr size_t kMaxTieGroup = 5;

std::vector<GroupOrder> group_orders(const PatchMesh& mesh, const std::vector<LineHit>& hits, size_t lo, size_t n) {
  std::array<uint8_t, 5> perm{};
  for (size_t k = 0; k < n; ++k) perm[k] = static_cast<uint8_t>(k);
  // Start from the order of patch indices so that ties between equal costs
  // resolve the same way whatever order Embree reported the hits in.
  std::sort(perm.begin(), perm.begin() + n, [&](uint8_t a, uint8_t b) { return hits[lo + a].patch < hits[lo + b].patch; });
  std::vector<GroupOrder> out;
  do {
    GroupOrder g;
    g.perm = perm;
    g.first_back_live = facing(mesh, hits[lo + perm[0]]).backward >= 0;
    g.last_forward_live = facing(mesh, hits[lo + perm[n - 1]]).forward >= 0;
    for (size_t k = 0; k + 1 < n; ++k)
      g.inner += (facing(mesh, hits[lo + perm[k]]).forward >= 0) != (facing(mesh, hits[lo + perm[k + 1]]).backward >= 0);
    out.push_back(g);
  } while (n > 1 && std::next_permutation(perm.begin(), perm.begin() + n, [&](uint8_t a, uint8_t b) {
    return hits[lo + a].patch < hits[lo + b].patch;
  }));
  return out;
}

}  // namespace

void order_ties(const PatchMesh& mesh, double epsilon, std::vector<LineHit>& hits) {
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

  // Dynamic programme over the groups; the state is whether the face that the
  // last crossing so far turns towards the line end is live. Beyond both ends
  // of the line is empty space, which counts as a black side.
  constexpr int kInf = 1 << 29;
  struct Cell {
    int cost = kInf;
    int order = -1;       // index into the group's orders
    int previous = 0;     // state before this group
  };
  std::vector<std::vector<GroupOrder>> orders(groups.size());
  std::vector<std::array<Cell, 2>> dp(groups.size());
  std::array<int, 2> before{0, kInf};
  for (size_t g = 0; g < groups.size(); ++g) {
    const auto [lo, n] = groups[g];
    if (n <= kMaxTieGroup) {
      orders[g] = group_orders(mesh, hits, lo, n);
    } else {  // too many to permute: keep the reported order
      GroupOrder keep;
      for (size_t k = 0; k < kMaxTieGroup; ++k) keep.perm[k] = static_cast<uint8_t>(k);
      keep.first_back_live = facing(mesh, hits[lo]).backward >= 0;
      keep.last_forward_live = facing(mesh, hits[lo + n - 1]).forward >= 0;
      orders[g] = {keep};
    }
    for (size_t o = 0; o < orders[g].size(); ++o) {
      const GroupOrder& go = orders[g][o];
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
      for (size_t k = 0; k < n; ++k) hits[lo + k] = scratch[orders[g][cell.order].perm[k]];
    }
    state = cell.previous;
  }
}

void transport_line(const PassInputs& in, const std::vector<LineHit>& hits, ShardAccumulator& acc) {
  const RadiosityState& s = *in.state;
  const PatchMesh& mesh = *in.mesh;
  const int ch = s.channels;
  const size_t n = hits.size();
  ++acc.lines;
  acc.hits += n;
  if (n == 0) return;

  using Send = ShardAccumulator::Send;
  std::vector<Send>& sends = acc.sends;
  sends.clear();

  auto send_from = [&](int face, int to_hit, bool forward) {
    if (face < 0) return;
    Send out{to_hit, forward, {0, 0, 0}};
    const size_t base = static_cast<size_t>(face) * ch;
    double fraction = std::min(in.share[face], acc.allowance - acc.quota_used[face]);
    if (fraction < 0) fraction = 0;
    acc.quota_used[face] += fraction;
    bool any = false;
    for (int c = 0; c < ch; ++c) {
      out.power[c] = in.quota[base + c] * fraction + acc.gathered[base + c];
      acc.gathered[base + c] = 0;
      any |= out.power[c] != 0;
    }
    if (any) sends.push_back(out);
  };

  for (size_t i = 0; i < n; ++i) {
    const Facing f = facing(mesh, hits[i]);
    send_from(f.forward, static_cast<int>(i) + 1, true);
    send_from(f.backward, static_cast<int>(i) - 1, false);
  }
  for (const Send& out : sends) {
    if (out.to_hit < 0 || out.to_hit >= static_cast<int>(n)) {
      for (int c = 0; c < ch; ++c) acc.escaped[c] += out.power[c];
      continue;
    }
    const Facing f = facing(mesh, hits[out.to_hit]);
    receive(s, out.forward ? f.backward : f.forward, out.power, acc);
  }
}

}  // namespace mpath
