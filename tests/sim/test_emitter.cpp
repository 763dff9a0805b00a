// Emitters (Coutinho §3.8): rate independent of fps, sub-step births, parameter draws and
// clamps, spread, disk and quad layouts, caps and windows, colour over lifetime, compaction.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "sim_test_util.hpp"
#include "particles/particle_store.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

using test::position_of;
using test::velocity_of;

/// A weightless, drag-free jet along +z from the origin: positions record birth order exactly.
ParticleSystemDef quiet_jet(double rate) {
  ParticleSystemDef def;
  def.name = "jet";
  def.gravity = Vec3::Zero();
  def.emitter.rate = rate;
  def.emitter.disk_radius = 1e-6;
  def.emitter.lifetime = {100.0, 0.0, 0.0};
  def.emitter.max_particles = 1'000'000;
  def.collide = false;
  return def;
}

TEST(SimEmitter, EmissionCountFollowsRateAtAnyFps) {
  for (double rate : {100.0, 37.3, 1000.0}) {
    for (int fps : {24, 30, 60, 144}) {
      World world(WorldDef{1.0 / 240, 3, 0.05});
      const auto ps = world.add_particle_system(quiet_jet(rate));
      const int frames = 2 * fps;  // 2 s
      for (int f = 1; f <= frames; ++f) {
        world.advance(1.0 / fps);
        const double expected = std::floor(rate * f / fps);
        ASSERT_LE(std::abs(double(world.emitted_count(ps)) - expected), 1.0)
            << "rate " << rate << " fps " << fps << " frame " << f;
      }
      EXPECT_LE(std::abs(double(world.emitted_count(ps)) - std::floor(rate * 2.0)), 1.0);
      EXPECT_EQ(world.particles(ps).count, world.emitted_count(ps));
    }
  }
}

TEST(SimEmitter, SubStepBirthsLeaveEvenlySpacedJet) {
  // 1000 particles/s at 10 m/s, steps of 1/60 s: ~17 births per step. If newborns were all
  // placed at the step's start or end they would bunch into bands 1/60 s apart.
  World world(WorldDef{1.0 / 60, 0, 0.05});
  ParticleSystemDef def = quiet_jet(1000.0);
  def.emitter.start_speed = {10.0, 0.0, 0.0};
  const auto ps = world.add_particle_system(def);
  for (int f = 0; f < 30; ++f) world.advance(1.0 / 60);
  const ParticleView v = world.particles(ps);
  ASSERT_GT(v.count, 400u);
  for (std::size_t i = 1; i < v.count; ++i) {
    ASSERT_EQ(v.id[i], v.id[i - 1] + 1);
    const double dz = v.position[3 * (i - 1) + 2] - v.position[3 * i + 2];
    ASSERT_NEAR(dz, 10.0 / 1000.0, 2e-5) << i;  // speed / rate
    ASSERT_NEAR(v.age[i - 1] - v.age[i], 1.0 / 1000.0, 2e-6) << i;
  }
}

TEST(SimEmitter, StartStopWindowAndMaxParticles) {
  World world(WorldDef{1.0 / 240, 0, 0.05});
  ParticleSystemDef def = quiet_jet(100.0);
  def.emitter.start_time = 0.5;
  def.emitter.stop_time = 1.0;
  const auto windowed = world.add_particle_system(def);
  ParticleSystemDef capped = quiet_jet(1000.0);
  capped.emitter.max_particles = 50;
  capped.emitter.lifetime = {0.5, 0.0, 0.0};
  const auto cap = world.add_particle_system(capped);
  world.advance(0.49);
  EXPECT_EQ(world.emitted_count(windowed), 0u);
  EXPECT_EQ(world.particles(cap).count, 50u);
  EXPECT_EQ(world.emitted_count(cap), 50u);  // paused, not queued
  for (int i = 0; i < 151; ++i) world.advance(0.01);  // to t = 2.0
  EXPECT_NEAR(double(world.emitted_count(windowed)), 50.0, 1.0);
  // The capped system's first 50 died at t = 0.5 + (birth); emission resumed, still <= 50.
  EXPECT_LE(world.particles(cap).count, 50u);
  EXPECT_GT(world.emitted_count(cap), 100u);
}

TEST(SimEmitter, DrawsAreClampedToTheirBounds) {
  World world(WorldDef{1.0 / 240, 11, 0.05});
  ParticleSystemDef def = quiet_jet(20000.0);
  def.emitter.lifetime = {1.0, 0.5, 0.8, 1.2};
  def.emitter.start_speed = {5.0, 3.0, 4.0, 6.0};
  def.emitter.radius = {0.02, 0.01, 0.015, 0.025};
  const auto ps = world.add_particle_system(def);
  world.advance(0.25);
  const ParticleView v = world.particles(ps);
  ASSERT_GT(v.count, 4000u);
  int at_min_speed = 0, at_max_speed = 0;
  for (std::size_t i = 0; i < v.count; ++i) {
    ASSERT_GE(v.lifetime[i], 0.8f);
    ASSERT_LE(v.lifetime[i], 1.2f);
    ASSERT_GE(v.radius[i], 0.015f);
    ASSERT_LE(v.radius[i], 0.025f);
    const double speed = velocity_of(v, i).norm();
    ASSERT_GE(speed, 4.0 - 1e-5);
    ASSERT_LE(speed, 6.0 + 1e-5);
    at_min_speed += speed < 4.0 + 1e-5;
    at_max_speed += speed > 6.0 - 1e-5;
  }
  // P(N(5, 3) < 4) = 0.37: the clamp is exercised, not vacuous.
  EXPECT_NEAR(double(at_min_speed) / double(v.count), 0.369, 0.03);
  EXPECT_NEAR(double(at_max_speed) / double(v.count), 0.369, 0.03);
}

TEST(SimEmitter, SpreadAnglesAreHalfNormalWithUniformAzimuth) {
  World world(WorldDef{1.0 / 240, 5, 0.05});
  ParticleSystemDef def = quiet_jet(40000.0);
  def.emitter.spread_deg = {0.0, 10.0, 0.0, 180.0};
  // Tilt the emitter: directions are measured from its +z axis, not the world's.
  def.emitter.transform.rotation = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 1, 0).normalized()));
  const auto ps = world.add_particle_system(def);
  world.advance(0.5);
  const ParticleView v = world.particles(ps);
  ASSERT_GT(v.count, 15000u);
  const Mat3 Rt = def.emitter.transform.rotation.toRotationMatrix().transpose();
  double sum_theta = 0.0, sum_cos_phi = 0.0, sum_sin_phi = 0.0;
  for (std::size_t i = 0; i < v.count; ++i) {
    const Vec3 d = Rt * velocity_of(v, i).normalized();
    sum_theta += std::acos(std::clamp(d.z(), -1.0, 1.0)) * 180.0 / std::numbers::pi;
    const double phi = std::atan2(d.y(), d.x());
    sum_cos_phi += std::cos(phi);
    sum_sin_phi += std::sin(phi);
  }
  const double n = double(v.count);
  // E|N(0, s)| = s sqrt(2/pi) = 7.979 deg; its standard error here is ~0.05 deg.
  EXPECT_NEAR(sum_theta / n, 10.0 * std::sqrt(2.0 / std::numbers::pi), 0.25);
  EXPECT_NEAR(sum_cos_phi / n, 0.0, 0.03);
  EXPECT_NEAR(sum_sin_phi / n, 0.0, 0.03);
}

TEST(SimEmitter, DiskStartPointsAreUniformOverTheArea) {
  World world(WorldDef{1.0 / 240, 8, 0.05});
  ParticleSystemDef def = quiet_jet(100000.0);
  def.emitter.start_speed = {0.0, 0.0, 0.0};
  def.emitter.disk_radius = 2.0;
  def.emitter.transform.translation = Vec3(1, 2, 3);
  const auto ps = world.add_particle_system(def);
  world.advance(0.1);
  const ParticleView v = world.particles(ps);
  ASSERT_GT(v.count, 9000u);
  int inner = 0;
  for (std::size_t i = 0; i < v.count; ++i) {
    const Vec3 p = position_of(v, i) - Vec3(1, 2, 3);
    ASSERT_NEAR(p.z(), 0.0, 1e-6);
    ASSERT_LE(p.norm(), 2.0 + 1e-6);
    inner += p.norm() < 1.0;
  }
  EXPECT_NEAR(double(inner) / double(v.count), 0.25, 0.015);  // area fraction, not radius
}

TEST(SimEmitter, QuadReleaseDoesNotOverlap) {
  // 6000/s at 60 Hz: 100 particles per release, radius 0.02 m. On 1 m x 0.6 m, cells of
  // 2 d = 0.08 m give 12 x 7 = 84 < 100, so cells of d = 0.04 m are used (dense choice); on
  // 10 m x 10 m the 2 d cells are plenty (sparse choice).
  for (const auto& size : {std::array<double, 2>{1.0, 0.6}, std::array<double, 2>{10.0, 10.0}}) {
    World world(WorldDef{1.0 / 60, 4, 0.05});
    ParticleSystemDef def = quiet_jet(6000.0);
    def.emitter.shape = EmitterShape::quad;
    def.emitter.quad_size = size;
    def.emitter.start_speed = {0.0, 0.0, 0.0};
    def.emitter.radius = {0.02, 0.0, 1e-6};
    const auto ps = world.add_particle_system(def);
    world.advance(1.0 / 60);
    const ParticleView v = world.particles(ps);
    ASSERT_EQ(v.count, 100u);
    double spread_x = 0.0;
    for (std::size_t i = 0; i < v.count; ++i) {
      const Vec3 p = position_of(v, i);
      ASSERT_LE(std::abs(p.x()), 0.5 * size[0] - 0.02 + 1e-6);
      ASSERT_LE(std::abs(p.y()), 0.5 * size[1] - 0.02 + 1e-6);
      spread_x = std::max(spread_x, std::abs(p.x()));
      for (std::size_t j = 0; j < i; ++j)
        ASSERT_GE((p - position_of(v, j)).norm(), 0.04 - 1e-6) << i << " " << j;
    }
    EXPECT_GT(spread_x, 0.3 * size[0]);  // the release covers the quad
  }
}

TEST(SimEmitter, PathMovesTheEmitterOverTime) {
  World world(WorldDef{1.0 / 240, 0, 0.05});
  ParticleSystemDef def = quiet_jet(100.0);
  def.emitter.start_speed = {0.0, 0.0, 0.0};
  def.emitter.path.smooth = false;
  def.emitter.path.keys = {Keyframe{0.0, Vec3(0, 0, 0)}, Keyframe{1.0, Vec3(10, 0, 0)}};
  const auto ps = world.add_particle_system(def);
  world.advance(1.0);
  const ParticleView v = world.particles(ps);
  ASSERT_GE(v.count, 99u);
  for (std::size_t i = 0; i < v.count; ++i) {
    const double t_birth = 1.0 - v.age[i];
    EXPECT_NEAR(v.position[3 * i], 10.0 * t_birth, 1e-4) << i;
  }
}

TEST(SimEmitter, ColorFollowsTheGradientOverLifetime) {
  World world(WorldDef{1.0 / 240, 0, 0.05});
  ParticleSystemDef def = test::spawn_only_system();
  def.emitter.color_over_lifetime = {ColorKey{0.0, {1.f, 0.f, 0.f, 1.f}},
                                     ColorKey{0.5, {0.f, 1.f, 0.f, 1.f}},
                                     ColorKey{1.0, {0.f, 0.f, 1.f, 0.f}}};
  const auto ps = world.add_particle_system(def);
  world.spawn_particle(ps, Vec3::Zero(), Vec3::Zero(), 1.0, 0.01, 2.0);
  const ParticleView v0 = world.particles(ps);
  EXPECT_EQ(v0.color[0], 1.f);
  EXPECT_EQ(v0.color[1], 0.f);
  world.advance(0.5);  // u = 0.25: halfway red -> green
  ParticleView v = world.particles(ps);
  EXPECT_NEAR(v.color[0], 0.5, 1e-4);
  EXPECT_NEAR(v.color[1], 0.5, 1e-4);
  EXPECT_NEAR(v.color[2], 0.0, 1e-4);
  world.advance(1.0);  // u = 0.75: halfway green -> blue, alpha 0.5
  v = world.particles(ps);
  EXPECT_NEAR(v.color[1], 0.5, 1e-4);
  EXPECT_NEAR(v.color[2], 0.5, 1e-4);
  EXPECT_NEAR(v.color[3], 0.5, 1e-4);
}

TEST(SimEmitter, TheOldestDyingAtTheFrontLeaveTheSurvivorsInOrder) {
  // Lifetimes growing with the id: every step the oldest die at the front of the store (the
  // usual case, dropped without moving anyone), sometimes with a later one dying too.
  World world(WorldDef{1.0 / 240, 0, 0.05});
  ParticleSystemDef def = test::spawn_only_system();
  def.gravity = Vec3::Zero();
  const auto ps = world.add_particle_system(def);
  const auto lifetime = [](int k) { return k % 97 == 50 ? 0.02 : 0.00512 + 0.001 * k; };
  for (int k = 0; k < 800; ++k) world.spawn_particle(ps, Vec3(k, 0, 0), Vec3::Zero(), 1.0, 0.01, lifetime(k));
  double t = 0.0;
  for (int step = 0; step < 240; ++step) {
    world.advance(1.0 / 240);
    t += 1.0 / 240;
    // Newborns behind the survivors, as an emitter's: they land where the dropped ones were
    // once the store's end is reached.
    for (int k = 0; k < 3; ++k) world.spawn_particle(ps, Vec3(-1, 0, 0), Vec3::Zero(), 1.0, 0.01, 10.0);
    const ParticleView v = world.particles(ps);
    std::vector<std::uint64_t> expected;
    for (int k = 0; k < 800; ++k)
      if (lifetime(k) > t + 1e-9) expected.push_back(std::uint64_t(k));
    ASSERT_EQ(v.count, expected.size() + 3 * std::size_t(step + 1)) << "step " << step;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      ASSERT_EQ(v.id[i], expected[i]) << "step " << step;
      ASSERT_EQ(v.position[3 * i], float(expected[i]));  // attributes moved with their particle
    }
    for (std::size_t i = expected.size(); i < v.count; ++i) ASSERT_EQ(v.position[3 * i], -1.f);
  }
}

TEST(SimEmitter, AColumnKeepsItsValuesThroughDropsShiftsAndGrowth) {
  detail::Column<std::uint32_t> c;
  c.reserve(8);
  for (std::uint32_t k = 0; k < 6; ++k) c.push_back(k);
  c.drop_front(4);  // live: 4 5 at slots 4, 5
  EXPECT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0], 4u);
  c.resize(5, 9);  // past the end: moved back to the start, no allocation
  EXPECT_EQ(c.capacity(), 8u);
  EXPECT_EQ(std::vector<std::uint32_t>(c.begin(), c.end()), (std::vector<std::uint32_t>{4, 5, 9, 9, 9}));
  c.resize(20);  // beyond the capacity: grows, values kept, new ones value-initialised
  EXPECT_GE(c.capacity(), 20u);
  EXPECT_EQ(c[1], 5u);
  EXPECT_EQ(c[4], 9u);
  EXPECT_EQ(c[19], 0u);
  const detail::Column<std::uint32_t> copy = c;
  c[0] = 77;
  EXPECT_EQ(copy[0], 4u);
  EXPECT_EQ(copy.size(), 20u);
  c.drop_front(20);
  EXPECT_TRUE(c.empty());
}

TEST(SimEmitter, DeadParticlesAreCompactedKeepingIdOrder) {
  World world(WorldDef{1.0 / 240, 0, 0.05});
  ParticleSystemDef def = test::spawn_only_system();
  def.gravity = Vec3::Zero();
  const auto ps = world.add_particle_system(def);
  std::vector<std::uint64_t> expected;
  // Deaths only past the first few hundred, in every third slot: the scan for the first death
  // must find it beyond its first block.
  for (int k = 0; k < 1000; ++k) {
    const double lifetime = k % 3 == 0 && k >= 600 ? 0.1 : (k % 3 == 1 ? 0.3 : 1.0);
    const std::uint64_t id =
        world.spawn_particle(ps, Vec3(k, 0, 0), Vec3(0, 0, 1), 1.0, 0.01, lifetime);
    EXPECT_EQ(id, std::uint64_t(k));
    if (lifetime > 0.2) expected.push_back(id);
  }
  world.advance(0.2);
  ParticleView v = world.particles(ps);
  ASSERT_EQ(v.count, expected.size());
  for (std::size_t i = 0; i < v.count; ++i) {
    EXPECT_EQ(v.id[i], expected[i]);
    EXPECT_EQ(v.position[3 * i], float(expected[i]));  // attributes moved with their particle
  }
  // Random lifetimes from an emitter: survivors stay in ascending id order at every frame.
  ParticleSystemDef jet = quiet_jet(500.0);
  jet.emitter.lifetime = {0.5, 0.3, 0.0, 2.0};
  const auto js = world.add_particle_system(jet);
  for (int f = 0; f < 90; ++f) {
    world.advance(1.0 / 30);
    v = world.particles(js);
    for (std::size_t i = 0; i < v.count; ++i) {
      ASSERT_LT(v.age[i], v.lifetime[i]);
      if (i > 0) {
        ASSERT_GT(v.id[i], v.id[i - 1]);
      }
    }
  }
  EXPECT_LT(v.count, world.emitted_count(js));  // some died
}

}  // namespace
}  // namespace simreel::sim
