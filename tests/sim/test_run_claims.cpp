// Work stealing over contiguous runs (core/run_claims.hpp), which the particle collider's pair
// search and sweeps use: every item claimed exactly once at any thread count, an owner's items a
// prefix of its run, and a slow thread's work taken over by the others.
#include <gtest/gtest.h>

#include <omp.h>

#include <atomic>
#include <chrono>
#include <cstddef>
#include <thread>
#include <vector>

#include "core/run_claims.hpp"

namespace {

using simreel::sim::detail::claim_item;
using simreel::sim::detail::claim_run;
using simreel::sim::detail::ClaimRun;
using simreel::sim::detail::drain_runs;

TEST(RunClaims, OwnerTakesTheFrontAThiefTheBackUntilEmpty) {
  ClaimRun run = claim_run(3, 7);
  std::size_t k = 0;
  ASSERT_TRUE(claim_item(run, true, k));
  EXPECT_EQ(k, 3u);
  ASSERT_TRUE(claim_item(run, false, k));
  EXPECT_EQ(k, 6u);
  ASSERT_TRUE(claim_item(run, false, k));
  EXPECT_EQ(k, 5u);
  ASSERT_TRUE(claim_item(run, true, k));
  EXPECT_EQ(k, 4u);
  EXPECT_FALSE(claim_item(run, true, k));
  EXPECT_FALSE(claim_item(run, false, k));
  ClaimRun empty = claim_run(5, 5);
  EXPECT_FALSE(claim_item(empty, true, k));
}

TEST(RunClaims, EveryItemOnceAndASlowThreadsWorkTakenOver) {
  // Runs of uneven length (one empty) over 1..4 threads; thread 0 sleeps on each of its items,
  // so the others must take the back of its run while it works through the front.
  for (int threads = 1; threads <= 4; ++threads) {
    const std::size_t p = std::size_t(threads);
    std::vector<std::size_t> bounds{0};
    for (std::size_t t = 0; t < p; ++t) bounds.push_back(bounds.back() + (t == 1 ? 0 : 12 + 5 * t));
    const std::size_t items = bounds.back();
    std::vector<ClaimRun> runs(p);
    for (std::size_t t = 0; t < p; ++t) runs[t] = claim_run(bounds[t], bounds[t + 1]);
    std::vector<std::atomic<int>> times(items);
    std::vector<int> by(items, -1);
    int team = 1;
#pragma omp parallel num_threads(threads)
    {
      const std::size_t t = std::size_t(omp_get_thread_num());
#pragma omp single
      team = omp_get_num_threads();
      drain_runs(runs.data(), p, t, [&](std::size_t k) {
        times[k].fetch_add(1);
        by[k] = int(t);
        if (t == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
      });
    }
    for (std::size_t k = 0; k < items; ++k) EXPECT_EQ(times[k].load(), 1) << threads << " threads, item " << k;
    // Thread 0's own items: the front of its run, without a gap.
    std::size_t own = 0;
    while (own < bounds[1] && by[own] == 0) ++own;
    for (std::size_t k = own; k < bounds[1]; ++k) EXPECT_NE(by[k], 0) << threads << " threads, item " << k;
    if (team > 1) {
      EXPECT_LT(own, bounds[1]) << "the other threads must take some of the slow thread's run";
    }
  }
}

}  // namespace
