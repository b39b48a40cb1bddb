// Multipath transport along one line: the pass semantics of design.md section 7
// on a sorted list of patch crossings. Shared by every solver method.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "radiosity_state.h"
#include "line_order.h"
#include "tracer.h"

namespace mpath {

// What a pass reads but never writes: the unshot power each face had at the
// start of the pass and the share of it that one crossing carries.
struct PassInputs {
  const RadiosityState* state = nullptr;
  const PatchMesh* mesh = nullptr;
  std::vector<double> quota;  // face * channels: U_f at pass start
  std::vector<double> share;  // face: 1 / (expected crossings in the pass)
};

// A shard's private accumulators, merged into the state after the pass.
struct ShardAccumulator {
  std::vector<double> gathered;   // face * channels: received this pass, not yet re-sent
  std::vector<double> phi_gain;   // face * channels
  std::vector<double> quota_used; // face: fraction of the quota sent
  double allowance = 1;           // fraction of each quota this shard may send
  std::array<double, 3> absorbed{}, escaped{};
  uint64_t lines = 0, hits = 0;

  // Scratch of transport_line: the sends of one line, taken before its receives.
  struct Send {
    int to_hit;    // -1 or the hit count: off the end of the line (escapes)
    bool forward;  // travelling along the line's direction
    double power[3];
  };
  std::vector<Send> sends;

  void reset(size_t faces, int channels);
};

// Power arriving at `face` (-1: a black back side): rho of it is kept as
// accumulated and unshot power, the rest absorbed.
void receive(const RadiosityState& state, int face, const double* power, ShardAccumulator& acc);

// One line in both directions: every face on it sends its per-line share of
// its quota plus what it gathered earlier in the pass; all sends are taken
// before any receive. Power leaving the ends of the line escapes.
void transport_line(const PassInputs& in, const std::vector<LineHit>& hits, ShardAccumulator& acc);

}  // namespace mpath
