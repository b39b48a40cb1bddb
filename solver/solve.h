// mpath-solve as a library call: load, mesh, first shot, iterations, outputs.
#pragma once

#include <string>

#include "config.h"

namespace mpath {

struct SolveFlags {
  bool resume = false;
  bool dry_run = false;
  std::string command_line;
};

// Runs a whole solve; throws InputError on bad input.
void run_solve(const Options& options, const SolveFlags& flags);

}  // namespace mpath
