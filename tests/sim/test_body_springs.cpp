// Damped springs between bodies (the rigid-body issue; Coutinho §4.3.3, eqs. 4.21–4.22): a body
// on a spring from the world oscillates at ω = √(k/m) about the static extension m g / k; two free
// bodies on a spring keep their total momentum and oscillate at √(k/μ) with μ the reduced mass; a
// damped spring's amplitude decays as e^{-c t / 2m}; removing a body removes its springs.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

WorldDef step_def(double h) {
  WorldDef d;
  d.max_step = h;
  d.threads = 1;
  d.allow_sleeping = false;
  return d;
}

BodyDef box(const Vec3& p, double mass, const Vec3& g = Vec3(0.0, 0.0, -9.81)) {
  BodyDef b;
  b.type = BodyType::dynamic;
  b.pose.translation = p;
  b.mass = mass;
  b.gravity = g;
  b.shapes.push_back(ShapeDef::box(Vec3::Constant(0.1)));
  return b;
}

/// Mean spacing (s) of the upward zero crossings of x sampled every h.
double period_of(const std::vector<double>& x, double h) {
  std::vector<double> c;
  for (std::size_t i = 1; i < x.size(); ++i)
    if (x[i - 1] < 0.0 && x[i] >= 0.0) c.push_back(h * (double(i - 1) + x[i - 1] / (x[i - 1] - x[i])));
  return c.size() < 2 ? 0.0 : (c.back() - c.front()) / double(c.size() - 1);
}

TEST(BodySprings, BodyHangingFromTheWorldOscillatesAtRootKOverMAboutTheStaticExtension) {
  const double m = 2.0, k = 200.0;
  for (double h : {1.0 / 60.0, 1.0 / 240.0}) {
    World w(step_def(h));
    const BodyHandle b = w.add_body(box({0.0, 0.0, 1.0}, m));
    BodySpringDef s;
    s.body_b = b;
    s.anchor_a = {0.0, 0.0, 2.0};  // world point
    s.anchor_b = {0.0, 0.0, 1.1};  // the box's top face centre
    s.stiffness = k;
    const BodySpringHandle sh = w.add_body_spring(s);
    const double z_eq = 1.0 - m * 9.81 / k;  // released at the rest length: amplitude m g / k
    std::vector<double> x;
    double lo = 1e9;
    for (int i = 0; i < int(6.0 / h); ++i) {
      w.advance(h);
      const double z = w.pose(b).translation.z();
      x.push_back(z - z_eq);
      lo = std::min(lo, z);
    }
    const double T = 2.0 * kPi * std::sqrt(m / k);
    EXPECT_NEAR(period_of(x, h), T, 0.005 * T) << "h = " << h;
    EXPECT_NEAR(lo, 1.0 - 2.0 * m * 9.81 / k, 0.02 * m * 9.81 / k) << "the lowest point, 2 m g / k down";
    // Force on body a (the world) towards b when stretched: -k (length - rest) along +z.
    const double length = 2.0 - (w.pose(b).translation.z() + 0.1);
    EXPECT_NEAR(w.body_spring_force(sh).z(), -k * (length - 0.9), 1e-9 * k);
  }
}

TEST(BodySprings, TwoFreeBodiesKeepTheirMomentumAndOscillateAtTheReducedMass) {
  const double m1 = 1.0, m2 = 3.0, k = 120.0, h = 1.0 / 240.0;
  World w(step_def(h));
  BodyDef a = box({0.0, 0.0, 1.0}, m1, Vec3::Zero());
  a.linear_velocity = {0.5, 0.2, 0.0};  // stretches the spring, and drifts
  const BodyHandle ha = w.add_body(a);
  const BodyHandle hb = w.add_body(box({-0.5, 0.0, 1.0}, m2, Vec3::Zero()));
  BodySpringDef s;
  s.body_a = ha;
  s.body_b = hb;
  s.anchor_a = {0.0, 0.0, 1.0};  // the centres: no torque
  s.anchor_b = {-0.5, 0.0, 1.0};
  s.stiffness = k;
  w.add_body_spring(s);
  const Vec3 p0 = m1 * a.linear_velocity;
  std::vector<double> gap;
  for (int i = 0; i < int(5.0 / h); ++i) {
    w.advance(h);
    const Vec3 p = w.motion(ha).linear_momentum + w.motion(hb).linear_momentum;
    ASSERT_NEAR((p - p0).norm(), 0.0, 1e-12) << "step " << i;
    gap.push_back((w.pose(ha).translation - w.pose(hb).translation).norm() - 0.5);
  }
  const double mu = m1 * m2 / (m1 + m2);
  const double T = 2.0 * kPi * std::sqrt(mu / k);
  EXPECT_NEAR(period_of(gap, h), T, 0.005 * T);
}

TEST(BodySprings, DampedSpringDecaysAsExpMinusCtOverTwoM) {
  // No gravity, a 1 kg box on a spring to the world pulled 0.1 m out: the amplitude after t is
  // 0.1 e^{-c t / 2m} (underdamped, c = 2 N s/m, k = 400 N/m).
  const double m = 1.0, k = 400.0, c = 2.0, h = 1.0 / 480.0;
  World w(step_def(h));
  const BodyHandle b = w.add_body(box({0.1, 0.0, 1.0}, m, Vec3::Zero()));
  BodySpringDef s;
  s.body_a = b;
  s.anchor_a = {0.1, 0.0, 1.0};
  s.anchor_b = {-0.5, 0.0, 1.0};
  s.rest_length = 0.5;
  s.stiffness = k;
  s.damping = c;
  w.add_body_spring(s);
  double peak = 0.0;
  const double t_end = 2.0;
  for (int i = 0; i < int(t_end / h); ++i) {
    w.advance(h);
    if (double(i) * h > t_end - 0.4) peak = std::max(peak, std::abs(w.pose(b).translation.x()));
  }
  // The last peaks lie within the final 0.4 s (period 0.314 s): compare with the envelope there.
  const double lo = 0.1 * std::exp(-c * t_end / (2.0 * m)), hi = 0.1 * std::exp(-c * (t_end - 0.4) / (2.0 * m));
  EXPECT_GT(peak, 0.97 * lo);
  EXPECT_LT(peak, 1.03 * hi);
}

TEST(BodySprings, RemovingABodyRemovesItsSpringsAndBadDefinitionsAreRefused) {
  World w(step_def(1.0 / 240.0));
  const BodyHandle b = w.add_body(box({0.0, 0.0, 1.0}, 1.0));
  BodySpringDef s;
  s.body_b = b;
  s.anchor_a = {0.0, 0.0, 2.0};
  s.anchor_b = {0.0, 0.0, 1.0};
  s.stiffness = 10.0;
  const BodySpringHandle sh = w.add_body_spring(s);
  BodySpringDef bad = s;
  bad.stiffness = -1.0;
  EXPECT_THROW(w.add_body_spring(bad), std::invalid_argument);
  bad = s;
  bad.body_b = {};
  EXPECT_THROW(w.add_body_spring(bad), std::invalid_argument);
  w.remove(b);
  EXPECT_THROW((void)w.body_spring_force(sh), std::out_of_range);
  w.advance(1.0 / 60.0);
}

}  // namespace
}  // namespace simreel::sim
