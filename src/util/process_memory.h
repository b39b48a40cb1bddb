// The process's memory: its peak, and how freed memory is kept.
#pragma once

#include <cstddef>

namespace mpath {

// Peak resident memory of this process, bytes.
size_t peak_rss_bytes();

// Asks the allocator to keep memory freed by the program for its next
// allocations instead of giving it back to the system at once: a pass
// allocates its shards' accumulators (megabytes) afresh, and faulting their
// pages in again every pass cost 10-20 % of a solve on OFFICE. Resident memory
// then stays at its peak, which the report gives anyway.
void keep_freed_memory();

}  // namespace mpath
