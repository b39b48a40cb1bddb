#include "transport.h"

#include <algorithm>

namespace mpath {

PassInputs PassInputs::start(RadiosityState& state, const PatchMesh& mesh, const std::vector<double>& crossings) {
  PassInputs in;
  in.mesh = &mesh;
  in.channels = state.channels;
  in.faces.resize(state.faces);
  for (size_t f = 0; f < state.faces; ++f) {
    FaceInput& face = in.faces[f];
    for (int c = 0; c < state.channels; ++c) {
      face.quota[c] = state.unshot[state.at(f, c)];
      face.rho[c] = state.rho[state.at(f, c)];
      state.unshot[state.at(f, c)] = 0;
    }
    face.share = crossings[f] > 0 ? 1.0 / crossings[f] : 0.0;
  }
  return in;
}

void ShardAccumulator::reset(size_t face_count) {
  faces.assign(face_count, FaceAccumulator{});
  absorbed = {};
  escaped = {};
  lines = hits = 0;
}

void sum_totals_over_ranks(std::array<double, 3>& absorbed, std::array<double, 3>& escaped, uint64_t& lines,
                           uint64_t& hits) {
  Ranks::sum(absorbed.data(), absorbed.size());
  Ranks::sum(escaped.data(), escaped.size());
  uint64_t counts[2] = {lines, hits};
  Ranks::sum(counts, 2);
  lines = counts[0];
  hits = counts[1];
}

void ShardAccumulator::sum_over_ranks() {
  Ranks::sum_records(faces);
  sum_totals_over_ranks(absorbed, escaped, lines, hits);
}

void receive(const RadiosityState& s, int face, const double* power, ShardAccumulator& acc) {
  const int ch = s.channels;
  if (face < 0) {
    for (int c = 0; c < ch; ++c) acc.absorbed[c] += power[c];
    return;
  }
  FaceAccumulator& a = acc.faces[face];
  for (int c = 0; c < ch; ++c) {
    const double kept = s.rho[s.at(face, c)] * power[c];
    a.phi_gain[c] += kept;
    a.gathered[c] += kept;
    acc.absorbed[c] += power[c] - kept;
  }
}

void receive_in_contact(const RadiosityState& s, int from, int to, const double* power, ShardAccumulator& acc) {
  const int ch = s.channels;
  for (int c = 0; c < ch; ++c) acc.absorbed[c] += power[c];
  if (to < 0) return;
  for (int c = 0; c < ch; ++c) {
    const double rho_from = s.rho[s.at(from, c)], rho_to = s.rho[s.at(to, c)];
    // Reflectances of 1 on both sides would hold the power for ever: a
    // reflectance a hair below 1 keeps the sums finite.
    const double loss = std::max(1.0 - rho_from * rho_to, 1e-9);
    acc.faces[to].phi_gain[c] += rho_to * power[c] / loss;
    acc.faces[from].phi_gain[c] += rho_from * rho_to * power[c] / loss;
  }
}

void transport_line(const PassInputs& in, const std::vector<LineHit>& hits, ShardAccumulator& acc) {
  const PatchMesh& mesh = *in.mesh;
  const int ch = in.channels;
  const size_t n = hits.size();
  ++acc.lines;
  acc.hits += n;
  if (n == 0) return;

  using Send = ShardAccumulator::Send;
  std::vector<Send>& sends = acc.sends;
  sends.clear();

  const auto towards = [&](int j, int d) {
    const Facing f = facing(mesh, hits[j]);
    return d > 0 ? f.forward : f.backward;
  };
  auto send_from = [&](int face, int i, int dir) {
    if (face < 0) return;
    Send out{i + dir, dir > 0, {0, 0, 0}};
    if (mesh.may_touch(hits[i].patch)) {
      const int j = next_seen(i, dir, static_cast<int>(n), towards);
      if (j >= 0 && j < static_cast<int>(n) && mesh.touching(hits[i].patch, hits[j].patch)) {
        face_keep(in.faces[face], acc.faces[face], acc.allowance, ch);
        return;
      }
    }
    face_send(in.faces[face], acc.faces[face], acc.allowance, ch, out.power);
    bool any = false;
    for (int c = 0; c < ch; ++c) any |= out.power[c] != 0;
    if (any) sends.push_back(out);
  };

  for (size_t i = 0; i < n; ++i) {
    const Facing f = facing(mesh, hits[i]);
    send_from(f.forward, static_cast<int>(i), +1);
    send_from(f.backward, static_cast<int>(i), -1);
  }
  for (const Send& out : sends) {
    // The first crossing on its way that does not let it through.
    int face = kInvisibleSide;
    int j = out.to_hit;
    for (; j >= 0 && j < static_cast<int>(n); j += out.forward ? 1 : -1) {
      const Facing f = facing(mesh, hits[j]);
      face = out.forward ? f.backward : f.forward;
      if (face != kInvisibleSide) break;
    }
    if (j < 0 || j >= static_cast<int>(n)) {
      for (int c = 0; c < ch; ++c) acc.escaped[c] += out.power[c];
      continue;
    }
    if (face < 0) {
      for (int c = 0; c < ch; ++c) acc.absorbed[c] += out.power[c];
      continue;
    }
    face_receive(in.faces[face], acc.faces[face], out.power, ch, acc.absorbed.data());
  }
}

namespace {

// Adds gathered power and Phi gains of every shard, and the energy terms.
void merge_gains(const std::vector<ShardAccumulator>& acc, RadiosityState& state) {
  const int ch = state.channels;
  for_each_record(state.faces, [&](size_t f) {
    for (const ShardAccumulator& a : acc) add_face_gains(a.faces[f], f, state);
  });
  for (const ShardAccumulator& a : acc)
    for (int c = 0; c < ch; ++c) {
      state.energy.absorbed[c] += a.absorbed[c];
      state.energy.escaped[c] += a.escaped[c];
    }
}

}  // namespace

void merge_pass(const PassInputs& in, const std::vector<ShardAccumulator>& acc, RadiosityState& state) {
  for_each_record(state.faces, [&](size_t f) {
    double unsent = 1.0;  // fraction of the quota no line took
    for (const ShardAccumulator& a : acc) unsent -= a.faces[f].quota_used;
    for (int c = 0; c < state.channels; ++c) state.unshot[state.at(f, c)] = in.faces[f].quota[c] * unsent;
  });
  merge_gains(acc, state);
}

std::vector<int> faces_no_line_crossed(const PassInputs& in, const std::vector<ShardAccumulator>& acc) {
  std::vector<int> faces;
  for (size_t f = 0; f < in.faces.size(); ++f) {
    bool held = false;
    for (int c = 0; c < in.channels; ++c) held |= in.faces[f].quota[c] > 0;
    if (!held) continue;
    bool crossed = false;
    for (const ShardAccumulator& a : acc) crossed |= a.faces[f].quota_used > 0;
    if (!crossed) faces.push_back(static_cast<int>(f));
  }
  return faces;
}

PassStats finish_pass(const PassInputs& in, const std::vector<ShardAccumulator>& acc, RadiosityState& state,
                      unsigned pass, std::chrono::steady_clock::time_point start) {
  merge_pass(in, acc, state);
  PassStats stats;
  stats.pass = static_cast<int>(pass);
  for (const ShardAccumulator& a : acc) {
    stats.lines += a.lines;
    stats.hits += a.hits;
  }
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats.unshot_fraction = state.remaining_fraction();
  return stats;
}

void merge_received(const std::vector<ShardAccumulator>& acc, RadiosityState& state) { merge_gains(acc, state); }

}  // namespace mpath
