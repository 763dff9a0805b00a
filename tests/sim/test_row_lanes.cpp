// The row kernels' AVX2 and AVX-512 forms (particles/row_lanes.hpp) give the compiler's clones'
// results bit for bit, over lengths that leave every tail, with masses, weights and signs that
// reach every select; and the semi-implicit step is exact for a constant acceleration (Coutinho
// §2.2). (On a CPU without AVX2, lanes = 4 and 8 run the clones, and without AVX-512 lanes = 8
// runs the AVX2 form: the comparisons then hold trivially, the checks against the formulas do
// not.)
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "particles/row_lanes.hpp"
#include "simreel/sim/random.hpp"

namespace simreel::sim {
namespace {

std::vector<double> random_rows(Rng& rng, std::size_t n, double lo, double hi) {
  std::vector<double> r(n);
  for (double& x : r) x = rng.uniform(lo, hi);
  return r;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  // (an empty vector's data() may be null, which memcmp must not be given)
  return a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

const std::size_t kLengths[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 15, 16, 17, 64, 255, 256};

// `shared`: every particle of the batch has one mass (the hand-written forms then divide once).
TEST(SimRowLanes, SemiImplicitLinearAvx2EqualsClonesBitForBit) {
  Rng rng(11);
  for (bool shared : {false, true})
  for (std::size_t len : kLengths) {
    for (double drag : {0.0, 0.02, 3.5}) {
      std::vector<double> m = random_rows(rng, len, 1e-4, 2.0);
      for (std::size_t i = 0; i < len; i += 5) m[i] = 1e-12;  // emitter.cpp's mass floor
      if (shared) m.assign(len, len % 2 == 0 ? 0.37 : 1e-12);
      const std::vector<double> x0 = random_rows(rng, 3 * len, -50.0, 50.0);
      std::vector<double> v0 = random_rows(rng, 3 * len, -20.0, 20.0);
      for (std::size_t c = 0; c < 3 * len; c += 7) v0[c] = -0.0;
      const std::vector<double> a = random_rows(rng, 3 * len, -30.0, 30.0);
      std::vector<double> x1 = x0, v1 = v0, x4 = x0, v4 = v0, x8 = x0, v8 = v0;
      const double h = rng.uniform(1e-4, 0.05);
      detail::semi_implicit_linear_rows(len, h, drag, 0.3, -0.7, -9.81, m.data(), x1.data(),
                                        v1.data(), a.data(), 1);
      detail::semi_implicit_linear_rows(len, h, drag, 0.3, -0.7, -9.81, m.data(), x4.data(),
                                        v4.data(), a.data(), 4);
      detail::semi_implicit_linear_rows(len, h, drag, 0.3, -0.7, -9.81, m.data(), x8.data(),
                                        v8.data(), a.data(), 8);
      EXPECT_TRUE(same_bits(x1, x4)) << "len " << len << " drag " << drag << " shared " << shared;
      EXPECT_TRUE(same_bits(v1, v4)) << "len " << len << " drag " << drag << " shared " << shared;
      EXPECT_TRUE(same_bits(x1, x8)) << "AVX-512, len " << len << " drag " << drag << " shared " << shared;
      EXPECT_TRUE(same_bits(v1, v8)) << "AVX-512, len " << len << " drag " << drag << " shared " << shared;
      if (len > 0) {
        EXPECT_FALSE(same_bits(x0, x4)) << "nothing moved";
      }
    }
  }
}

TEST(SimRowLanes, SemiImplicitLinearIsExactForConstantAccelerationAtEachWidth) {
  // Without drag x' = x + h (v + h g) - (h² / 2) g = x + h v + (h² / 2) g: the parabola.
  const double g[3] = {0.5, -1.0, -9.81};
  for (int lanes : {1, 4, 8})
    for (double h : {1e-3, 1.0 / 60, 0.1}) {
      const std::size_t len = 13;
      std::vector<double> m(len, 0.25), x(3 * len), v(3 * len), a(3 * len);
      for (std::size_t c = 0; c < 3 * len; ++c) {
        x[c] = 0.1 * double(c);
        v[c] = 1.0 - 0.2 * double(c % 5);
        a[c] = g[c % 3];
      }
      const std::vector<double> xs = x, vs = v;
      detail::semi_implicit_linear_rows(len, h, 0.0, g[0], g[1], g[2], m.data(), x.data(),
                                        v.data(), a.data(), lanes);
      for (std::size_t c = 0; c < 3 * len; ++c) {
        EXPECT_NEAR(v[c], vs[c] + h * g[c % 3], 1e-12);
        EXPECT_NEAR(x[c], xs[c] + h * vs[c] + 0.5 * h * h * g[c % 3], 1e-12)
            << "lanes " << lanes << " h " << h << " row " << c / 3 << " axis " << c % 3;
      }
    }
}

TEST(SimRowLanes, NoiseDragAvx2EqualsClonesBitForBit) {
  Rng rng(12);
  // A rotation about an oblique axis, row-major.
  const double c = std::cos(0.7), s = std::sin(0.7);
  const double q[9] = {c, -s, 0.0, s * 0.6, c * 0.6, -0.8, s * 0.8, c * 0.8, 0.6};
  // shared: 0 each particle its own weight and mass; 1, 2, 3 one mass for all and one weight
  // for all (1 everywhere, 0 or -0 outside the region: the hand-written forms divide once)
  for (int shared : {0, 1, 2, 3})
  for (std::size_t len : kLengths)
    for (double amplitude : {0.0, 1.7}) {
      std::vector<double> w = random_rows(rng, len, 0.0, 1.0);
      for (std::size_t k = 0; k < len; k += 3) w[k] = 0.0;   // outside the region
      for (std::size_t k = 1; k < len; k += 4) w[k] = -0.0;  // outside too (-0 == 0)
      for (std::size_t k = 2; k < len; k += 5) w[k] = 1.0;
      if (shared > 0) w.assign(len, shared == 1 ? 1.0 : shared == 2 ? 0.0 : -0.0);
      const std::vector<double> ux = random_rows(rng, len, -1.0, 1.0),
                                uy = random_rows(rng, len, -1.0, 1.0),
                                uz = random_rows(rng, len, -1.0, 1.0);
      std::vector<double> mass = random_rows(rng, len, 1e-4, 2.0);
      if (shared > 0) mass.assign(len, 0.0731);
      std::vector<double> v = random_rows(rng, 3 * len, -5.0, 5.0);
      for (std::size_t k = 0; k < 3 * len; k += 4) v[k] = 0.0;  // u - v = 0 where amplitude = 0
      std::vector<double> a0 = random_rows(rng, 3 * len, -10.0, 10.0);
      for (std::size_t k = 0; k < 3 * len; k += 6) a0[k] = -0.0;  // -0 + (+0) = +0 outside
      std::vector<double> a1 = a0, a4 = a0, a8 = a0;
      detail::add_noise_drag_rows(len, w.data(), ux.data(), uy.data(), uz.data(), q, amplitude,
                                  0.8, mass.data(), v.data(), a1.data(), 1);
      detail::add_noise_drag_rows(len, w.data(), ux.data(), uy.data(), uz.data(), q, amplitude,
                                  0.8, mass.data(), v.data(), a4.data(), 4);
      detail::add_noise_drag_rows(len, w.data(), ux.data(), uy.data(), uz.data(), q, amplitude,
                                  0.8, mass.data(), v.data(), a8.data(), 8);
      EXPECT_TRUE(same_bits(a1, a4)) << "len " << len << " amplitude " << amplitude << " shared " << shared;
      EXPECT_TRUE(same_bits(a1, a8)) << "AVX-512, len " << len << " amplitude " << amplitude << " shared " << shared;
      // and the drag itself, per particle: (w k_d / m) (amplitude R u - v), none outside
      for (std::size_t k = 0; k < len; ++k)
        for (int r = 0; r < 3; ++r) {
          const double u = amplitude * (q[3 * r] * ux[k] + q[3 * r + 1] * uy[k] + q[3 * r + 2] * uz[k]);
          const double want = w[k] == 0.0 ? 0.0 : w[k] * 0.8 / mass[k] * (u - v[3 * k + r]);
          EXPECT_NEAR(a4[3 * k + r] - a0[3 * k + r], want, 1e-9 * (1.0 + std::abs(want)));
        }
    }
}

TEST(SimRowLanes, RowsAndColumnsAvx2EqualClonesAndRoundTrip) {
  Rng rng(13);
  for (std::size_t len : kLengths) {
    std::vector<float> rows(3 * len);
    for (std::size_t k = 0; k < 3 * len; ++k) rows[k] = float(rng.uniform(-1e3, 1e3));
    if (len > 2) rows[4] = -0.0f;  // a signed zero and a subnormal keep their bits
    if (len > 3) rows[9] = 1e-40f;
    for (int lanes : {1, 4}) {
      if (lanes == 4 && !detail::row_lanes_avx2()) continue;
      std::vector<double> x(len), y(len), z(len);
      detail::rows_to_columns(rows.data(), len, x.data(), y.data(), z.data(), lanes);
      const auto exact = [](double got, float want) {
        const double w = want;
        return std::memcmp(&got, &w, sizeof(double)) == 0;
      };
      for (std::size_t k = 0; k < len; ++k) {
        ASSERT_TRUE(exact(x[k], rows[3 * k])) << "len " << len << " lanes " << lanes << " row " << k;
        ASSERT_TRUE(exact(y[k], rows[3 * k + 1])) << "len " << len << " lanes " << lanes << " row " << k;
        ASSERT_TRUE(exact(z[k], rows[3 * k + 2])) << "len " << len << " lanes " << lanes << " row " << k;
      }
      // The float columns: the same values, bits and all.
      std::vector<float> fx(len), fy(len), fz(len), back(3 * len + 1, 7.0f);
      detail::rows_to_columns(rows.data(), len, fx.data(), fy.data(), fz.data(), lanes);
      for (std::size_t k = 0; k < len; ++k) {
        ASSERT_EQ(std::memcmp(&fx[k], &rows[3 * k], sizeof(float)), 0) << "len " << len << " lanes " << lanes << " row " << k;
        ASSERT_EQ(std::memcmp(&fy[k], &rows[3 * k + 1], sizeof(float)), 0) << "len " << len << " lanes " << lanes << " row " << k;
        ASSERT_EQ(std::memcmp(&fz[k], &rows[3 * k + 2], sizeof(float)), 0) << "len " << len << " lanes " << lanes << " row " << k;
      }
      detail::columns_to_rows(fx.data(), fy.data(), fz.data(), len, back.data(), lanes);
      if (len > 0) {  // (rows.data() may be null when empty)
        EXPECT_EQ(std::memcmp(back.data(), rows.data(), 3 * len * sizeof(float)), 0)
            << "len " << len << " lanes " << lanes;
      }
      EXPECT_EQ(back[3 * len], 7.0f) << "wrote past the rows";
    }
  }
}

}  // namespace
}  // namespace simreel::sim
