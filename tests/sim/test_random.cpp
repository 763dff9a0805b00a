// Rng: the project's own generator and normal distribution.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "simreel/sim/random.hpp"

namespace simreel::sim {
namespace {

TEST(SimRng, SameSeedAndStreamGiveTheSameSequence) {
  Rng a(42, 3), b(42, 3);
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(a.next_u64(), b.next_u64());
}

TEST(SimRng, StreamsAndSeedsDiffer) {
  Rng a(42, 0), b(42, 1), c(43, 0);
  int same_ab = 0, same_ac = 0;
  for (int i = 0; i < 1000; ++i) {
    const std::uint64_t x = a.next_u64();
    same_ab += x == b.next_u64();
    same_ac += x == c.next_u64();
  }
  EXPECT_EQ(same_ab, 0);
  EXPECT_EQ(same_ac, 0);
}

TEST(SimRng, UniformIsInUnitIntervalWithMeanHalf) {
  Rng rng(7);
  const int n = 200000;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double u = rng.uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    sum += u;
  }
  // sd of the mean: sqrt(1/12 / n) ~ 6.5e-4; 5 sigma.
  EXPECT_NEAR(sum / n, 0.5, 5 * std::sqrt(1.0 / 12.0 / n));
}

TEST(SimRng, NormalHasZeroMeanAndUnitDeviation) {
  Rng rng(2024, 5);
  const int n = 200000;
  double sum = 0.0, sum2 = 0.0, sum4 = 0.0;
  int beyond_2sigma = 0;
  for (int i = 0; i < n; ++i) {
    const double x = rng.normal();
    ASSERT_TRUE(std::isfinite(x));
    sum += x;
    sum2 += x * x;
    sum4 += x * x * x * x;
    beyond_2sigma += std::abs(x) > 2.0;
  }
  const double mean = sum / n;
  const double var = sum2 / n - mean * mean;
  // Standard errors: mean 1/sqrt(n), variance sqrt(2/n); 5 sigma bounds.
  EXPECT_NEAR(mean, 0.0, 5.0 / std::sqrt(n));
  EXPECT_NEAR(var, 1.0, 5.0 * std::sqrt(2.0 / n));
  // Shape, not just moments: kurtosis 3 and P(|x| > 2) = 0.0455.
  EXPECT_NEAR(sum4 / n, 3.0, 0.1);
  EXPECT_NEAR(double(beyond_2sigma) / n, 0.0455, 0.003);
}

TEST(SimRng, NormalWithZeroDeviationReturnsTheMeanWithoutDrawing) {
  Rng a(1), b(1);
  EXPECT_EQ(a.normal(3.5, 0.0), 3.5);
  EXPECT_EQ(a.next_u64(), b.next_u64());
  EXPECT_NEAR(Rng(9).normal(10.0, 2.0), 10.0 + 2.0 * Rng(9).normal(), 1e-12);
}

}  // namespace
}  // namespace simreel::sim
