#include "process_memory.h"

#include <malloc.h>
#include <sys/resource.h>

namespace mpath {

size_t peak_rss_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<size_t>(usage.ru_maxrss) * 1024;
}

void keep_freed_memory() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 32 << 20);   // blocks up to 32 MiB from the heap, not from mmap
  mallopt(M_TRIM_THRESHOLD, 1 << 30);    // and the heap not trimmed below 1 GiB of free space
#endif
}

}  // namespace mpath
