// Multipath transport along one line: the pass semantics of docs/method.md, 7
// on a sorted list of patch crossings. Shared by every solver method.
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include "radiosity_state.h"
#include "ranks.h"
#include "line_order.h"
#include "tracer.h"

namespace mpath {

// What a pass reads of a face but never writes, in one cache line: the
// unshot power it had at the start of the pass (its quota), the share of it
// that one crossing carries, and its reflectance.
struct alignas(64) FaceInput {
  double quota[3] = {0, 0, 0};
  double share = 0;  // 1 / (crossings in the pass)
  double rho[3] = {0, 0, 0};
};

struct PassInputs {
  const PatchMesh* mesh = nullptr;
  int channels = 3;
  std::vector<FaceInput> faces;

  // Moves the state's unshot power into the quotas (unshot becomes 0);
  // `crossings` per face (0: the face is never crossed and keeps its quota).
  static PassInputs start(RadiosityState& state, const PatchMesh& mesh, const std::vector<double>& crossings);
};

// What a shard accumulates for a face during a pass, in one cache line.
struct alignas(64) FaceAccumulator {
  double gathered[3] = {0, 0, 0};  // received this pass, not yet re-sent
  double phi_gain[3] = {0, 0, 0};
  double quota_used = 0;           // fraction of the quota sent
  double unused = 0;               // the cache line's rest: the whole is summed over ranks as 8 doubles
};
static_assert(sizeof(FaceAccumulator) == 8 * sizeof(double));

// A shard's private accumulators, merged into the state after the pass.
// Aligned to two cache lines (an adjacent-line prefetch pair) so that shards
// side by side in a vector never share one: their counters change with every
// line, and sharing cut two threads' throughput to below one thread's.
struct alignas(128) ShardAccumulator {
  std::vector<FaceAccumulator> faces;
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

  void reset(size_t face_count);
  // Sums the accumulators over the MPI ranks (ranks.h).
  void sum_over_ranks();
};

// Adds what face `f` gathered and its Phi gain in `a` to the state.
inline void add_face_gains(const FaceAccumulator& a, size_t f, RadiosityState& state) {
  for (int c = 0; c < state.channels; ++c) {
    state.unshot[state.at(f, c)] += a.gathered[c];
    state.phi[state.at(f, c)] += a.phi_gain[c];
  }
}

// Sums a shard's energy terms and line counts over the MPI ranks.
void sum_totals_over_ranks(std::array<double, 3>& absorbed, std::array<double, 3>& escaped, uint64_t& lines,
                           uint64_t& hits);

// Sums each shard's accumulators over the MPI ranks, where there are several:
// after it every rank holds what all of them made, shard by shard.
template <typename Shard>
void sum_shards_over_ranks(std::vector<Shard>& shards) {
  if (Ranks::size() > 1)
    for (Shard& s : shards) s.sum_over_ranks();
}

// Runs f(0) .. f(shards - 1) on the threads, in a task context of its own:
// when a sibling loop (another box of the same depth) fails, this one still
// runs to its end instead of being cancelled half done, so that no caller
// merges accumulators a cancelled shard never filled; the sibling's error
// then reaches the caller of the outer loop.
template <typename F>
void for_each_shard(int shards, const F& f) {
  tbb::task_group_context context(tbb::task_group_context::isolated);
  tbb::parallel_for(0, shards, f, context);
}

// f(i) for i in [0, n) on the threads, in blocks: the per-face loops around
// a pass (its inputs, the merge of its shards) each write only element i's
// own records, so that the result is the same on any number of threads. Run
// one after another they were the serial part of every pass (on OFFICE's
// root box 5-7 ms a pass to merge 8 shards of 86,662 faces, a tenth of an
// adaptive pass on two threads). In a task context of its own, as
// for_each_shard: a failing sibling box does not leave a merge half done.
template <typename F>
void for_each_record(size_t n, const F& f) {
  tbb::task_group_context context(tbb::task_group_context::isolated);
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, n, 4096),
      [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) f(i);
      },
      context);
}

// Runs a pass's shards, one per accumulator in `acc`: reset(s) for every
// shard, run(s) for this MPI rank's own (Ranks::owns), side by side on the
// threads; then every shard's accumulators are summed over the ranks, so
// that each rank merges exactly what one process would (ranks.h).
template <typename Shard, typename Reset, typename Run>
void run_shards(std::vector<Shard>& acc, const Reset& reset, const Run& run) {
  const int shards = static_cast<int>(acc.size());
  for_each_shard(shards, [&](int s) {
    reset(s);
    if (Ranks::owns(s, shards)) run(s);
  });
  sum_shards_over_ranks(acc);
}

// What face `input` / `a` sends along one crossing: its share of its quota
// (never more in all than `allowance` of it) plus what it gathered earlier
// in the pass, which is then cleared. Shared by every transport.
inline void face_send(const FaceInput& input, FaceAccumulator& a, double allowance, int ch, double* power) {
  double fraction = std::min(input.share, allowance - a.quota_used);
  if (fraction < 0) fraction = 0;
  a.quota_used += fraction;
  for (int c = 0; c < ch; ++c) {
    power[c] = input.quota[c] * fraction + a.gathered[c];
    a.gathered[c] = 0;
  }
}

// A crossing where the face touches the next surface (a frame's back on the
// wall): its share of the quota is taken as for a send, but the power stays
// with the face and leaves along its next crossing in the pass (or stays
// unshot): nothing passes between surfaces pressed together, and no power
// is lost or made (docs/scene-formats.md, "Surfaces in contact").
inline void face_keep(const FaceInput& input, FaceAccumulator& a, double allowance, int ch) {
  double power[3];
  face_send(input, a, allowance, ch, power);
  for (int c = 0; c < ch; ++c) a.gathered[c] = power[c];
}

// Power arriving at a face during a pass: rho of it is accumulated and
// gathered for sending on, the rest absorbed.
inline void face_receive(const FaceInput& input, FaceAccumulator& a, const double* power, int ch, double* absorbed) {
  for (int c = 0; c < ch; ++c) {
    const double kept = input.rho[c] * power[c];
    a.phi_gain[c] += kept;
    a.gathered[c] += kept;
    absorbed[c] += power[c] - kept;
  }
}

// Power arriving at `face` (-1: a black back side) outside a pass (the first
// shot): rho of it is kept as accumulated and unshot power, the rest absorbed.
void receive(const RadiosityState& state, int face, const double* power, ShardAccumulator& acc);

// Power that face `from` emits where it touches face `to` (-1: a black back
// side): the two see only each other, so it bounces between them until it
// is absorbed, all of it, in closed form. `to` keeps rho_to / (1 - rho_from
// rho_to) of it and `from` rho_from rho_to / (1 - rho_from rho_to), as
// radiosity that never leaves the contact (not unshot).
void receive_in_contact(const RadiosityState& state, int from, int to, const double* power, ShardAccumulator& acc);

// Adds a pass's shard accumulators to the state, in shard order; the share of
// each face's quota that no line took stays unshot.
void merge_pass(const PassInputs& in, const std::vector<ShardAccumulator>& acc, RadiosityState& state);

// The faces that held a quota that no line of the pass crossed (so none of it
// was taken), in face order: their power waits in place for a later pass.
std::vector<int> faces_no_line_crossed(const PassInputs& in, const std::vector<ShardAccumulator>& acc);

struct PassStats {
  int pass = 0;
  uint64_t lines = 0;
  uint64_t hits = 0;
  double seconds = 0;
  double unshot_fraction = 0;  // (unshot + held in ARs) / emitted after the pass
};

// merge_pass, then the pass's statistics (`start`: when the pass began).
PassStats finish_pass(const PassInputs& in, const std::vector<ShardAccumulator>& acc, RadiosityState& state,
                      unsigned pass, std::chrono::steady_clock::time_point start);
// The same for the first shot, which has no quotas.
void merge_received(const std::vector<ShardAccumulator>& acc, RadiosityState& state);

// One line in both directions: every face on it sends its per-line share of
// its quota plus what it gathered earlier in the pass; all sends are taken
// before any receive. Power leaving the ends of the line escapes.
void transport_line(const PassInputs& in, const std::vector<LineHit>& hits, ShardAccumulator& acc);

}  // namespace mpath
