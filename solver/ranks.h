// The MPI ranks of one mpath-solve run (docs/cluster.md). Launched by mpirun
// or srun, each rank runs the same solve on the same state; every pass gives
// each rank a contiguous run of its shards (solver.shards), and the shards'
// accumulators are summed over the ranks before the pass merges them in
// shard order. A shard that a rank does not run holds zeros there, so every
// rank merges exactly the accumulators one rank alone would have made: the
// answer is the same bytes on any number of ranks. Rank 0 alone writes
// checkpoints and outputs. Run without a launcher, or built without MPI
// (CMake option MPATH_MPI), there is one rank and none of this costs anything.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mpath {

class Ranks {
 public:
  // Joins the ranks when a launcher started this process (MPI_Init); a plain
  // start is one rank. Call once, first thing in main.
  static void start(int* argc, char*** argv);
  // Leaves them (MPI_Finalize) after the run, or ends every rank with `status`
  // when this one failed, so that none waits for it for ever.
  static void finish(int status);

  static int rank() { return rank_; }
  static int size() { return size_; }
  static bool root() { return rank_ == 0; }
  // Whether this rank runs shard `shard` of `shards`: contiguous runs in rank order.
  static bool owns(int shard, int shards) {
    const long long lo = static_cast<long long>(shards) * rank_ / size_;
    const long long hi = static_cast<long long>(shards) * (rank_ + 1) / size_;
    return shard >= lo && shard < hi;
  }
  // Sums over the ranks, in place: `count` doubles or 64-bit counts.
  static void sum(double* data, size_t count);
  static void sum(uint64_t* data, size_t count);
  // The same for a vector of records made of doubles alone (accumulators).
  template <typename T>
  static void sum_records(std::vector<T>& records) {
    sum_records(records.data(), records.size());
  }
  // The first `count` records at `records`.
  template <typename T>
  static void sum_records(T* records, size_t count) {
    static_assert(sizeof(T) % sizeof(double) == 0, "records of doubles alone");
    if (count > 0) sum_raw(records, count * (sizeof(T) / sizeof(double)));
  }
  // Whether MPI was built in.
  static bool built_with_mpi();

 private:
  static void sum_raw(void* doubles, size_t count);
  static int rank_, size_;
  static bool mpi_;
};

}  // namespace mpath
