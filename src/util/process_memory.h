// The process's memory: its peak, and how freed memory is kept.
#pragma once

#include <cstddef>
#include <string>

namespace mpath {

// Peak resident memory of this process, bytes.
size_t peak_rss_bytes();

// Asks the allocator to keep memory freed by the program for its next
// allocations instead of giving it back to the system at once: a pass
// allocates its shards' accumulators (megabytes) afresh, and faulting their
// pages in again every pass cost 10-20 % of a solve on OFFICE. Resident memory
// then stays at its peak, which the report gives anyway.
void keep_freed_memory();

// Called first thing in main (before MPI or any thread starts): where the
// kernel gives transparent huge pages only to memory that asks for them
// ("madvise", as on the machines measured) and glibc can ask (2.35 and
// later), runs the program again in place (same process id, arguments and
// environment) with GLIBC_TUNABLES=glibc.malloc.hugetlb=1 added, so that
// the allocator asks.
// First touches of memory are page faults, 2.7 ms per MB on a virtual
// machine where this was measured, a quarter of a short solve's time; with
// huge pages a 2 MB page is one fault (docs/performance.md, "Huge pages").
// Not done when GLIBC_TUNABLES already names glibc.malloc.hugetlb (the
// user's choice, or this process after its exec) or MPATH_HUGE_PAGES=0;
// when the exec fails the program runs on as it is.
void use_huge_pages(char** argv);

// The kernel's transparent huge page mode ("always", "madvise", "never";
// "" when unknown) and whether this process's allocator asks for them
// (reported in report.json and preprocess.json).
std::string transparent_huge_pages();
bool malloc_asks_for_huge_pages();

}  // namespace mpath
