// The engine's parallel stable counting sort (core/counting_sort.hpp): the serial sort's ranks at
// any thread count, items left out, and the warm-start caches and grid orders built on it.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <numeric>
#include <vector>

#include "core/counting_sort.hpp"
#include "simreel/sim/random.hpp"

namespace {

using simreel::sim::Rng;
using simreel::sim::detail::CountingSortScratch;
using simreel::sim::detail::stable_counting_sort;

TEST(CountingSort, RanksAreTheStableSortsAtAnyThreadCount) {
  // Items in 97 buckets, a tenth of them left out (bucket 97), some buckets empty: each kept
  // item's rank must be its place in a stable sort by bucket, however the items and the buckets
  // are split over the threads (stretches of uneven length for 3 of 10,007).
  const std::size_t m = 10007, buckets = 97;
  Rng rng(5, 0);
  std::vector<std::size_t> bucket(m);
  for (auto& b : bucket) {
    b = rng.uniform(0.0, 1.0) < 0.1 ? buckets : std::size_t(rng.uniform(0.0, 60.0)) * 3 / 2;
  }
  std::vector<std::size_t> expected;  // kept items in (bucket, index) order
  for (std::size_t q = 0; q < m; ++q)
    if (bucket[q] < buckets) expected.push_back(q);
  std::stable_sort(expected.begin(), expected.end(),
                   [&](std::size_t a, std::size_t b) { return bucket[a] < bucket[b]; });
  ASSERT_GT(expected.size(), 8500u);
  CountingSortScratch scratch;
  for (int parts : {1, 2, 3, 4, 16}) {  // (16: as many as kMaxSortParts take part)
    std::vector<std::size_t> at;
    std::atomic<int> readies{0};
    stable_counting_sort(
        m, buckets, parts, scratch, [&](std::size_t q) { return bucket[q]; },
        [&](std::size_t kept) {
          ++readies;
          at.assign(kept, m);
        },
        [&](std::size_t q, std::size_t rank) { at[rank] = q; });
    EXPECT_EQ(readies.load(), 1) << parts;
    EXPECT_EQ(at, expected) << parts << " threads";
  }
}

TEST(CountingSort, NothingKeptAndNoItems) {
  CountingSortScratch scratch;
  for (int parts : {1, 2}) {
    std::size_t kept = 99, placed = 0;
    stable_counting_sort(
        5, 3, parts, scratch, [](std::size_t) { return std::size_t(3); },
        [&](std::size_t k) { kept = k; }, [&](std::size_t, std::size_t) { ++placed; });
    EXPECT_EQ(kept, 0u);
    EXPECT_EQ(placed, 0u);
    stable_counting_sort(
        0, 3, parts, scratch, [](std::size_t) { return std::size_t(0); },
        [&](std::size_t k) { kept = k; }, [&](std::size_t, std::size_t) { ++placed; });
    EXPECT_EQ(kept, 0u);
    EXPECT_EQ(placed, 0u);
  }
}

}  // namespace
