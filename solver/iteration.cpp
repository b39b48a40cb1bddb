#include "iteration.h"

#include <spdlog/spdlog.h>

#include <string>

namespace mpath {

void iterate(const Options& options, const RadiosityState& state, IterationLog& log, const PassFunction& run_pass,
             const std::function<void()>& after_pass) {
  const double emitted = state.emitted_total();
  if (log.first_unshot < 0) log.first_unshot = state.unshot_total();
  for (unsigned pass = static_cast<unsigned>(log.passes.size()) + 1; pass <= static_cast<unsigned>(options.solver.iterations);
       ++pass) {
    if (!(emitted > 0) || state.remaining_fraction() < options.solver.tolerance) break;
    const PassStats p = run_pass(pass);
    spdlog::info("pass {}: {} lines, {} hits, {:.2f} s, unshot {:.3e} of emitted{}", p.pass, p.lines, p.hits, p.seconds,
                 p.unshot_fraction,
                 state.ar_in.empty() ? std::string() : fmt::format(" (held in ARs {:.3e})", state.held_total() / emitted));
    log.passes.push_back(p);
    log.lines += p.lines;
    log.hits += p.hits;
    if (after_pass) after_pass();
  }
  log.converged = !(emitted > 0) || state.remaining_fraction() < options.solver.tolerance;
}

}  // namespace mpath
