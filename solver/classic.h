// Classic Multipath: after the first shot, passes of fresh uniform global
// lines over the scene box, traced on the fly; crossing counts are forecast
// (N lines cross a face of area A about N 2A/S times, S the box's area) and
// what a face was due to send but no line took stays unshot for the next
// pass; the power of a face that no line of the pass crossed at all is shot
// with local lines instead.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "config.h"
#include "radiosity_state.h"
#include "sampling.h"
#include "tracer.h"
#include "iteration.h"
#include "transport.h"

namespace mpath {

// Lines of classic pass k: lines.total x U_k / U_1, at least coverage_lines.
uint64_t classic_pass_lines(const Options& options, const PatchMesh& mesh, const IterationLog& log,
                            const RadiosityState& state);

// Forecast crossings of each face by N lines uniform over the scene box: N 2A/S.
std::vector<double> forecast_crossings(const PatchMesh& mesh, double lines);

// Lines that cross the median face about 16 times: the fewest a pass casts,
// so that what is left unshot keeps moving.
uint64_t coverage_lines(const PatchMesh& mesh);

// Runs passes until unshot / emitted < solver.tolerance or solver.iterations
// passes. Pass k casts lines.total * U_k / U_1 lines (at least
// coverage_lines), so lines follow the power left to distribute.
IterationLog solve_classic(const Options& options, const PatchMesh& mesh, const Tracer& tracer,
                           RadiosityState& state, int shards);

// The random stream of shard `shard`'s line order in classic pass `pass`.
Rng pass_order_rng(unsigned long long seed, unsigned pass, int shard);

// Calls f(i) for each line index i in lo..hi-1 in the order a classic pass's
// shard takes them: a pseudo-random permutation of the range
// (IndexPermutation, its keys from `order`, pass_order_rng). Power a face
// gathers during a pass leaves on the next line crossing it. Randomised
// Halton lines taken by index come in a pattern (consecutive indices
// alternate halves of the first coordinate, and so on), and even shuffled
// block by block the lines near one another in the sequence are spread
// evenly, so that the next line crossing a small face avoids the one the
// power came by: either way the answer is biased (docs/algorithm.md, "Order
// of lines in a pass"). Independent random lines are drawn in call order,
// so for them the order changes nothing.
template <typename F>
void for_each_pass_line(uint64_t lo, uint64_t hi, Rng& order, F&& f) {
  const IndexPermutation permutation(hi - lo, order);
  for (uint64_t k = lo; k < hi; ++k) f(lo + permutation(k - lo));
}

// One pass of `lines` fresh global lines, then the power on faces none of
// them crossed shot with local lines (shoot_unshot; their count added to
// `local_lines` when given); exposed for tests and benchmarks.
PassStats classic_pass(const PatchMesh& mesh, const Tracer& tracer, RadiosityState& state, uint64_t lines,
                       unsigned long long seed, unsigned pass, int shards,
                       const std::string& sequence = "random", uint64_t* local_lines = nullptr);

}  // namespace mpath
