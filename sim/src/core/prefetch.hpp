#pragma once
// A cache-line prefetch that the optimiser keeps. GCC treats __builtin_prefetch as free of side
// effects, so a loop that only prefetches (or a function whose prefetch hangs on a value it can
// reason about) may be deleted whole; on x86-64 the instruction is written out instead. A hint
// only: no result depends on it. Private.

namespace simreel::sim::detail {

/// Asks for the cache line holding p (read, all cache levels). p need not be valid memory: a
/// prefetch never faults.
inline void prefetch_line(const void* p) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  asm volatile("prefetcht0 (%0)" : : "r"(p));
#else
  __builtin_prefetch(p);
#endif
}

}  // namespace simreel::sim::detail
