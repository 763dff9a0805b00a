// Quadratic drag F = -c_2 |v| v (issue 15) against closed forms, for every integrator and several
// step sizes: terminal speed √(m g / c_2), v(t) = v_t tanh(g t / v_t) from rest, and the
// horizontal decay v(t) = v0 / (1 + c_2 v0 t / m).
#include <gtest/gtest.h>

#include <cmath>

#include "sim_test_util.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

constexpr Integrator kAll[] = {Integrator::semi_implicit_euler, Integrator::rk4,
                               Integrator::explicit_euler,      Integrator::rk2,
                               Integrator::implicit_euler,      Integrator::adaptive};

/// One particle of mass m from v0 under gravity g and quadratic drag c2 (plus linear k), to time
/// T in steps of h; returns its velocity.
Vec3 run(Integrator integrator, double h, double T, const Vec3& v0, const Vec3& g, double c2,
         double m, double k = 0.0) {
  World world(WorldDef{h, 1, 0.05});
  ParticleSystemDef def = test::spawn_only_system();
  def.integrator = integrator;
  def.gravity = g;
  def.drag = k;
  def.drag_quadratic = c2;
  const auto ps = world.add_particle_system(def);
  world.spawn_particle(ps, Vec3::Zero(), v0, m, 0.01, 100.0);
  const int n = int(std::lround(T / h));
  for (int i = 0; i < n; ++i) world.advance(h);
  const ParticleView view = world.particles(ps);
  EXPECT_EQ(view.count, 1u);
  return test::velocity_of(view, 0);
}

TEST(QuadraticDrag, TerminalSpeedIsSqrtMgOverC2AtEveryStep) {
  const double m = 0.01, c2 = 1e-3, g = 9.81, vt = std::sqrt(m * g / c2);  // 9.90 m/s
  for (Integrator in : kAll)
    for (double h : {1.0 / 30.0, 1.0 / 120.0, 1.0 / 240.0, 1.0 / 960.0}) {
      const Vec3 v = run(in, h, 8.0, Vec3::Zero(), Vec3(0, 0, -g), c2, m);
      EXPECT_NEAR(-v.z(), vt, 0.005 * vt) << "integrator " << int(in) << " h " << h;
      EXPECT_NEAR(v.x(), 0.0, 1e-9);
    }
}

TEST(QuadraticDrag, HeavyQuadraticDragStaysStable) {
  // h c_2 |v| / m = 1/30 * 1 * 100 / 1e-3 >> 2: an explicit drag would blow up; the implicit
  // one must settle on the terminal speed.
  const double m = 1e-3, c2 = 1.0, g = 9.81, vt = std::sqrt(m * g / c2);
  for (Integrator in : {Integrator::semi_implicit_euler, Integrator::rk4, Integrator::implicit_euler}) {
    const Vec3 v = run(in, 1.0 / 30.0, 2.0, Vec3(0, 0, 100.0), Vec3(0, 0, -g), c2, m);
    EXPECT_NEAR(-v.z(), vt, 0.005 * vt) << "integrator " << int(in);
  }
}

TEST(QuadraticDrag, FallFromRestFollowsTanh) {
  const double m = 0.01, c2 = 1e-3, g = 9.81, vt = std::sqrt(m * g / c2);
  for (Integrator in : kAll)
    for (double h : {1.0 / 240.0, 1.0 / 960.0})
      for (double t : {0.25, 0.5, 1.0, 2.0}) {
        const Vec3 v = run(in, h, t, Vec3::Zero(), Vec3(0, 0, -g), c2, m);
        const double exact = vt * std::tanh(g * t / vt);
        EXPECT_NEAR(-v.z(), exact, 0.005 * exact) << "integrator " << int(in) << " h " << h << " t " << t;
      }
}

TEST(QuadraticDrag, HorizontalDecayIsHyperbolic) {
  const double m = 0.01, c2 = 1e-3, v0 = 10.0;
  for (Integrator in : kAll)
    for (double h : {1.0 / 240.0, 1.0 / 960.0})
      for (double t : {0.5, 1.0, 3.0}) {
        const Vec3 v = run(in, h, t, Vec3(v0, 0, 0), Vec3::Zero(), c2, m);
        const double exact = v0 / (1.0 + c2 * v0 * t / m);
        EXPECT_NEAR(v.x(), exact, 0.005 * exact) << "integrator " << int(in) << " h " << h << " t " << t;
      }
}


TEST(QuadraticDrag, NegativeCoefficientIsRejected) {
  World world(WorldDef{1.0 / 240.0, 1, 0.05});
  ParticleSystemDef def = test::spawn_only_system();
  def.drag_quadratic = -1.0;
  EXPECT_THROW(world.add_particle_system(def), std::invalid_argument);
}

}  // namespace
}  // namespace simreel::sim
