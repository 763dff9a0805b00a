// Collisions (Coutinho §3.4 swept spheres, §3.6.1 impulses with friction, §3.6.3 resting
// contact) against planes and boxes, static and kinematic.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "sim_test_util.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

using test::position_of;
using test::velocity_of;

constexpr double kR = 0.01;  // particle radius (m)

PlaneDef ground(double restitution, double friction) {
  PlaneDef p;
  p.material = {restitution, friction};
  return p;
}

/// Drops a particle from `gap` above the plane (centre at gap + r) and returns the apex gap of
/// the first bounce.
double first_bounce_apex(double e, double gap) {
  World world(WorldDef{1.0 / 1000, 0, 0.05});
  world.add_plane(ground(e, 0.0));
  const auto ps = world.add_particle_system(test::spawn_only_system());
  world.spawn_particle(ps, Vec3(0, 0, gap + kR), Vec3::Zero(), 0.01, kR, 100.0);
  bool bounced = false;
  double apex = -1.0;
  for (int i = 0; i < 4000; ++i) {
    world.advance(1.0 / 1000);
    const ParticleView v = world.particles(ps);
    const double z = v.position[2], vz = v.velocity[2];
    EXPECT_GE(z, double(v.radius[0]));
    if (!bounced && vz > 0.0) bounced = true;
    if (bounced) {
      apex = std::max(apex, z);
      if (vz < 0.0) break;
    }
  }
  EXPECT_TRUE(bounced);
  return apex - kR;
}

TEST(SimCollision, BounceHeightIsRestitutionSquaredTimesDropHeight) {
  for (double e : {0.5, 0.8}) {
    const double apex = first_bounce_apex(e, 2.0);
    EXPECT_NEAR(apex, e * e * 2.0, 0.02 * e * e * 2.0) << "e = " << e;
  }
}

TEST(SimCollision, ObliqueImpactAppliesRestitutionAndCoulombFriction) {
  // No gravity: one clean impact at (3, 0, -4) m/s with e = 0.5. Normal: v_n' = -e v_n = 2.
  // Tangential: v_t' = v_t - mu (1 + e) |v_n| = 3 - 6 mu, until the critical coefficient
  // mu* = |v_t| / ((1 + e) |v_n|) = 0.5 (Coutinho eqs. 3.56–3.57) where sliding stops.
  for (double mu : {0.0, 0.2, 0.49, 0.51, 2.0}) {
    World world;
    world.add_plane(ground(0.5, mu));
    ParticleSystemDef def = test::spawn_only_system();
    def.gravity = Vec3::Zero();
    const auto ps = world.add_particle_system(def);
    world.spawn_particle(ps, Vec3(0, 0, 0.5), Vec3(3, 0, -4), 0.01, kR, 100.0);
    world.advance(0.25);
    const Vec3 v = velocity_of(world.particles(ps), 0);
    EXPECT_NEAR(v.z(), 2.0, 1e-5) << mu;
    EXPECT_NEAR(v.x(), std::max(0.0, 3.0 - 6.0 * mu), 1e-5) << mu;
    EXPECT_EQ(v.y(), 0.0f);
  }
}

TEST(SimCollision, FrictionDragsAParticleAlongAMovingBox) {
  // A conveyor: the box slides at 1 m/s under a particle at rest on it. Contact friction
  // accelerates the particle at mu g until it moves with the box (after 1 / (mu g) = 0.204 s).
  const double mu = 0.5, g = 9.81;
  World world;
  BoxDef belt;
  belt.half_extents = Vec3(20, 1, 0.5);
  belt.material = {0.0, mu};
  belt.path.smooth = false;
  belt.path.keys = {Keyframe{0.0, Vec3(0, 0, -0.5)}, Keyframe{10.0, Vec3(10, 0, -0.5)}};
  world.add_box(belt);
  const auto ps = world.add_particle_system(test::spawn_only_system());
  world.spawn_particle(ps, Vec3(0, 0, kR), Vec3::Zero(), 0.01, kR, 100.0);
  world.advance(0.1);
  ParticleView v = world.particles(ps);
  EXPECT_NEAR(v.velocity[0], mu * g * 0.1, 0.03);
  EXPECT_NEAR(v.position[0], 0.5 * mu * g * 0.01, 0.01);  // it barely moved: no backward slip
  EXPECT_NEAR(v.position[2], kR, 1e-5);
  world.advance(0.4);
  v = world.particles(ps);
  EXPECT_NEAR(v.velocity[0], 1.0, 1e-3);
  EXPECT_NEAR(v.position[2], kR, 1e-5);
}

TEST(SimCollision, PerfectlyPlasticImpactStopsOnTheSurface) {
  World world(WorldDef{1.0 / 240, 0, 0.05});
  world.add_plane(ground(0.0, 0.3));
  const auto ps = world.add_particle_system(test::spawn_only_system());
  world.spawn_particle(ps, Vec3(0, 0, 1.0), Vec3(0, 0, -3), 0.01, kR, 100.0);
  for (int f = 0; f < 30; ++f) world.advance(1.0 / 60);
  const ParticleView v = world.particles(ps);
  EXPECT_NEAR(v.position[2], kR, 1e-6);
  EXPECT_EQ(v.velocity[2], 0.0f);
}

TEST(SimCollision, NoParticleEndsAStepBelowAPlaneAtAnySpeed) {
  struct Case {
    Vec3 normal, velocity;
    double height;
  };
  const Case cases[] = {
      {Vec3::UnitZ(), Vec3(0, 0, -200), 1.0},       {Vec3::UnitZ(), Vec3(0, 0, -1000), 1.0},
      {Vec3::UnitZ(), Vec3(0, 0, -1000), 3.0},      {Vec3::UnitZ(), Vec3(150, 80, -200), 0.5},
      {Vec3::UnitZ(), Vec3(700, -300, -1000), 2.0}, {Vec3(0.3, -0.2, 1), Vec3(400, 0, -1000), 0.7},
      {Vec3(0, -1, 1), Vec3(0, 0, -1000), 0.2},  // 45 degree slope
  };
  for (const Case& c : cases) {
    for (double e : {0.0, 0.5, 1.0}) {
      World world(WorldDef{1.0 / 240, 0, 0.05});
      PlaneDef plane = ground(e, 0.3);
      plane.normal = c.normal;
      plane.point = Vec3(0, 0, -0.25);
      world.add_plane(plane);
      const auto ps = world.add_particle_system(test::spawn_only_system());
      world.spawn_particle(ps, plane.point + c.height * c.normal.normalized(), c.velocity, 0.01,
                           kR, 100.0);
      const Vec3 n = c.normal.normalized();
      for (int step = 0; step < 240; ++step) {
        world.advance(1.0 / 240);
        const ParticleView v = world.particles(ps);
        const double d = n.dot(position_of(v, 0) - plane.point) - double(v.radius[0]);
        ASSERT_GE(d, 0.0) << "speed " << c.velocity.norm() << " e " << e << " step " << step;
      }
    }
  }
}

TEST(SimCollision, RestingParticleStaysPut) {
  World world;  // default max_step 1/240
  world.add_plane(ground(0.5, 0.3));
  const auto ps = world.add_particle_system(test::spawn_only_system());
  world.spawn_particle(ps, Vec3(0.3, -0.2, kR), Vec3::Zero(), 0.01, kR, 100.0);
  for (int f = 0; f < 120; ++f) {
    world.advance(1.0 / 60);
    const ParticleView v = world.particles(ps);
    ASSERT_NEAR(v.position[2], kR, 1e-6) << f;
    ASSERT_EQ(v.velocity[2], 0.0f) << f;
    ASSERT_EQ(v.position[0], 0.3f);
    ASSERT_EQ(v.position[1], -0.2f);
  }
}

TEST(SimCollision, BouncingParticleComesToRest) {
  for (double max_step : {1.0 / 240, 1.0 / 60}) {
    World world(WorldDef{max_step, 0, 0.05});
    world.add_plane(ground(0.5, 0.3));
    const auto ps = world.add_particle_system(test::spawn_only_system());
    world.spawn_particle(ps, Vec3(0, 0, 0.3), Vec3::Zero(), 0.01, kR, 100.0);
    for (int f = 0; f < 180; ++f) world.advance(1.0 / 60);
    const ParticleView v = world.particles(ps);
    EXPECT_NEAR(v.position[2], kR, 1e-6) << max_step;
    EXPECT_EQ(v.velocity[2], 0.0f) << max_step;
  }
}

TEST(SimCollision, SlidingParticleDeceleratesByMuGAndStops) {
  const double mu = 0.3, v0 = 3.0, g = 9.81;
  World world;
  world.add_plane(ground(0.5, mu));
  const auto ps = world.add_particle_system(test::spawn_only_system());
  world.spawn_particle(ps, Vec3(0, 0, kR), Vec3(v0, 0, 0), 0.01, kR, 100.0);
  world.advance(0.5);
  ParticleView v = world.particles(ps);
  EXPECT_NEAR(v.velocity[0], v0 - mu * g * 0.5, 1e-4);
  EXPECT_NEAR(v.position[0], v0 * 0.5 - 0.5 * mu * g * 0.25, 0.005);  // O(h) scheme error 3 mm
  EXPECT_NEAR(v.position[2], kR, 1e-6);
  world.advance(1.5);  // stops at v0 / (mu g) = 1.02 s
  v = world.particles(ps);
  EXPECT_EQ(v.velocity[0], 0.0f);
  EXPECT_EQ(v.velocity[1], 0.0f);
  EXPECT_NEAR(v.position[0], v0 * v0 / (2 * mu * g), 0.01);
  // Critical friction on a slope: static where tan(slope) <= mu, sliding where it is not.
  for (double slope_deg : {10.0, 25.0}) {
    World w;
    PlaneDef incline = ground(0.0, mu);
    const double a = slope_deg * std::numbers::pi / 180.0;
    incline.normal = Vec3(-std::sin(a), 0, std::cos(a));
    w.add_plane(incline);
    const auto s = w.add_particle_system(test::spawn_only_system());
    w.spawn_particle(s, kR * incline.normal, Vec3::Zero(), 0.01, kR, 100.0);
    w.advance(1.0);
    const double speed = test::velocity_of(w.particles(s), 0).norm();
    if (std::tan(a) <= mu) {
      EXPECT_EQ(speed, 0.0) << slope_deg;
    } else {
      // Sliding down with a = g (sin - mu cos).
      EXPECT_NEAR(speed, g * (std::sin(a) - mu * std::cos(a)) * 1.0, 0.02) << slope_deg;
    }
  }
}

/// Depth of a sphere centre inside a box expanded by r (negative when outside).
double depth_in_box(const BoxDef& box, const Vec3& p, double r) {
  const Vec3 l = box.transform.rotation.toRotationMatrix().transpose() * (p - box.transform.translation);
  return (box.half_extents + Vec3::Constant(r) - l.cwiseAbs()).minCoeff();
}

TEST(SimCollision, ParticleBouncesOffStaticBoxTop) {
  World world(WorldDef{1.0 / 1000, 0, 0.05});
  BoxDef box;
  box.transform.translation = Vec3(0, 0, 0.5);
  box.half_extents = Vec3(0.5, 0.5, 0.5);
  box.material = {0.5, 0.0};
  world.add_box(box);
  const auto ps = world.add_particle_system(test::spawn_only_system());
  world.spawn_particle(ps, Vec3(0.1, 0.2, 3.0), Vec3::Zero(), 0.01, kR, 100.0);
  const double gap = 3.0 - (1.0 + kR);
  bool bounced = false;
  double apex = 0.0;
  for (int i = 0; i < 4000; ++i) {
    world.advance(1.0 / 1000);
    const ParticleView v = world.particles(ps);
    const Vec3 p = position_of(v, 0);
    ASSERT_LE(depth_in_box(box, p, kR), 1e-5) << i;
    if (v.velocity[2] > 0.0f) bounced = true;
    if (bounced) apex = std::max(apex, p.z() - (1.0 + kR));
  }
  EXPECT_TRUE(bounced);
  EXPECT_NEAR(apex, 0.25 * gap, 0.02 * 0.25 * gap);
  const ParticleView v = world.particles(ps);  // settled on top after 4 s
  EXPECT_NEAR(v.position[2], 1.0 + kR, 1e-5);
  EXPECT_NEAR(v.position[0], 0.1, 1e-6);
  EXPECT_EQ(v.velocity[2], 0.0f);
}

TEST(SimCollision, FastParticleDoesNotTunnelThroughThinBox) {
  for (double tilt_deg : {0.0, 30.0}) {
    for (const Vec3& vel_local : {Vec3(0, 0, -200), Vec3(30, 20, -200), Vec3(0, 0, -1000)}) {
      World world;  // 1/240 s: 0.83 m (or 4.2 m) per step against 5 cm of box
      BoxDef box;
      box.transform.translation = Vec3(0, 0, 0.5);
      box.transform.rotation = Quat(Eigen::AngleAxisd(tilt_deg * std::numbers::pi / 180, Vec3::UnitX()));
      box.half_extents = Vec3(2.0, 2.0, 0.025);
      box.material = {0.5, 0.3};
      world.add_box(box);
      const Mat3 R = box.transform.rotation.toRotationMatrix();
      const auto ps = world.add_particle_system(test::spawn_only_system());
      world.spawn_particle(ps, box.transform.translation + R * Vec3(0.1, 0, 1.5), R * vel_local,
                           0.01, kR, 100.0);
      bool hit = false;
      for (int step = 0; step < 24; ++step) {
        world.advance(1.0 / 240);
        const ParticleView v = world.particles(ps);
        const Vec3 l = R.transpose() * (position_of(v, 0) - box.transform.translation);
        ASSERT_GE(l.z(), 0.025 + kR - 1e-5) << "tilt " << tilt_deg << " step " << step;
        hit = hit || (R.transpose() * velocity_of(v, 0)).z() > 0.0;
      }
      EXPECT_TRUE(hit) << "tilt " << tilt_deg;
    }
  }
}

TEST(SimCollision, KinematicBoxIsReportedWithItsInterpolatedPose) {
  World world;
  world.add_plane(ground(0.5, 0.3));
  BoxDef fixed;
  fixed.transform.translation = Vec3(5, 0, 1);
  const auto static_box = world.add_box(fixed);
  BoxDef moving;
  moving.path.smooth = false;
  moving.path.keys = {
      Keyframe{0.0, Vec3(0, 0, 0), Quat::Identity()},
      Keyframe{1.0, Vec3(2, 0, 1), Quat(Eigen::AngleAxisd(std::numbers::pi / 2, Vec3::UnitZ()))}};
  const auto kin = world.add_box(moving);
  EXPECT_TRUE(world.pose(kin).translation.isZero());
  for (int f = 0; f < 10; ++f) {
    const std::vector<MovedObject>& moved = world.advance(1.0 / 30);
    ASSERT_EQ(moved.size(), 1u);
    EXPECT_EQ(moved[0].handle, kin.id);
    const Transform expect = moving.path.sample(world.time());
    EXPECT_TRUE(moved[0].translation.isApprox(expect.translation, 1e-12));
    EXPECT_TRUE(moved[0].rotation.isApprox(expect.rotation.toRotationMatrix(), 1e-12));
    EXPECT_TRUE(world.pose(kin).translation.isApprox(expect.translation, 1e-12));
  }
  EXPECT_TRUE(world.pose(static_box).translation.isApprox(Vec3(5, 0, 1)));
  world.advance(1.0);  // past the last key: one last report of the final pose, then none
  world.advance(0.5);
  EXPECT_TRUE(world.advance(0.5).empty());
  EXPECT_TRUE(world.pose(kin).translation.isApprox(Vec3(2, 0, 1), 1e-12));
}

TEST(SimCollision, RisingBoxCarriesARestingParticle) {
  World world;
  BoxDef lift;
  lift.half_extents = Vec3(1, 1, 0.5);
  lift.material = {0.0, 0.5};
  lift.path.smooth = false;
  lift.path.keys = {Keyframe{0.0, Vec3(0, 0, -0.5)}, Keyframe{1.0, Vec3(0, 0, 0.5)}};  // top 0 -> 1
  world.add_box(lift);
  const auto ps = world.add_particle_system(test::spawn_only_system());
  world.spawn_particle(ps, Vec3(0.2, 0, kR), Vec3::Zero(), 0.01, kR, 100.0);
  for (int f = 1; f <= 55; ++f) {
    world.advance(1.0 / 60);
    const double top = lift.path.sample(world.time()).translation.z() + 0.5;
    const ParticleView v = world.particles(ps);
    ASSERT_GE(v.position[2], top + kR - 1e-5) << f;
    ASSERT_LE(v.position[2], top + kR + 1e-3) << f;
    ASSERT_NEAR(v.velocity[2], 1.0, 1e-3) << f;  // moving with the box
  }
  for (int f = 0; f < 120; ++f) world.advance(1.0 / 60);  // box stops; particle settles on it
  const ParticleView v = world.particles(ps);
  EXPECT_NEAR(v.position[2], 1.0 + kR, 1e-5);
  EXPECT_NEAR(v.position[0], 0.2, 1e-5);
}

}  // namespace
}  // namespace simreel::sim
