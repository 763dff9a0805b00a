#pragma once
// Work items split into one run per thread, each thread taking its own run from the front and,
// once that is empty, items from the back of the others' (work stealing over contiguous runs).
// For passes whose items are independent and whose results do not depend on which thread
// computed them (each item writes only its own outputs): the split still decides who does what
// on a machine whose cores run alike, so each thread keeps its own data in its core's cache,
// while a thread on a slower or busier core (a shared VM's) no longer holds the others at the
// barrier for more than an item. Private.

#include <atomic>
#include <cstddef>
#include <cstdint>

namespace simreel::sim::detail {

/// One thread's run of items [front, back), packed as front << 32 | back so that the owner
/// (advancing front) and a thief (retreating back) claim with one compare-and-swap.
using ClaimRun = std::uint64_t;

/// A run of items [front, back) (each below 2^32).
[[nodiscard]] inline ClaimRun claim_run(std::size_t front, std::size_t back) {
  return std::uint64_t(front) << 32 | std::uint64_t(back);
}

/// Claims one item of `run` (its front when `own`, else its back) into `item`; false when the
/// run is empty. Any number of threads may claim from one run at once.
inline bool claim_item(ClaimRun& run, bool own, std::size_t& item) {
  std::atomic_ref<std::uint64_t> r(run);
  std::uint64_t s = r.load(std::memory_order_relaxed);
  for (;;) {
    const std::uint64_t front = s >> 32, back = s & 0xffffffffu;
    if (front >= back) return false;
    const std::uint64_t next = own ? (front + 1) << 32 | back : front << 32 | (back - 1);
    if (r.compare_exchange_weak(s, next, std::memory_order_relaxed)) {
      item = std::size_t(own ? front : back - 1);
      return true;
    }
  }
}

/// Thread t of `parts`: f(item) for the items of its own run runs[t], front to back, then for
/// those left in the others' (runs[t + 1], ... , each from its back), until all are claimed.
/// The caller's barrier after it makes every item's writes visible to every thread.
template <class F>
void drain_runs(ClaimRun* runs, std::size_t parts, std::size_t t, const F& f) {
  std::size_t item = 0;
  while (claim_item(runs[t], true, item)) f(item);
  for (std::size_t o = 1; o < parts; ++o)
    while (claim_item(runs[(t + o) % parts], false, item)) f(item);
}

}  // namespace simreel::sim::detail
