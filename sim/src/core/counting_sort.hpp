// A stable counting sort split over OpenMP threads, with the serial sort's result at any thread
// count (Knuth, TAOCP vol. 3 §5.2 "distribution counting"; the per-thread histograms of the
// parallel radix sorts, e.g. Satish, Harris & Garland 2009).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <omp.h>

// Translation units built without OpenMP (tests and benchmarks that include the engine's
// headers) get no pragmas, which leaves the serial sort (and no -Wunknown-pragmas).
#if defined(_OPENMP)
#define SIMREEL_OMP(directive) _Pragma(#directive)
#else
#define SIMREEL_OMP(directive)
#endif

namespace simreel::sim::detail {

/// Scratch of stable_counting_sort(), kept between calls so that a step allocates nothing.
struct CountingSortScratch {
  std::vector<std::vector<std::uint32_t>> counts;  ///< per thread: per bucket
  std::vector<std::size_t> totals;                 ///< per thread's stretch of buckets
};

/// Sorts the items [0, m) stably by bucket: bucket(q) in [0, buckets), or `buckets` to leave the
/// item out. place(q, rank) is called once for each item kept, rank in [0, kept), in the order
/// of (bucket, q) — the ranks of the serial counting sort. ready(kept) runs once, on one
/// thread, after the counting and before any place(). `parts` > 1 splits the items and the
/// buckets over that many threads in contiguous stretches (each with its own counts, so a
/// bucket's items take their places stretch by stretch: the same ranks); bucket() and place()
/// are then called concurrently, and place() must write only where its rank says.
/// Cost: O(m + parts × buckets) work and parts × buckets counters of scratch, so at most
/// kMaxSortParts threads take part (the grid's sort has up to 4 buckets a particle: 64 bytes of
/// counters a particle at most, whatever the world's thread count).
inline constexpr int kMaxSortParts = 4;
template <class Bucket, class Ready, class Place>
void stable_counting_sort(std::size_t m, std::size_t buckets, int parts, CountingSortScratch& scratch,
                          const Bucket& bucket, const Ready& ready, const Place& place) {
  parts = std::min(parts, kMaxSortParts);
  if (scratch.counts.size() < std::size_t(std::max(parts, 1))) scratch.counts.resize(std::size_t(std::max(parts, 1)));
  if (parts <= 1) {  // one pass of prefix sums, no region
    std::vector<std::uint32_t>& start = scratch.counts[0];
    start.assign(buckets + 2, 0);
    for (std::size_t q = 0; q < m; ++q) ++start[bucket(q) + 1];
    for (std::size_t b = 0; b < buckets; ++b) start[b + 1] += start[b];
    ready(std::size_t(start[buckets]));
    for (std::size_t q = 0; q < m; ++q) {
      const std::size_t b = bucket(q);
      if (b < buckets) place(q, std::size_t(start[b]++));
    }
    return;
  }
  scratch.totals.assign(std::size_t(parts) + 1, 0);
SIMREEL_OMP(omp parallel num_threads(parts) if (parts > 1))
  {
    const std::size_t t = std::size_t(omp_get_thread_num()), p = std::size_t(omp_get_num_threads());
    std::vector<std::uint32_t>& own = scratch.counts[t];
    own.assign(buckets + 1, 0);  // the last counts the items left out
    const std::size_t q0 = m * t / p, q1 = m * (t + 1) / p;
    for (std::size_t q = q0; q < q1; ++q) ++own[bucket(q)];
SIMREEL_OMP(omp barrier)
    // Exclusive sums over (bucket, stretch of items), the buckets split over the threads.
    const std::size_t b0 = buckets * t / p, b1 = buckets * (t + 1) / p;
    std::size_t sum = 0;
    for (std::size_t b = b0; b < b1; ++b)
      for (std::size_t u = 0; u < p; ++u) sum += scratch.counts[u][b];
    scratch.totals[t + 1] = sum;
SIMREEL_OMP(omp barrier)
SIMREEL_OMP(omp single)
    {
      for (std::size_t u = 0; u < p; ++u) scratch.totals[u + 1] += scratch.totals[u];
      ready(scratch.totals[p]);
    }  // (its implied barrier)
    sum = scratch.totals[t];
    for (std::size_t b = b0; b < b1; ++b)
      for (std::size_t u = 0; u < p; ++u) {
        const std::uint32_t k = scratch.counts[u][b];
        scratch.counts[u][b] = std::uint32_t(sum);
        sum += k;
      }
SIMREEL_OMP(omp barrier)
    for (std::size_t q = q0; q < q1; ++q) {
      const std::size_t b = bucket(q);
      if (b < buckets) place(q, std::size_t(own[b]++));
    }
  }
}

}  // namespace simreel::sim::detail

#undef SIMREEL_OMP
