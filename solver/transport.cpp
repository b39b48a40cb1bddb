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

// Live/black mismatches between neighbours in hits[lo..hi] and their outside neighbours.
int mismatches(const PatchMesh& mesh, const std::vector<LineHit>& hits, size_t lo, size_t hi) {
  int count = 0;
  const size_t from = lo > 0 ? lo - 1 : lo;
  const size_t to = std::min(hi + 1, hits.size() - 1);
  for (size_t i = from; i < to; ++i) {
    const bool a = facing(mesh, hits[i]).forward >= 0;
    const bool b = facing(mesh, hits[i + 1]).backward >= 0;
    count += a != b;
  }
  return count;
}

}  // namespace

void order_ties(const PatchMesh& mesh, double epsilon, std::vector<LineHit>& hits) {
  size_t i = 0;
  while (i + 1 < hits.size()) {
    size_t j = i;
    while (j + 1 < hits.size() && hits[j + 1].t - hits[i].t <= epsilon) ++j;
    const size_t n = j - i + 1;
    if (n >= 2 && n <= 5) {
      std::vector<LineHit> best(hits.begin() + i, hits.begin() + j + 1);
      std::sort(best.begin(), best.end(), [](const LineHit& a, const LineHit& b) { return a.patch < b.patch; });
      std::copy(best.begin(), best.end(), hits.begin() + i);
      int best_cost = mismatches(mesh, hits, i, j);
      std::vector<LineHit> perm = best;
      while (best_cost > 0 && std::next_permutation(perm.begin(), perm.end(),
                                                    [](const LineHit& a, const LineHit& b) { return a.patch < b.patch; })) {
        std::copy(perm.begin(), perm.end(), hits.begin() + i);
        const int cost = mismatches(mesh, hits, i, j);
        if (cost < best_cost) {
          best_cost = cost;
          best = perm;
        }
      }
      std::copy(best.begin(), best.end(), hits.begin() + i);
    }
    i = j + 1;
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
