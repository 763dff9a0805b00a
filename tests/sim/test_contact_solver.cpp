// Sequential-impulse contact solver (Catto 2005/2006; Coutinho §4.8) alone and with the
// integrator on scenes whose contacts come from collide(): bounce height, resting box, slope,
// stack, momentum and energy in a sphere–sphere collision.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "rigid_scene.hpp"

namespace simreel::sim::detail {
namespace {

using test::RigidScene;
constexpr double kDefaultStep = 1.0 / 240.0;  // WorldDef::max_step

RigidBodyDef unit_body(const Vec3& position, const Vec3& velocity) {
  RigidBodyDef d;
  d.mass = 2.0;
  d.inertia = Vec3(0.3, 0.4, 0.5).asDiagonal();
  d.position = position;
  d.linear_velocity = velocity;
  return d;
}

TEST(ContactSolver, TangentBasisIsRightHandedAndOrthonormal) {
  for (const Vec3& n : {Vec3(0, 0, 1), Vec3(1, 0, 0), Vec3(0, -1, 0), Vec3(1, 2, -3).normalized(),
                        Vec3(-0.6, 0.0, 0.8)}) {
    Vec3 t1, t2;
    tangent_basis(n, t1, t2);
    EXPECT_NEAR(t1.norm(), 1.0, 1e-15);
    EXPECT_NEAR(t2.norm(), 1.0, 1e-15);
    EXPECT_NEAR(t1.dot(n), 0.0, 1e-15);
    EXPECT_NEAR(t1.cross(t2).dot(n), 1.0, 1e-15);
  }
}

/// One body (unit_body) moving at `velocity` onto the static ground: contact at its centre of
/// mass, normal +z from the ground (a) to the body (b); prepared and solved with h = 0.01 s.
struct OneContact {
  RigidBodies bodies;
  std::array<ContactPoint, 1> contacts;
};
OneContact solve_one(const Vec3& velocity, double restitution, double friction,
                     double depth = 0.0) {
  OneContact o;
  add_body(o.bodies, unit_body(Vec3::Zero(), velocity));
  ContactPoint& c = o.contacts[0];
  c.body_b = 0;
  c.restitution = restitution;
  c.friction = friction;
  c.depth = depth;
  ContactSolver solver;
  solver.prepare(o.bodies, o.contacts, 0.01);
  solver.solve(o.bodies, o.contacts);
  return o;
}

TEST(ContactSolver, SingleImpactFollowsNewtonsLaw) {
  // A body hits the static world at its centre of mass: v_n⁺ = -e v_n⁻ exactly.
  const OneContact o = solve_one(Vec3(0.0, 0.0, -2.0), 0.5, 0.0);
  EXPECT_NEAR(o.bodies.linear_velocity[0].z(), 1.0, 1e-14);
  EXPECT_NEAR(o.contacts[0].normal_impulse, 2.0 * 3.0, 1e-13);  // m Δv
  // Same impact with the roles swapped: body a above the ground, normal from a (body) down to b.
  RigidBodies b2;
  add_body(b2, unit_body(Vec3::Zero(), Vec3(0.0, 0.0, -2.0)));
  ContactPoint c;
  c.body_a = 0;
  c.normal = -Vec3::UnitZ();
  c.restitution = 0.5;
  std::array<ContactPoint, 1> contacts{c};
  ContactSolver solver;
  solver.prepare(b2, contacts, 0.01);
  solver.solve(b2, contacts);
  EXPECT_NEAR(b2.linear_velocity[0].z(), 1.0, 1e-14);
}

TEST(ContactSolver, SlowApproachIsRestingContactNoBounce) {
  // 0.3 m/s is below the 0.5 m/s threshold: no bounce even with e = 1.
  EXPECT_NEAR(solve_one(Vec3(0.0, 0.0, -0.3), 1.0, 0.0).bodies.linear_velocity[0].z(), 0.0,
              1e-14);
}

TEST(ContactSolver, FrictionStaysInsideTheCoulombCone) {
  // Sliding diagonally (between the tangent axes) on the ground with μ = 0.2: the tangent impulse
  // is μ λ_n in magnitude and opposes the sliding direction (a cone, not a pyramid).
  const OneContact o = solve_one(Vec3(3.0, 3.0, -1.0), 0.0, 0.2);
  const ContactPoint& c = o.contacts[0];
  Vec3 t1, t2;
  tangent_basis(Vec3::UnitZ(), t1, t2);
  const Vec3 Pt = c.tangent_impulse[0] * t1 + c.tangent_impulse[1] * t2;
  EXPECT_GT(c.normal_impulse, 0.0);
  EXPECT_NEAR(Pt.norm(), 0.2 * c.normal_impulse, 1e-9);
  EXPECT_NEAR(Pt.normalized().dot(-Vec3(1, 1, 0).normalized()), 1.0, 1e-6);
}

TEST(ContactSolver, SpeculativeContactLetsTheGapClose) {
  // 1 cm apart; at 2 m/s and h = 0.01 the body would travel 2 cm: it closes exactly the gap.
  EXPECT_NEAR(solve_one(Vec3(0.0, 0.0, -2.0), 0.0, 0.0, -0.01).bodies.linear_velocity[0].z(), -1.0,
              1e-12);
}

TEST(ContactSolver, DeterministicBitForBit) {
  auto run = [] {
    RigidScene s;
    s.add_ground();
    for (int k = 0; k < 3; ++k)
      s.add(ConvexShape::box(Vec3(0.5, 0.4, 0.3)), 500.0, Vec3(0.05 * k, -0.03 * k, 0.3 + 0.62 * k),
            Quat(Eigen::AngleAxisd(0.02 * k, Vec3::UnitZ())));
    for (int i = 0; i < 200; ++i) s.step(kDefaultStep);
    return s.bodies.position;
  };
  EXPECT_EQ(run(), run());
}

/// Drops a sphere (bottom at height H0 above the ground) with restitution e; returns the highest
/// bottom height reached after the first bounce, before the next one.
double bounce_height(double h, double H0, double e) {
  RigidScene s;
  s.restitution = e;
  s.friction = 0.0;
  s.add_ground();
  const double r = 0.25;
  s.add(ConvexShape::sphere(r), 1000.0, Vec3(0.0, 0.0, r + H0));
  bool bounced = false;
  double apex = -1.0;
  for (int i = 0; i < static_cast<int>(3.0 / h); ++i) {
    s.step(h);
    const double vz = s.bodies.linear_velocity[1].z();
    if (!s.contacts.empty() && vz > 0.0) bounced = true;
    if (bounced) {
      apex = std::max(apex, s.bodies.position[1].z() - r);
      if (vz < 0.0 && s.bodies.position[1].z() - r < 0.5 * apex) break;
    }
  }
  return apex;
}

// Discrete contact has O(h V) errors in the bounce height (V = impact speed): the contact is
// found up to h V deep, the rebound velocity acts over a whole step, the slop stays. They
// partly cancel and are not monotone in h (figures printed); 1% holds at the default step and
// at 1/1000 s, not at 1/60 s (about -3%).
TEST(ContactSolver, SphereBouncesToESquaredH) {
  const double H0 = 1.0, e = 0.5;
  std::array<double, 3> rel{};
  const std::array<double, 3> steps = {1.0 / 60.0, kDefaultStep, 1.0 / 1000.0};
  for (int k = 0; k < 3; ++k)
    rel[k] = bounce_height(steps[k], H0, e) / (e * e * H0) - 1.0;
  std::printf("[ figures  ] bounce height / e^2 H - 1: %+.4f (1/60) %+.4f (1/240) %+.4f (1/1000)\n",
              rel[0], rel[1], rel[2]);
  EXPECT_LE(std::abs(rel[1]), 0.01);
  EXPECT_LE(std::abs(rel[2]), 0.01);
}

}  // namespace
}  // namespace simreel::sim::detail

namespace simreel::sim::detail {
namespace {

TEST(ContactSolverPhysics, BoxDroppedFlatComesToRestAndStays) {
  RigidScene s;
  s.friction = 0.5;
  s.add_ground();
  const Vec3 half(0.5, 0.3, 0.2);
  s.add(ConvexShape::box(half), 500.0, Vec3(0.2, -0.1, half.z() + 0.3));
  const double h = kDefaultStep;
  double t_rest = -1.0;
  for (int i = 0; i < static_cast<int>(2.0 / h); ++i) {
    s.step(h);
    const double speed = s.bodies.linear_velocity[1].norm() + s.bodies.angular_velocity[1].norm() * 0.5;
    if (speed < 1e-3 && t_rest < 0.0) t_rest = (i + 1) * h;
    if (speed >= 1e-3) t_rest = -1.0;
  }
  ASSERT_GT(t_rest, 0.0) << "not at rest within 2 s";
  const Vec3 x_rest = s.bodies.position[1];
  const Quat q_rest = s.bodies.orientation[1];
  double worst_speed = 0.0, worst_depth = 0.0;
  for (int i = 0; i < static_cast<int>(10.0 / h); ++i) {
    s.step(h);
    worst_speed = std::max(worst_speed, s.bodies.linear_velocity[1].norm());
    worst_depth = std::max(worst_depth, s.max_depth());
  }
  std::printf("[ figures  ] box at rest after %.3f s; over 10 s: max speed %.2e m/s, max depth "
              "%.2e m, drift %.2e m, %.2e rad\n", t_rest, worst_speed, worst_depth,
              (s.bodies.position[1] - x_rest).norm(), s.bodies.orientation[1].angularDistance(q_rest));
  EXPECT_LT(worst_speed, 1e-3);
  EXPECT_LE(worst_depth, s.solver.settings().slop * 1.01);
  EXPECT_LT((s.bodies.position[1] - x_rest).norm(), 1e-4);
  EXPECT_LT(s.bodies.orientation[1].angularDistance(q_rest), 1e-4);
  EXPECT_NEAR(s.bodies.position[1].z(), half.z(), 2.0 * s.solver.settings().slop);
}

/// Box on a slope of angle theta with friction mu, started at rest; returns the displacement
/// along the slope (downhill positive) after `duration` and the mean acceleration.
std::pair<double, double> slide(double theta, double mu, double duration) {
  RigidScene s;
  s.friction = mu;
  const Quat tilt(Eigen::AngleAxisd(theta, Vec3::UnitY()));
  s.add_ground(tilt);
  const Vec3 half(0.3, 0.3, 0.1);
  // Rotating about y by θ > 0 tips +x down: (cos θ, 0, -sin θ) is downhill.
  const Vec3 up = tilt * Vec3::UnitZ(), downhill = tilt * Vec3::UnitX();
  s.add(ConvexShape::box(half), 500.0, (half.z() - 0.0005) * up, tilt);
  const double h = kDefaultStep;
  const int n = static_cast<int>(duration / h);
  for (int i = 0; i < n; ++i) s.step(h);
  // Started at rest: constant acceleration a = v(t) / t (velocities are exact for constant
  // forces under semi-implicit Euler, positions carry an O(h) offset).
  return {s.bodies.position[1].dot(downhill), s.bodies.linear_velocity[1].dot(downhill) / (n * h)};
}

TEST(ContactSolverPhysics, BoxOnSlopeSticksBelowTheFrictionAngleAndSlidesAbove) {
  const double g = 9.81, mu = 0.4;
  for (const double theta_deg : {10.0, 20.0}) {  // tan 20° = 0.364 < 0.4
    const auto [d, a] = slide(theta_deg * M_PI / 180.0, mu, 2.0);
    EXPECT_LT(std::abs(d), 1e-3) << theta_deg << "°";
  }
  for (const double theta_deg : {30.0, 45.0}) {
    const double th = theta_deg * M_PI / 180.0;
    const auto [d, a] = slide(th, mu, 1.0);
    const double expected = g * (std::sin(th) - mu * std::cos(th));
    std::printf("[ figures  ] slope %.0f°: a = %.4f m/s² vs %.4f (%.2f%%)\n", theta_deg, a,
                expected, 100.0 * (a / expected - 1.0));
    EXPECT_NEAR(a, expected, 0.02 * expected);
  }
}

TEST(ContactSolverPhysics, StackOfFiveBoxesStandsTenSeconds) {
  RigidScene s;
  s.friction = 0.6;
  s.add_ground();
  s.add_box_stack(5, Vec3(0.4, 0.4, 0.2), 400.0, 0.0, 0.01);
  std::vector<Vec3> start = s.bodies.position;
  const double h = kDefaultStep;
  for (int i = 0; i < static_cast<int>(10.0 / h); ++i) s.step(h);
  double drift = 0.0;
  for (std::size_t k = 1; k < s.bodies.size(); ++k)
    drift = std::max(drift, (s.bodies.position[k] - start[k]).norm());
  std::printf("[ figures  ] 5-box stack after 10 s: max displacement %.2e m, max depth %.2e m\n",
              drift, s.max_depth());
  EXPECT_LT(drift, 0.01);
  for (std::size_t k = 1; k < s.bodies.size(); ++k)
    EXPECT_LT(s.bodies.linear_velocity[k].norm(), 1e-3);
}

TEST(ContactSolverPhysics, SphereSphereConservesMomentumAndEnergyForEOne) {
  for (const double e : {1.0, 0.3}) {
    RigidScene s;
    s.gravity.setZero();
    s.restitution = e;
    s.friction = 0.0;
    s.add(ConvexShape::sphere(0.3), 1000.0, Vec3(-1.0, 0.0, 0.0), Quat::Identity(), Vec3(2.0, 0.0, 0.0));
    s.add(ConvexShape::sphere(0.2), 3000.0, Vec3(1.0, 0.15, 0.05), Quat::Identity(), Vec3(-1.0, 0.0, 0.0));
    auto momentum = [&] {
      return Vec3(s.bodies.mass[0] * s.bodies.linear_velocity[0] +
                  s.bodies.mass[1] * s.bodies.linear_velocity[1]);
    };
    auto energy = [&] { return kinetic_energy(s.bodies, 0) + kinetic_energy(s.bodies, 1); };
    const Vec3 P0 = momentum();
    const double E0 = energy();
    bool hit = false;
    for (int i = 0; i < 600; ++i) {
      s.step(kDefaultStep);
      hit = hit || !s.contacts.empty();
    }
    ASSERT_TRUE(hit);
    EXPECT_LE((momentum() - P0).norm(), 1e-12 * P0.norm()) << "e " << e;
    if (e == 1.0) EXPECT_NEAR(energy(), E0, 1e-9 * E0);
    else EXPECT_LT(energy(), 0.99 * E0);
    // Frictionless spheres: no spin.
    EXPECT_LE(s.bodies.angular_velocity[0].norm() + s.bodies.angular_velocity[1].norm(), 1e-12);
  }
}

}  // namespace
}  // namespace simreel::sim::detail
