// Checkpoints of a solve: the state after a finished iteration (the first
// shot, then every solver.checkpoint_seconds or so, and the last pass:
// run_iterations in solve.cpp), written atomically to
// output.dir/checkpoint.bin, so that `mpath-solve --resume` continues an
// interrupted run and gets the uninterrupted result.
#pragma once

#include <filesystem>
#include <string>

#include <spdlog/spdlog.h>

#include "iteration.h"
#include "config.h"
#include "radiosity_state.h"
#include "ranks.h"

namespace mpath {

// Everything a solve's state depends on, hashed: scene, mesh, method, lines,
// first shot, emitters, shards (not threads or ranks); not the iteration cap, tolerance or outputs.
// `geometry`: mesh_hash of the mesh (a solve on a store passes the store's
// own, which it has checked equal: hashing the mesh again took 10 ms of
// OFFICE's serial start).
std::string checkpoint_key(const Options& options, const std::string& geometry);

void write_checkpoint(const std::filesystem::path& path, const std::string& key, const RadiosityState& state,
                      const IterationLog& log);

// Loads a checkpoint into `state` and `log`; throws InputError naming the file
// when it is damaged or was made with other settings.
void read_checkpoint(const std::filesystem::path& path, const std::string& key, RadiosityState& state,
                     IterationLog& log);

// Where a solve's checkpoints go and the key they are written with.
struct Checkpoint {
  std::filesystem::path path;
  std::string key;
  // Rank 0 writes it; with several MPI ranks the others hold the same state.
  void save(const RadiosityState& state, const IterationLog& log) const {
    if (!Ranks::root()) return;
    write_checkpoint(path, key, state, log);
    spdlog::debug("checkpoint after {} pass(es) written to {}", log.passes.size(), path.string());
  }
};

}  // namespace mpath
