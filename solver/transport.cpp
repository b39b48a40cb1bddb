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
