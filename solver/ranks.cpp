#include "ranks.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

#ifdef MPATH_HAVE_MPI
#include <mpi.h>
#endif

namespace mpath {

int Ranks::rank_ = 0;
int Ranks::size_ = 1;
bool Ranks::mpi_ = false;

#ifdef MPATH_HAVE_MPI
namespace {

// A launcher (mpirun, srun with PMI or PMIx) started this process.
bool launched() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(v)) return true;
  return false;
}

}  // namespace
#endif

bool Ranks::built_with_mpi() {
#ifdef MPATH_HAVE_MPI
  return true;
#else
  return false;
#endif
}

void Ranks::start(int* argc, char*** argv) {
#ifdef MPATH_HAVE_MPI
  if (!launched()) return;
  int provided = 0;
  // Only the thread that called main calls MPI; the passes' threads never do.
  MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
  mpi_ = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
#else
  (void)argc;
  (void)argv;
  // Several processes of a build without MPI would each solve alone and
  // write the same output.dir: refused, by name.
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (const char* n = std::getenv(v); n && std::atoi(n) > 1) {
      std::fprintf(stderr, "mpath-solve: error: started as %s MPI processes, but built without MPI (configure with "
                   "OpenMPI installed, or -DMPATH_MPI=ON); run it as one process\n", n);
      std::exit(1);
    }
#endif
}

void Ranks::finish(int status) {
#ifdef MPATH_HAVE_MPI
  if (!mpi_) return;
  if (status != 0 && size_ > 1) MPI_Abort(MPI_COMM_WORLD, status);  // the others may wait in a sum
  MPI_Finalize();
  mpi_ = false;
#else
  (void)status;
#endif
}

#ifdef MPATH_HAVE_MPI
namespace {

// Sums `count` values of `type` (8 bytes each) over the ranks, in place, in
// pieces an int can count.
void allreduce(void* data, size_t count, MPI_Datatype type) {
  if (Ranks::size() <= 1) return;
  constexpr size_t kPiece = size_t{1} << 28;
  for (size_t at = 0; at < count; at += kPiece)
    MPI_Allreduce(MPI_IN_PLACE, static_cast<char*>(data) + at * 8, static_cast<int>(std::min(kPiece, count - at)), type,
                  MPI_SUM, MPI_COMM_WORLD);
}

}  // namespace
#endif

void Ranks::sum(double* data, size_t count) { sum_raw(data, count); }

void Ranks::sum_raw(void* doubles, size_t count) {
#ifdef MPATH_HAVE_MPI
  allreduce(doubles, count, MPI_DOUBLE);
#else
  (void)doubles;
  (void)count;
#endif
}

void Ranks::sum(uint64_t* data, size_t count) {
#ifdef MPATH_HAVE_MPI
  static_assert(sizeof(uint64_t) == 8 && sizeof(double) == 8);
  allreduce(data, count, MPI_UINT64_T);
#else
  (void)data;
  (void)count;
#endif
}

}  // namespace mpath
