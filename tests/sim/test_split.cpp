// Particle split (Coutinho §3.9.1): counts per generation, the split age, the delay in steps,
// the depth, and what children inherit (velocity, direction, size, mass, lifespan, age).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "sim_test_util.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

using test::velocity_of;

constexpr double kH = 0.01;  // internal step = sampling time (one step per advance)

ParticleSystemDef splitting_system(std::size_t children, std::size_t depth, std::size_t delay) {
  ParticleSystemDef def = test::spawn_only_system("split");
  def.gravity = Vec3::Zero();
  def.collide = false;
  def.emitter.max_particles = 100000;
  def.emitter.split.enabled = true;
  def.emitter.split.children = children;
  def.emitter.split.depth = depth;
  def.emitter.split.delay_steps = delay;
  def.emitter.split.age = 0.105;  // reached at the end of step 11 (age 0.11), not step 10
  return def;
}

/// Live count and total created after each step, for `steps` steps.
struct History {
  std::vector<std::size_t> live;
  std::vector<std::uint64_t> created;
};
History run(const ParticleSystemDef& def, int steps) {
  World world(WorldDef{kH, 1, 0.05});
  const auto ps = world.add_particle_system(def);
  world.spawn_particle(ps, Vec3::Zero(), Vec3(1, 0, 0), 1.0, 0.1, 100.0);
  History h;
  for (int s = 1; s <= steps; ++s) {
    world.advance(kH);
    h.live.push_back(world.particles(ps).count);
    h.created.push_back(world.emitted_count(ps));
  }
  return h;
}

TEST(SimSplit, ChildrenAndDepthGiveExactGenerations) {
  // 1 particle, 4 children, depth 2, delay 1: at step 11 the parent creates 4 (5 live); at step
  // 12 all 5 split once more (20 new, 25 live); then every lineage has split twice: (4+1)^2.
  const History h = run(splitting_system(4, 2, 1), 30);
  for (int s = 1; s <= 30; ++s) {
    const std::size_t k = std::size_t(s - 1);
    const std::size_t live = s < 11 ? 1 : s == 11 ? 5 : 25;
    EXPECT_EQ(h.created[k], live) << "step " << s;  // nobody dies in this run
    EXPECT_EQ(h.live[k], live) << "step " << s;
  }
  // Depth 3, 3 children: 4, 16, 64 at steps 11, 12, 13, then no more.
  const History h3 = run(splitting_system(3, 3, 1), 20);
  EXPECT_EQ(h3.live[10], 4u);
  EXPECT_EQ(h3.live[11], 16u);
  EXPECT_EQ(h3.live[12], 64u);
  EXPECT_EQ(h3.live[19], 64u);
  EXPECT_EQ(h3.created[19], 64u);
}

TEST(SimSplit, ParentsWaitWhileTheirChildrenDoNotFit) {
  // max_particles 5: the first split (1 + 4 <= 5) happens; the next ones (5 + 4 > 5) cannot.
  ParticleSystemDef def = splitting_system(4, 2, 1);
  def.emitter.max_particles = 5;
  const History h = run(def, 40);
  EXPECT_EQ(h.live[10], 5u);
  EXPECT_EQ(h.live[39], 5u);
  EXPECT_EQ(h.created[39], 5u);
}

TEST(SimSplit, DelayIsCountedInSimulationSteps) {
  // "A split delay of two indicates that, after the particle-split age has been reached, the
  // particle will create new child particles every other simulation time step": splits at steps
  // 11, 11 + delay, 11 + 2 delay, each tripling the family (2 children + the parent).
  for (std::size_t delay : {1u, 2u, 5u}) {
    const History h = run(splitting_system(2, 3, delay), 40);
    for (int s = 1; s <= 40; ++s) {
      const int d = int(delay);
      const std::size_t live = s < 11 ? 1 : s < 11 + d ? 3 : s < 11 + 2 * d ? 9 : 27;
      ASSERT_EQ(h.live[std::size_t(s - 1)], live) << "delay " << delay << " step " << s;
    }
  }
}

TEST(SimSplit, ChildrenInheritFractionsOfTheParent) {
  constexpr std::size_t kN = 20000;
  ParticleSystemDef def = splitting_system(kN, 1, 1);
  def.emitter.split.age = 0.795;  // split at the end of step 80 (age 0.8)
  def.emitter.split.velocity_fraction = 0.4;
  def.emitter.split.direction_deviation_deg = 20.0;
  def.emitter.split.size_fraction = 0.5;
  def.emitter.split.lifetime_deviation = 0.6;
  World world(WorldDef{kH, 1, 0.05});
  const auto ps = world.add_particle_system(def);
  const Vec3 v0(0, 6, 8);  // 10 m/s, no gravity or drag: constant
  world.spawn_particle(ps, Vec3(1, 2, 3), v0, 2.0, 0.08, 5.0);
  for (int s = 0; s < 80; ++s) world.advance(kH);
  const ParticleView all = world.particles(ps);
  ASSERT_EQ(all.count, kN + 1);  // the parent lives on
  ASSERT_EQ(all.id[0], 0u);
  ParticleView v = all;  // the children: skip the parent
  v.count = kN;
  v.position += 3;
  v.velocity += 3;
  v.radius += 1;
  v.mass += 1;
  v.age += 1;
  v.lifetime += 1;
  const double cos_max = std::cos(20.0 * std::numbers::pi / 180.0);
  double sum_cos = 0.0, sum_life = 0.0, sum_life2 = 0.0;
  for (std::size_t i = 0; i < v.count; ++i) {
    const Vec3 u = velocity_of(v, i);
    ASSERT_NEAR(u.norm(), 4.0, 1e-5);                        // 0.4 of the parent's speed
    const double c = u.normalized().dot(v0.normalized());
    ASSERT_GE(c, cos_max - 1e-6);                             // within the maximum deviation
    sum_cos += c;
    ASSERT_FLOAT_EQ(v.radius[i], 0.04f);                      // 0.5 of the parent's size
    ASSERT_FLOAT_EQ(v.mass[i], 2.0f * 0.125f);                // same density: m f^3
    ASSERT_FLOAT_EQ(v.lifetime[i], 5.0f);                     // the parent's lifespan
    ASSERT_GE(v.age[i], 0.8f - 0.6f - 1e-4f);                 // the parent's age +- 0.6 s
    ASSERT_LE(v.age[i], 0.8f + 0.6f + 1e-4f);
    sum_life += v.age[i];
    sum_life2 += double(v.age[i]) * v.age[i];
    ASSERT_NEAR(v.position[3 * i], all.position[0], 1e-5);   // born where the parent is
  }
  const double n = double(kN);
  // Uniform over the cap: cos(theta) uniform on [cos_max, 1].
  const double var_cos = (1.0 - cos_max) * (1.0 - cos_max) / 12.0;
  EXPECT_NEAR(sum_cos / n, 0.5 * (1.0 + cos_max), 5.0 * std::sqrt(var_cos / n));
  // Age: the parent's (0.8 s) + U(-0.6, 0.6): mean 0.8, variance 0.12.
  const double mean_life = sum_life / n;
  EXPECT_NEAR(mean_life, 0.8, 5.0 * std::sqrt(0.12 / n));
  EXPECT_NEAR(sum_life2 / n - mean_life * mean_life, 0.12, 5.0 * std::sqrt(0.8 / n) * 0.12);
}

TEST(SimSplit, EmittedParticlesSplitAtTheirSplitAgeAndAreDeterministic) {
  // A jet of 100/s whose particles split into 3 at age 0.2 s: each child's age is its parent's
  // (>= 0.2 s) within the 0.1 s deviation, and two runs give identical states.
  auto make = [] {
    ParticleSystemDef def;
    def.gravity = Vec3::Zero();
    def.collide = false;
    def.emitter.rate = 100.0;
    def.emitter.start_speed = {1.0, 0.2, 0.0};
    def.emitter.lifetime = {2.0, 0.0, 0.0};  // nobody dies in the 1 s run
    def.emitter.split = SplitDef{true, 3, 0.2, 1, 1, 0.5, 30.0, 0.7, 0.1};
    return def;
  };
  World a(WorldDef{1.0 / 240, 9, 0.05}), b(WorldDef{1.0 / 240, 9, 0.05});
  const auto pa = a.add_particle_system(make());
  const auto pb = b.add_particle_system(make());
  for (int f = 0; f < 30; ++f) {
    a.advance(1.0 / 30);
    b.advance(1.0 / 30);
  }
  const ParticleView va = a.particles(pa), vb = b.particles(pb);
  ASSERT_EQ(va.count, vb.count);
  std::size_t children = 0;
  for (std::size_t i = 0; i < va.count; ++i) {
    ASSERT_EQ(va.id[i], vb.id[i]);
    for (int k = 0; k < 3; ++k) ASSERT_EQ(va.position[3 * i + std::size_t(k)], vb.position[3 * i + std::size_t(k)]);
    if (va.radius[i] < 0.0085f) {
      ++children;
      ASSERT_NEAR(va.radius[i], 0.007, 1e-6);  // 0.7 of 0.01
      ASSERT_GE(va.age[i], 0.2f - 0.1f - 1e-5f);  // a parent's age (>= 0.2 s) +- 0.1 s
    } else {
      ASSERT_NEAR(va.radius[i], 0.01, 1e-6);  // emitted particles live on after their split
    }
  }
  // Born at j / 100 s (j = 1..100): the 80 of age >= 0.2 s at t = 1 s have split once (depth 1)
  // into 3 each (the 80th reaches 0.2 s exactly at the end, so allow it either way).
  EXPECT_NEAR(double(children), 3.0 * 80.0, 3.0);
}

}  // namespace
}  // namespace simreel::sim
