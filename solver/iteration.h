// The iteration driver every solver method runs: passes until the power left
// to distribute falls below solver.tolerance or solver.iterations passes.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "config.h"
#include "radiosity_state.h"
#include "transport.h"

namespace mpath {

struct IterationLog {
  std::vector<PassStats> passes;
  uint64_t lines = 0;
  uint64_t hits = 0;
  bool converged = false;
  double first_unshot = -1;  // unshot power before the first pass (W, summed over channels)
};

// Runs passes after those already in `log` until unshot / emitted <
// solver.tolerance or solver.iterations passes in all, calling `after_pass`
// after each (checkpoints).
using PassFunction = std::function<PassStats(unsigned pass)>;
void iterate(const Options& options, const RadiosityState& state, IterationLog& log, const PassFunction& run_pass,
             const std::function<void()>& after_pass = {});

}  // namespace mpath
