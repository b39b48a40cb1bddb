// mpath-preprocess as a library call: mesh the scene, trace the stored lines
// and write the store (manifest and box files) in store.dir.
#pragma once

#include <cstdint>
#include <string>

#include "config.h"

namespace mpath {

struct ShardSpec {
  int index = 1;  // 1-based
  int count = 1;
};

// Parses "i/n" (1 <= i <= n); throws InputError otherwise.
ShardSpec parse_shard(const std::string& text);

struct PreprocessStats {
  uint64_t lines = 0, events = 0, bytes = 0, raw_bytes = 0;
  double trace_seconds = 0, encode_seconds = 0, compress_seconds = 0, write_seconds = 0;  // summed over threads
  double wall_seconds = 0, hierarchy_seconds = 0, pilot_seconds = 0;
  uint64_t pilot_lines = 0;  // local lines of the pilot, and as many global ones (0: no pilot ran)
  double first_shot_share = 0;  // first-shot lines per line of lines.total the pilot chose (0: none chosen)
  // The store's first shot (first_shot.bin), written when the store is complete.
  uint64_t first_shot_lines = 0, first_shot_bytes = 0;
  double first_shot_seconds = 0;
  // The same for the second shot (second_shot.bin).
  uint64_t second_shot_lines = 0, second_shot_bytes = 0;
  double second_shot_seconds = 0;
  // The same for the lights' shot (lights_shot.bin).
  uint64_t lights_shot_lines = 0, lights_shot_bytes = 0;
  double lights_shot_seconds = 0;
  bool skipped = false;  // the shard's file was already finished and verified
  bool manifest_written = false;
};

// `print_hierarchy`: build the hierarchy, print its tree and stop.
PreprocessStats run_preprocess(const Options& options, const ShardSpec& shard, bool dry_run = false,
                               bool print_hierarchy = false);

}  // namespace mpath
