// Orders of convergence and energy behaviour of the integrators (Coutinho Appendix B) on a
// spring pair, a harmonic oscillator with a closed form, and adaptive step doubling (eq. B.31)
// on an eccentric Kepler orbit.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "sim_test_util.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

using test::position_of;
using test::velocity_of;

// Two unit masses on a spring along x: extension e(t) = A cos(ω t), ω = sqrt(k_s / μ), μ = 1/2.
constexpr double kOmega = 2 * std::numbers::pi;  // one period per second
constexpr double kMu = 0.5;
constexpr double kKs = kOmega * kOmega * kMu;
constexpr double kA = 0.5;

struct Oscillator {
  double extension, energy;
};

Oscillator oscillate(Integrator in, double h, double T) {
  World world(WorldDef{h, 1, 0.05});
  ParticleSystemDef d = test::spawn_only_system();
  d.integrator = in;
  d.gravity = Vec3::Zero();
  d.collide = false;
  InitialParticle p;
  p.mass = 1.0;
  p.position = Vec3(-0.5 * (1 + kA), 0, 0);
  d.initial_particles.push_back(p);
  p.position = Vec3(0.5 * (1 + kA), 0, 0);
  d.initial_particles.push_back(p);
  d.springs = {SpringDef{0, 1, kKs, 0.0, 1.0}};
  const auto ps = world.add_particle_system(d);
  const int n = int(std::lround(T / h));
  for (int i = 0; i < n; ++i) world.advance(h);
  const ParticleView v = world.particles(ps);
  const double e = (position_of(v, 1) - position_of(v, 0)).norm() - 1.0;
  const double ke = 0.5 * (velocity_of(v, 0).squaredNorm() + velocity_of(v, 1).squaredNorm());
  return {e, ke + 0.5 * kKs * e * e};
}

double error_at(Integrator in, double h, double T) {
  return std::abs(oscillate(in, h, T).extension - kA * std::cos(kOmega * T));
}

void expect_order(Integrator in, double h, double T, double order, double slack) {
  const double e1 = error_at(in, h, T), e2 = error_at(in, h / 2, T), e4 = error_at(in, h / 4, T);
  const double expected = std::pow(2.0, order);
  EXPECT_NEAR(e1 / e2, expected, slack * expected) << "h " << h << " errors " << e1 << " " << e2;
  EXPECT_NEAR(e2 / e4, expected, slack * expected) << "h " << h / 2 << " errors " << e2 << " " << e4;
}

// T = 0.3 s (not a whole period, where the first-order phase and amplitude errors would cancel).
// RK4 runs at larger steps: its error must stay well above the float rounding of the stored
// state (~1e-7 m here).
TEST(SimIntegrators, ExplicitEulerIsFirstOrder) { expect_order(Integrator::explicit_euler, 1e-3, 0.3, 1, 0.1); }
TEST(SimIntegrators, SemiImplicitEulerIsFirstOrder) { expect_order(Integrator::semi_implicit_euler, 1e-3, 0.3, 1, 0.1); }
TEST(SimIntegrators, ImplicitEulerIsFirstOrder) { expect_order(Integrator::implicit_euler, 1e-3, 0.3, 1, 0.1); }
TEST(SimIntegrators, MidpointRk2IsSecondOrder) { expect_order(Integrator::rk2, 1e-2, 0.3, 2, 0.1); }
TEST(SimIntegrators, Rk4IsFourthOrder) { expect_order(Integrator::rk4, 0.1, 1.3, 4, 0.15); }

TEST(SimIntegrators, EnergyDriftIsOrderedRk4ImplicitExplicit) {
  const double h = 1.0 / 200, T = 2.0;
  const double e0 = 0.5 * kKs * kA * kA;
  const double rk4 = oscillate(Integrator::rk4, h, T).energy - e0;
  const double imp = oscillate(Integrator::implicit_euler, h, T).energy - e0;
  const double exp = oscillate(Integrator::explicit_euler, h, T).energy - e0;
  EXPECT_GT(exp, 0.0);  // explicit Euler gains energy
  EXPECT_LT(imp, 0.0);  // implicit Euler loses it
  EXPECT_LT(std::abs(rk4), std::abs(imp));
  EXPECT_LT(std::abs(imp), std::abs(exp));
}

TEST(SimIntegrators, ImplicitEulerStaysBoundedWhereExplicitDiverges) {
  // ω h = 2π / 10: explicit Euler's amplitude grows by sqrt(1 + (ω h)²) per step.
  const double h = 0.1, T = 5.0;
  EXPECT_LT(std::abs(oscillate(Integrator::implicit_euler, h, T).extension), kA);
  EXPECT_GT(std::abs(oscillate(Integrator::explicit_euler, h, T).extension), 10 * kA);
}

// ---------------------------------------------------------------------------------------------
// Adaptive step doubling on a Kepler orbit of eccentricity 0.9: a light body around a heavy one
// under the gravitational pair force; after one period it must be back where it started. The
// step needed at periapsis is far smaller than at apoapsis, where adaptive stepping pays.

struct Orbit {
  double error;
  std::uint64_t steps;
};

Orbit kepler(Integrator in, double max_step, double tolerance) {
  const double G = 1.0, M = 1.0, m = 1e-9, a = 1.0, ecc = 0.9;
  const double ra = a * (1 + ecc);
  const double va = std::sqrt(G * (M + m) * (1 - ecc) / ra);
  const double period = 2 * std::numbers::pi * std::sqrt(a * a * a / (G * (M + m)));
  World world(WorldDef{max_step, 1, 0.05});
  ParticleSystemDef d = test::spawn_only_system();
  d.integrator = in;
  d.tolerance = tolerance;
  d.gravity = Vec3::Zero();
  d.collide = false;
  d.pair_forces = {G, 0.0, 10.0, 0.0};
  InitialParticle sun, planet;
  sun.mass = M;
  planet.mass = m;
  planet.position = Vec3(ra, 0, 0);
  planet.velocity = Vec3(0, va, 0);
  d.initial_particles = {sun, planet};
  const auto ps = world.add_particle_system(d);
  world.advance(period);
  const ParticleView v = world.particles(ps);
  return {(position_of(v, 1) - position_of(v, 0) - planet.position).norm(), world.integrator_steps(ps)};
}

TEST(SimIntegrators, AdaptiveKeepsErrorUnderToleranceWithFewerSteps) {
  const double tol = 1e-6;
  const Orbit adaptive = kepler(Integrator::adaptive, 0.5, tol);
  // Global error after one orbit: within the per-step tolerance times the accepted steps (the
  // local errors do not all add up; in practice far less).
  EXPECT_LT(adaptive.error, tol * double(adaptive.steps)) << adaptive.steps;
  EXPECT_LT(adaptive.error, 1e-3);
  // Fixed-step RK4 needs many more steps for the same accuracy.
  std::uint64_t fixed_steps = 0;
  for (int n = 64; n <= 65536; n *= 2) {
    const double period = 2 * std::numbers::pi * std::sqrt(1.0 / (1.0 + 1e-9));
    const Orbit fixed = kepler(Integrator::rk4, period / n, tol);
    if (fixed.error <= adaptive.error) {
      fixed_steps = fixed.steps;
      break;
    }
  }
  ASSERT_GT(fixed_steps, 0u);
  // Even counting the two extra half steps of every doubling, adaptive is cheaper.
  EXPECT_LT(3 * adaptive.steps, fixed_steps) << adaptive.steps << " vs " << fixed_steps;
}

}  // namespace
}  // namespace simreel::sim
