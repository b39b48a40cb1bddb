// Brings the cache line holding `p` towards the core ahead of its use.
// __builtin_prefetch alone is not enough: GCC 12 at -O3 counts it as free of
// side effects and drops a loop of prefetches, or a call to a function made of
// them, as dead code; on x86-64 the instruction is issued from an asm statement
// the compiler must keep.
#pragma once

namespace mpath {

inline void prefetch(const void* p) {
#if defined(__x86_64__)
  asm volatile("prefetcht0 %0" : : "m"(*static_cast<const char*>(p)));
#else
  __builtin_prefetch(p);
#endif
}

// The same into the core's second-level cache only: for data wanted a few
// hundred nanoseconds later, which should not push out of the first-level
// cache what the core works on until then.
inline void prefetch_l2(const void* p) {
#if defined(__x86_64__)
  asm volatile("prefetcht1 %0" : : "m"(*static_cast<const char*>(p)));
#else
  __builtin_prefetch(p, 0, 2);
#endif
}

}  // namespace mpath
