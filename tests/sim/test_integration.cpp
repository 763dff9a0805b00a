// Integrators against closed forms (Coutinho §3.3.1–3.3.2, App. B): free fall, linear drag,
// and the order of convergence of semi-implicit Euler (1) and RK4 (4).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "particles/particle_store.hpp"
#include "sim_test_util.hpp"
#include "simreel/sim/random.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

struct State {
  Vec3 x, v;
};

/// One particle from x0 with v0, gravity g, drag k (kg/s) on mass m, advanced to time T in steps
/// of h (one advance() call per step, so h is exact).
State simulate(Integrator integrator, double h, double T, const Vec3& x0, const Vec3& v0,
               const Vec3& g, double k, double m) {
  World world(WorldDef{h, 1, 0.05});
  ParticleSystemDef def = test::spawn_only_system();
  def.integrator = integrator;
  def.gravity = g;
  def.drag = k;
  const auto ps = world.add_particle_system(def);
  world.spawn_particle(ps, x0, v0, m, 0.01, 100.0);
  const int n = int(std::lround(T / h));
  for (int i = 0; i < n; ++i) world.advance(h);
  const ParticleView view = world.particles(ps);
  EXPECT_EQ(view.count, 1u);
  return {test::position_of(view, 0), test::velocity_of(view, 0)};
}

/// Closed form with linear drag: v(t) = v_t + (v0 - v_t) e^{-ct}, v_t = g / c, c = k / m;
/// x(t) = x0 + v_t t + (v0 - v_t)(1 - e^{-ct}) / c. Without drag: x0 + v0 t + g t^2 / 2.
State exact(double t, const Vec3& x0, const Vec3& v0, const Vec3& g, double k, double m) {
  if (k == 0.0) return {x0 + v0 * t + 0.5 * g * t * t, v0 + g * t};
  const double c = k / m;
  const Vec3 vt = g / c;
  const double e = std::exp(-c * t);
  return {x0 + vt * t + (v0 - vt) * (1.0 - e) / c, vt + (v0 - vt) * e};
}

const Vec3 kG(0, 0, -9.81);

TEST(SimIntegration, SemiImplicitEulerFreeFallIsExact) {
  // v += g h; x += h v - h² g / 2 = x + h v0 + h² g / 2: exact under constant gravity (issue 15;
  // the plain scheme x += h v was g h t / 2 off).
  const Vec3 x0(1, 2, 10), v0(3, -1, 4);
  const double T = 1.0;
  for (double h : {1.0 / 60, 1.0 / 240}) {
    const State s = simulate(Integrator::semi_implicit_euler, h, T, x0, v0, kG, 0.0, 1.0);
    const State e = exact(T, x0, v0, kG, 0.0, 1.0);
    EXPECT_LT((s.x - e.x).norm(), 1e-4) << h;  // float storage at 10 m (ulp 1e-6), not the method
    EXPECT_LT((s.v - e.v).norm(), 2e-5) << h;
  }
}

TEST(SimIntegration, ChunksThatShareOneMassGiveEachParticleItsOwnBits) {
  // Semi-implicit Euler with linear drag divides d = m / (m + h k_d) once for a chunk whose
  // particles share one mass (an emitter's), and per particle otherwise: every particle must get
  // the same bits either way. The same particles integrated with the last of every chunk of 128
  // given another mass (each chunk then mixed), at several masses, with drag strong enough
  // (h k_d / m from 0.01 to 0.4) that a one-ulp change in d shows.
  const double h = 1.0 / 240;
  detail::ForceParams f{};
  f.gravity[2] = -9.81f;
  f.drag = 0.05f;
  const std::size_t n = 1000;
  for (const float mass : {2e-3f, 1.3e-3f, 7.7e-4f, 5.1e-4f, 3.3e-3f, 1.9e-2f}) {
    detail::ParticleStore shared;
    shared.reserve(n);
    shared.append(n);
    Rng rng(11);
    for (std::size_t i = 0; i < 3 * n; ++i) {
      shared.position[i] = float(rng.uniform(-3, 3));
      shared.velocity[i] = float(rng.uniform(-8, 8));
    }
    for (std::size_t i = 0; i < n; ++i) {
      shared.mass[i] = mass;
      shared.age[i] = 0.0f;
    }
    const detail::ParticleStore start = shared;
    detail::ParticleStore mixed = shared;
    for (std::size_t i = 127; i < n; i += 128) mixed.mass[i] = 2.0f * mass;
    for (int step = 0; step < 5; ++step) {
      ASSERT_FALSE(detail::integrate(shared, 0, n, h, f, Integrator::semi_implicit_euler, 1));
      ASSERT_FALSE(detail::integrate(mixed, 0, n, h, f, Integrator::semi_implicit_euler, 1));
    }
    std::size_t differ = 0, compared = 0, slowed = 0;
    for (std::size_t i = 0; i < n; ++i) {
      // The drag acted: the horizontal speed fell by (1 + h k_d / m)^-5.
      slowed += std::abs(shared.velocity[3 * i]) < 0.96f * std::abs(start.velocity[3 * i]);
      if (i % 128 == 127) continue;
      differ += std::memcmp(&shared.position[3 * i], &mixed.position[3 * i], 3 * sizeof(float)) != 0 ||
                std::memcmp(&shared.velocity[3 * i], &mixed.velocity[3 * i], 3 * sizeof(float)) != 0;
      ++compared;
    }
    EXPECT_EQ(differ, 0u) << "mass " << mass;
    EXPECT_GT(compared, n - n / 50);
    EXPECT_GT(slowed, n - n / 50) << "mass " << mass;
  }
}

TEST(SimIntegration, Rk4FreeFallIsExact) {
  const Vec3 x0(1, 2, 10), v0(3, -1, 4);
  const State s = simulate(Integrator::rk4, 1.0 / 60, 1.0, x0, v0, kG, 0.0, 1.0);
  const State e = exact(1.0, x0, v0, kG, 0.0, 1.0);
  EXPECT_LT((s.x - e.x).norm(), 1e-5);  // float storage, not the method
  EXPECT_LT((s.v - e.v).norm(), 1e-5);
}

TEST(SimIntegration, LinearDragMatchesClosedForm) {
  const Vec3 x0(0, 0, 5), v0(4, 0, 12);
  const double m = 0.2, k = 0.3, T = 2.0;
  const State e = exact(T, x0, v0, kG, k, m);
  const State rk = simulate(Integrator::rk4, 1.0 / 240, T, x0, v0, kG, k, m);
  EXPECT_LT((rk.x - e.x).norm(), 2e-5);
  EXPECT_LT((rk.v - e.v).norm(), 2e-5);
  const State se = simulate(Integrator::semi_implicit_euler, 1.0 / 240, T, x0, v0, kG, k, m);
  EXPECT_LT((se.x - e.x).norm(), 0.1);  // O(h): ~h/2 per unit of velocity change, and more
  EXPECT_LT((se.v - e.v).norm(), 0.05);
  EXPECT_GT((se.v - e.v).norm(), 1e-4);  // first order: visibly worse than RK4
  // Terminal velocity is approached: v -> m g / k.
  const State late = simulate(Integrator::rk4, 1.0 / 60, 20.0, x0, v0, kG, k, m);
  EXPECT_NEAR(late.v.z(), -m * 9.81 / k, 1e-4);
  EXPECT_NEAR(late.v.x(), 0.0, 1e-4);
}

TEST(SimIntegration, HeavyDragOnLightParticlesStaysStable) {
  // h k / m = (1/240) 1e-3 / 1e-9 ~ 4000: explicit drag would multiply v by -4000 per step.
  // Both integrators must settle on the terminal velocity m g / k instead.
  const double m = 1e-9, k = 1e-3;
  for (Integrator integ : {Integrator::semi_implicit_euler, Integrator::rk4}) {
    const State s = simulate(integ, 1.0 / 240, 0.5, Vec3(0, 0, 1), Vec3(50, 0, 50), kG, k, m);
    EXPECT_NEAR(s.v.z(), -m * 9.81 / k, 1e-9) << int(integ);
    EXPECT_NEAR(s.v.x(), 0.0, 1e-9) << int(integ);
    EXPECT_NEAR(s.x.x(), 50.0 * m / k, 1e-5) << int(integ);  // the transient's displacement
  }
}

/// Errors in position and velocity on the drag problem at step h.
State drag_errors(Integrator integ, double h, const Vec3& g) {
  const Vec3 x0(0, 0, 1), v0(3, 0, 8);
  const double m = 0.1, k = 0.5, T = 1.0;  // c = 5 /s: the step resolves e^{-ct} coarsely
  const State s = simulate(integ, h, T, x0, v0, g, k, m);
  const State e = exact(T, x0, v0, g, k, m);
  return {s.x - e.x, s.v - e.v};
}

TEST(SimIntegration, SemiImplicitEulerConvergesAtFirstOrder) {
  auto err = [](double h) {
    const State e = drag_errors(Integrator::semi_implicit_euler, h, kG);
    return e.x.norm() + e.v.norm();
  };
  const double e1 = err(0.02), e2 = err(0.01), e4 = err(0.005);
  EXPECT_NEAR(e1 / e2, 2.0, 0.2);
  EXPECT_NEAR(e2 / e4, 2.0, 0.2);
}

TEST(SimIntegration, Rk4ConvergesAtFourthOrder) {
  // Pure drag (g = 0) and the velocity error: the errors at h/4 are ~1e-6 m/s, so float storage
  // noise must scale with the state, which decays here. For v' = -c v RK4's global error is
  // c T z^4 / 120 (1 + 5 z / 6 + ...) with z = c h, so halving z = 0.5 -> 0.25 -> 0.125 gives
  // ratios 18.8 and 17.5 on the way to 16 (a third-order method would give 8).
  auto err = [](double h) { return drag_errors(Integrator::rk4, h, Vec3::Zero()).v.norm(); };
  const double e1 = err(0.1), e2 = err(0.05), e4 = err(0.025);
  EXPECT_NEAR(e1 / e2, 16.0 * (1 + 5 * 0.5 / 6) / (1 + 5 * 0.25 / 6), 2.0);
  EXPECT_NEAR(e2 / e4, 16.0 * (1 + 5 * 0.25 / 6) / (1 + 5 * 0.125 / 6), 2.0);
  // And with gravity RK4 stays far ahead of semi-implicit Euler at the same step.
  EXPECT_LT(drag_errors(Integrator::rk4, 0.05, kG).x.norm() * 1e3,
            drag_errors(Integrator::semi_implicit_euler, 0.05, kG).x.norm());
}

TEST(SimIntegration, StepCountIsCeilOfSamplingOverMaxStepWithoutRoundingExtras) {
  World world(WorldDef{0.1, 0, 0.05});
  world.advance(0.1 + 0.1);  // 0.2 / 0.1 may round above 2
  EXPECT_EQ(world.step_count(), 2u);
  world.advance(0.3);  // 2.9999999999999996 steps' worth: 3
  EXPECT_EQ(world.step_count(), 5u);
  world.advance(0.20000000001);  // ratio 2.0000000001: rounding noise, still 2 steps
  EXPECT_EQ(world.step_count(), 7u);
  world.advance(0.20001);  // a real excess: 3 steps
  EXPECT_EQ(world.step_count(), 10u);
  world.advance(0.01);  // shorter than max_step: one step
  EXPECT_EQ(world.step_count(), 11u);
  EXPECT_NEAR(world.time(), 0.91001, 1e-9);
  World w60(WorldDef{1.0 / 240, 0, 0.05});
  w60.advance(1.0 / 60);
  EXPECT_EQ(w60.step_count(), 4u);
}

}  // namespace
}  // namespace simreel::sim
