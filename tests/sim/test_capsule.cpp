// The capsule shape (a segment along local z grown by a radius) against closed forms: time of
// impact and restitution on its side and on an end cap, sliding along it under Coulomb friction,
// no tunnelling at several step sizes, the §3.4.2 inside test, and cloth draped over it.
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

constexpr double kR = 0.01;   // particle radius (m)
constexpr double kCapR = 0.2;  // capsule radius (m)
constexpr double kCapH = 0.5;  // capsule half height (m): the segment is 1 m long

/// A horizontal capsule along world x through the origin (local z turned onto x).
BodyHandle horizontal_capsule(World& world, const Material& m) {
  BodyDef b;
  b.pose.rotation = Quat(Eigen::AngleAxisd(std::numbers::pi / 2, Vec3::UnitY()));
  b.shapes = {ShapeDef::capsule(kCapR, kCapH)};
  b.shapes[0].material = m;
  return world.add_body(b);
}

ParticleSystemDef probes(bool gravity) {
  ParticleSystemDef def = test::spawn_only_system();
  if (!gravity) def.gravity = Vec3::Zero();
  return def;
}

TEST(Capsule, DroppedOnTheSideHitsAtTheAnalyticTimeAndBouncesWithRestitution) {
  // Straight down at 2 m/s (no gravity) from z = 1 over the side: contact when the centre is at
  // z = R + r, at t* = (1 - R - r) / 2; it leaves at e * 2 m/s.
  const double e = 0.5;
  World world;
  horizontal_capsule(world, Material(e, 0.3));
  const auto ps = world.add_particle_system(probes(false));
  world.spawn_particle(ps, Vec3(0.1, 0, 1), Vec3(0, 0, -2), 0.01, kR, 100);
  const double t_hit = (1.0 - kCapR - kR) / 2.0, T = 0.5;
  world.advance(T);
  const ParticleView v = world.particles(ps);
  EXPECT_NEAR(velocity_of(v, 0).z(), 2.0 * e, 1e-6);
  EXPECT_NEAR(position_of(v, 0).z(), kCapR + kR + 2.0 * e * (T - t_hit), 1e-5);
  EXPECT_NEAR(position_of(v, 0).x(), 0.1, 1e-6);
}

TEST(Capsule, AimedAtAnEndCapReflectsOffTheCapSphere) {
  // Along -x at 2 m/s, 0.1 m above the axis, towards the cap centred at (H, 0, 0): contact where
  // |p - (H, 0, 0)| = R + r, normal n = (p - cap) / (R + r), v' = v - (1 + e)(v.n) n (frictionless).
  const double e = 0.8;
  World world;
  horizontal_capsule(world, Material(e, 0.0));
  const auto ps = world.add_particle_system(probes(false));
  const double y0 = 0.1, Rg = kCapR + kR;
  world.spawn_particle(ps, Vec3(2, 0, y0), Vec3(-2, 0, 0), 0.01, kR, 100);
  world.advance(1.0);
  const Vec3 n = Vec3(std::sqrt(Rg * Rg - y0 * y0), 0, y0) / Rg;
  const Vec3 v0(-2, 0, 0);
  const Vec3 expected = v0 - (1.0 + e) * v0.dot(n) * n;
  EXPECT_LT((velocity_of(world.particles(ps), 0) - expected).norm(), 1e-5)
      << velocity_of(world.particles(ps), 0).transpose() << " vs " << expected.transpose();
  // A capped cylinder of the same size would have turned it back along +x (flat end face).
  EXPECT_GT(velocity_of(world.particles(ps), 0).z(), 0.5);
}

/// Slides a probe along the top of a horizontal capsule (or cylinder) at 1 m/s under gravity,
/// mu = 0.2, steps of 1 ms, for T = 0.25 s (it stops only after v0 / (mu g) = 0.51 s).
ParticleView slide(World& world, bool capsule) {
  BodyDef b;
  b.pose.rotation = Quat(Eigen::AngleAxisd(std::numbers::pi / 2, Vec3::UnitY()));
  b.shapes = {capsule ? ShapeDef::capsule(kCapR, kCapH) : ShapeDef::cylinder(kCapR, kCapH)};
  b.shapes[0].material = Material(0.0, 0.2);
  world.add_body(b);
  const auto ps = world.add_particle_system(probes(true));
  world.spawn_particle(ps, Vec3(-0.3, 0, kCapR + kR), Vec3(1, 0, 0), 0.01, kR, 100);
  for (int i = 0; i < 250; ++i) world.advance(0.001);
  return world.particles(ps);
}

TEST(Capsule, SlidingAlongTheTopDeceleratesAtMuG) {
  // Resting on top and pushed along the axis: Coulomb friction decelerates it at mu g
  // (v(T) = v0 - mu g T) while the contact holds it at z = R + r.
  const double mu = 0.2, g = 9.81, v0 = 1.0, T = 0.25;
  World world(WorldDef{1.0 / 1000, 0, 0.05});
  const ParticleView v = slide(world, true);
  EXPECT_NEAR(velocity_of(v, 0).x(), v0 - mu * g * T, 2e-3);
  EXPECT_NEAR(position_of(v, 0).z(), kCapR + kR, 1e-6);
  EXPECT_GT(position_of(v, 0).x(), -0.2);
}

// Known defect, shared with the cylinder (found while writing the test above): the probe's
// position stops advancing after ~0.14 s at x = -0.1875 while its velocity goes on following
// mu g, so x(T) lags x0 + v0 T - mu g T^2 / 2 = -0.111 by 7.6 cm. A plane or box gives the closed
// form. Enable once the swept pass no longer stalls on round tops.
TEST(Capsule, SlidingPositionFollowsTheClosedFormOnRoundTops) {
  const double mu = 0.2, g = 9.81, v0 = 1.0, T = 0.25;
  for (const bool capsule : {true, false}) {
    World world(WorldDef{1.0 / 1000, 0, 0.05});
    const ParticleView v = slide(world, capsule);
    EXPECT_NEAR(position_of(v, 0).x(), -0.3 + v0 * T - 0.5 * mu * g * T * T, 2e-3) << capsule;
  }
}

TEST(Capsule, FastParticlesDoNotTunnelAtAnyStepSize) {
  // A thin upright capsule (R = 2 cm) and particles at 500 m/s (8 m per 1/60 s frame) aimed at
  // its side, at its end cap from above, and starting at offsets along the step.
  for (const double dt : {1.0 / 60, 1.0 / 240, 1.0 / 1000}) {
    World world(WorldDef{dt, 0, 0.05});
    BodyDef b;
    b.shapes = {ShapeDef::capsule(0.02, 1.0)};
    b.shapes[0].material = Material(0.5, 0.0);
    world.add_body(b);
    const auto ps = world.add_particle_system(probes(false));
    for (int k = 0; k < 7; ++k) {
      world.spawn_particle(ps, Vec3(-3.0 - 0.29 * k, 0, 0.001 * k), Vec3(500, 0, 0), 0.01, kR, 100);
      world.spawn_particle(ps, Vec3(0.001 * k, 0, 4.0 + 0.37 * k), Vec3(0, 0, -500), 0.01, kR, 100);
    }
    for (int f = 0; f < 6; ++f) world.advance(1.0 / 60);
    const ParticleView v = world.particles(ps);
    ASSERT_EQ(v.count, 14u) << dt;
    for (std::size_t i = 0; i < v.count; i += 2) {
      EXPECT_LT(position_of(v, i).x(), -kR) << "dt " << dt << " side " << i;
      EXPECT_LT(velocity_of(v, i).x(), -200.0) << "dt " << dt << " side " << i;
      EXPECT_GT(position_of(v, i + 1).z(), 1.0 + 0.02 + kR - 1e-6) << "dt " << dt << " cap " << i;
      EXPECT_GT(velocity_of(v, i + 1).z(), 200.0) << "dt " << dt << " cap " << i;
    }
  }
}

TEST(Capsule, ParticlesInsideAreRemovedButNotInTheCornersACylinderWouldFill) {
  // Upright capsule R = 0.2, H = 0.5: inside = within R of the segment |z| <= H (§3.4.2). The
  // point (0.9 R, 0, H + 0.9 R) lies in the capped cylinder of half height H + R but 1.27 R from
  // the segment's end: outside the capsule.
  World world;
  BodyDef b;
  b.shapes = {ShapeDef::capsule(kCapR, kCapH)};
  world.add_body(b);
  const auto ps = world.add_particle_system(probes(false));
  world.spawn_particle(ps, Vec3(0.1, 0, 0.3), Vec3::Zero(), 0.01, kR, 100);             // side part
  world.spawn_particle(ps, Vec3(0, 0.05, kCapH + 0.15), Vec3::Zero(), 0.01, kR, 100);   // end cap
  world.spawn_particle(ps, Vec3(0.9 * kCapR, 0, kCapH + 0.9 * kCapR), Vec3::Zero(), 0.01, kR, 100);
  world.advance(1.0 / 60);
  const ParticleView v = world.particles(ps);
  ASSERT_EQ(v.count, 1u);
  EXPECT_EQ(world.removed_inside_count(ps), 2u);
  EXPECT_NEAR(position_of(v, 0).x(), 0.9 * kCapR, 1e-6);
}

TEST(Capsule, ClothDrapedOverItStaysOutside) {
  // A cloth dropped on the horizontal capsule: every vertex ends at least `thickness` (less a
  // small tolerance) from the segment's grown surface, and the middle rests on top.
  World world;
  horizontal_capsule(world, Material(0.0, 0.5));
  ClothDef c;
  c.rows = c.columns = 15;
  c.width = c.height = 0.8;
  c.transform.translation = Vec3(0, 0, 0.4);
  const ClothHandle h = world.add_cloth(c);
  for (int f = 0; f < 60; ++f) world.advance(1.0 / 60);
  const ClothView v = world.cloth(h);
  double top = -1.0;
  for (std::size_t i = 0; i < v.vertex_count; ++i) {
    const Vec3 x(v.positions[3 * i], v.positions[3 * i + 1], v.positions[3 * i + 2]);
    const Vec3 axis(std::clamp(x.x(), -kCapH, kCapH), 0, 0);
    EXPECT_GT((x - axis).norm(), kCapR + c.thickness - 1e-3) << x.transpose();
    if (std::abs(x.x()) < 0.05 && std::abs(x.y()) < 0.05) top = std::max(top, x.z());
  }
  EXPECT_NEAR(top, kCapR + c.thickness, 5e-3);
}

}  // namespace
}  // namespace simreel::sim
