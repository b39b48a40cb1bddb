// Runs a program's work on solver.threads threads.
#pragma once

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <cstddef>

namespace mpath {

// f() with `threads` threads for its parallel loops, as many as asked even
// above the cores: TBB's own arena has one per core and no more, so a run
// asking for more (to share a node's cores with others, or a test making
// its parts finish out of order) gets an arena of that many.
template <typename F>
auto run_on_threads(int threads, const F& f) {
  const tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism,
                                        static_cast<size_t>(threads));
  tbb::task_arena arena(threads);
  return arena.execute(f);
}

}  // namespace mpath
