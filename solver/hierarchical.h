// Hierarchical Multipath over the stored lines (docs/method.md, 7, paper
// figure 5): one iteration is MP(root); MP(S) is one pass over S's stored
// lines in which S's own faces, the ARs of S's walls (power that entered S)
// and the ARs of S's child boxes (power that left them) send, and power
// crossing a child box is split by the child's transmittance into what
// enters it (the child's In) and what goes on; then MP(B) for every child B.
// Boxes of one depth are independent and run in parallel, each box's lines in
// shards. With the root box alone this is stored-line Multipath.
#pragma once

#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <vector>

#include "box_store.h"
#include "progress.h"
#include "iteration.h"
#include "radiosity_state.h"
#include "ranks.h"
#include "tracer.h"
#include "transport.h"

namespace mpath {

// Sizes the state's AR arrays for the store's boxes (zero power).
void add_ar_state(const BoxStore& store, RadiosityState& state);

// Per box, what its passes of the last iteration did (for the report).
struct BoxPassStats {
  uint64_t lines = 0, hits = 0;
  double seconds = 0;
};

// The power a stored line carries in later iterations: 0 (every line of
// every box, every iteration) while solver.adaptive_lines is off or before
// the first iteration; else the first iteration's, so that each box's pass
// takes lines in proportion to the power it has to send, as classic
// Multipath casts fewer lines in later passes (docs/algorithm.md).
double line_power(const Options& options, const BoxStore& store, const IterationLog& log);

// Whether the next iteration should take every stored line, with adaptive
// lines: when, at the factors by which the last (partial) pass and the
// first (every line) took the power left down, full passes would bring it
// below `tolerance` for less work than partial ones, or partial ones would
// need more than `passes_left`. A partial pass moves a face's received
// power on only where the face has a later crossing among the lines it
// takes, so on scenes of many faces a few lines each (OFFICE at 2M lines)
// thin passes took the power down by 10-40 % each and ran into the
// iteration cap, where one full pass took it down tenfold.
bool full_pass_pays(const IterationLog& log, uint64_t store_lines, double emitted, size_t faces, double tolerance,
                    int passes_left);

// Where the power still to distribute is (W, summed over channels), and how
// much of it no stored line can carry (faces without a crossed proxy, ARs
// without a target): that part stays whatever the iterations do.
struct Remaining {
  double unshot = 0, in = 0, out = 0;
  double stuck_faces = 0, stuck_in = 0, stuck_out = 0;
  int deepest_box = 0;       // the box holding the most
  double deepest_power = 0;
};
Remaining remaining_power(const BoxStore& store, const RadiosityState& state);

// Power no stored line can carry (on faces without a crossed proxy: small
// patches in boxes with few lines) is shot with kUncarriedLines local lines
// per face (shoot_unshot), like the first shot, so that it moves on instead
// of waiting; returns the local lines cast. Run after each iteration.
uint64_t shoot_uncarried(const PatchMesh& mesh, const TracerOnDemand& tracer, const BoxStore& store,
                         RadiosityState& state, unsigned pass, unsigned long long seed, int shards_wanted);

// One iteration of mpath-solve's stored-line methods with the options'
// schedule and line power: hierarchical_iteration, then shoot_uncarried
// (its local lines added to `uncarried` when given).
PassStats stored_iteration(const Options& options, const PatchMesh& mesh, const TracerOnDemand& tracer,
                           const BoxStore& store, RadiosityState& state, const IterationLog& log, unsigned pass,
                           int shards_wanted, std::vector<BoxPassStats>* per_box = nullptr,
                           uint64_t* uncarried = nullptr);

// The order in which pass `pass` takes the n lines of chunk `chunk` of box
// `box` of a store traced with `seed` (lines.seed): a pseudo-random
// permutation, new every pass. Chunks are stored sorted by what their lines
// meet; power a face gathers leaves on the next line crossing it, and any
// order tied to the lines' geometry sends it along a line like the one it
// came by (docs/algorithm.md, "Order of lines in a pass"). The seed is in
// it because a chunk's k-th line meets nearly the same faces in every seed's
// store: with one order for all, every seed's pass met the faces in the
// same sequence, and the seeds shared an error their spread did not show.
void chunk_line_order(unsigned long long seed, unsigned pass, int box, uint64_t chunk, size_t n,
                      std::vector<uint32_t>& order);

// Runs f(0) .. f(boxes - 1), the passes of the boxes of one depth: side by
// side on the threads with one MPI rank; one after another with several,
// since every rank must sum the boxes' accumulators in the same order, from
// the thread that called main (ranks.h).
template <typename F>
void for_each_box(size_t boxes, const F& f) {
  if (Ranks::size() > 1) {
    for (size_t k = 0; k < boxes; ++k) f(k);
    return;
  }
  tbb::parallel_for(size_t{0}, boxes, f);
}

struct ChunkPart {
  uint64_t chunk;
  uint64_t lines;
};

// The lines a pass over `fraction` of box b's lines takes: a run of whole
// chunks from a place that moves from pass to pass, and the first lines of
// the last. Every line when `fraction` is 1.
std::vector<ChunkPart> pass_parts(const BoxStore& store, int b, double fraction, unsigned pass);

// A box pass's shards: one per chunk it reads, at most `shards_wanted`
// (solver.shards), at least one.
inline int pass_shards(int shards_wanted, size_t chunks) {
  return static_cast<int>(std::max<size_t>(1, std::min<size_t>(static_cast<size_t>(shards_wanted), chunks)));
}

// Lines in parts [lo, hi).
inline uint64_t part_lines(const std::vector<ChunkPart>& parts, uint64_t lo, uint64_t hi) {
  uint64_t n = 0;
  for (uint64_t i = lo; i < hi; ++i) n += parts[i].lines;
  return n;
}

// How many lines ahead of the one in transport stream_pass_lines announces
// (`ahead(lines, k', d)`, d from kLinesAhead down to 1), so that a transport
// can bring the memory a line will touch into the caches in stages while
// earlier lines run: a pass reads per-face records chosen at random among a
// box's faces, and waiting for each of them in turn was most of its time.
inline constexpr size_t kLinesAhead = 4;

// One shard's lines of a pass over box b: for each part in [lo, hi) the
// part's lines are taken in the pass's random order (chunk_line_order; an
// adaptive pass takes the first of them, a random subset of the chunk), its
// chunk read and decoded straight into that order (BoxStore::read_lines:
// a pass then reads its lines' events one after another in memory) and
// checked (`check(lines, c)`, which throws on a damaged one, and may
// rewrite the events' fields for the transport: the lines are the thread's
// own copy), and the lines
// run: `line(lines, k)` for k = 0, 1, ..., after `ahead(lines, k + d, d)`
// for the lines d = 1 .. kLinesAhead places after it. (Taking the chunk's
// first lines instead, and decoding only them, raised the furnace error at
// rho 0.99 by a fifth: every thin pass then met the same lines.)
// `sides`: the box's patch sides for the decoder to write into the events
// (linestore::EventSides), or none.
template <typename Check, typename Line, typename Ahead>
void stream_pass_lines(const BoxStore& store, int b, const std::vector<ChunkPart>& parts, uint64_t lo, uint64_t hi,
                       unsigned pass, Progress& progress, const linestore::EventSides* sides, const Check& check,
                       const Line& line, const Ahead& ahead) {
  // The lines and order per thread, kept from pass to pass: their buffers
  // are megabytes, and allocating them afresh for every box of every pass
  // cost page faults.
  thread_local linestore::DecodedChunk lines;
  thread_local std::vector<uint32_t> order;
  for (uint64_t i = lo; i < hi; ++i) {
    const uint64_t c = parts[i].chunk;
    const size_t n = store.chunk_lines(b, c);
    const size_t take = std::min<size_t>(n, parts[i].lines);
    chunk_line_order(store.seed(), pass, b, c, n, order);
    store.read_lines(b, c, order.data(), take, lines, sides);
    check(lines, c);
    for (size_t k = 0; k < take; ++k) {
      for (size_t d = kLinesAhead; d >= 1; --d)
        if (k + d < take) ahead(lines, static_cast<uint32_t>(k + d), d);
      line(lines, static_cast<uint32_t>(k));
    }
    progress.advance(take);
  }
}

// One iteration: MP(root) and, depth by depth, MP of every box. Each box's
// pass takes every line of the box (exact crossing counts) when
// `power_per_line` is 0; otherwise as many as carry about that power each
// (at least the box's coverage): a run of chunks, counts scaled, each face
// and AR sending at most its quota and keeping what no line took.
// `v_cycle`: the subscenes also pass before the root, deepest first, so that
// power crosses every level up and down in one iteration (docs/algorithm.md).
PassStats hierarchical_iteration(const BoxStore& store, RadiosityState& state, unsigned pass, int shards_wanted,
                                 double power_per_line = 0.0, bool v_cycle = false,
                                 std::vector<BoxPassStats>* per_box = nullptr);

}  // namespace mpath
