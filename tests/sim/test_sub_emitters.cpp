// Sub-emitters (SubEmitterDef, Unity's "Sub Emitters" with the death trigger): where and when the
// sub-particles are born (the parent's death point and instant within the step), what they
// inherit, how many (count, probability, split children excluded), and the API's checks.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "sim_test_util.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

constexpr double kH = 0.01;  // internal step = sampling time (one step per advance)

/// A target that emits only from its parents: a point, at rest, no gravity, long-lived.
ParticleSystemDef target_system() {
  ParticleSystemDef def = test::spawn_only_system("flashes");
  def.gravity = Vec3::Zero();
  def.collide = false;
  def.emitter.shape = EmitterShape::point;
  def.emitter.start_speed = Distribution{0.0, 0.0};
  def.emitter.lifetime = Distribution{5.0, 0.0};
  def.emitter.max_particles = 100000;
  return def;
}

ParticleSystemDef parent_system() {
  ParticleSystemDef def = test::spawn_only_system("stars");
  def.gravity = Vec3::Zero();
  def.collide = false;
  def.emitter.max_particles = 100000;
  return def;
}

// A parent moving at 2 m/s along x with lifetime 0.1234 s dies 0.0066 s before the end of the
// step that ends at 0.13 s, at x = 0.2468 m. Its sub-particles are born there and then: with the
// velocity inherited they end the step where the parent would be (x = 0.26 m), aged 0.0066 s;
// with none they stay at the death point. Nothing is born before.
TEST(SubEmitters, BornAtTheParentsDeathPointAndInstant) {
  for (const double inherit : {1.0, 0.0}) {
    World world(WorldDef{kH, 1, 0.05});
    const auto stars = world.add_particle_system(parent_system());
    const auto flashes = world.add_particle_system(target_system());
    SubEmitterDef se;
    se.system = flashes;
    se.count = 3;
    se.inherit_velocity = inherit;
    world.add_sub_emitter(stars, se);
    world.spawn_particle(stars, Vec3::Zero(), Vec3(2, 0, 0), 1.0, 0.1, 0.1234);
    for (int s = 0; s < 12; ++s) {
      world.advance(kH);
      ASSERT_EQ(world.particles(flashes).count, 0u) << "step " << s + 1;
    }
    world.advance(kH);  // t = 0.13: the parent dies in this step
    EXPECT_EQ(world.particles(stars).count, 0u);
    const ParticleView v = world.particles(flashes);
    ASSERT_EQ(v.count, 3u);
    for (std::size_t i = 0; i < v.count; ++i) {
      EXPECT_NEAR(v.age[i], 0.13 - 0.1234, 1e-6);
      EXPECT_NEAR(v.position[3 * i], inherit > 0.0 ? 0.26 : 0.2468, 1e-5) << "inherit " << inherit;
      EXPECT_NEAR(v.position[3 * i + 1], 0.0, 1e-7);
      EXPECT_NEAR(v.velocity[3 * i], 2.0 * inherit, 1e-6);
    }
  }
}

// Probability: one draw per dying parent (binomial); 0 never fires. split_children false: only
// the emitted parent fires, not the two children its split made.
TEST(SubEmitters, ProbabilityAndSplitChildren) {
  for (const double p : {0.0, 0.5, 1.0}) {
    World world(WorldDef{kH, 7, 0.05});
    const auto stars = world.add_particle_system(parent_system());
    const auto flashes = world.add_particle_system(target_system());
    SubEmitterDef se;
    se.system = flashes;
    se.count = 1;
    se.probability = p;
    world.add_sub_emitter(stars, se);
    for (int k = 0; k < 2000; ++k) world.spawn_particle(stars, Vec3(k, 0, 0), Vec3::Zero(), 1.0, 0.1, 0.05);
    for (int s = 0; s < 10; ++s) world.advance(kH);
    const double n = double(world.emitted_count(flashes));
    EXPECT_NEAR(n, 2000.0 * p, 4.0 * std::sqrt(2000.0 * p * (1.0 - p)) + 1e-9) << "probability " << p;
  }
  for (const bool children_fire : {true, false}) {
    World world(WorldDef{kH, 1, 0.05});
    ParticleSystemDef parent = parent_system();
    parent.emitter.split.enabled = true;
    parent.emitter.split.children = 2;
    parent.emitter.split.age = 0.01;
    parent.emitter.split.depth = 1;
    const auto stars = world.add_particle_system(parent);
    const auto flashes = world.add_particle_system(target_system());
    SubEmitterDef se;
    se.system = flashes;
    se.count = 5;
    se.split_children = children_fire;
    world.add_sub_emitter(stars, se);
    world.spawn_particle(stars, Vec3::Zero(), Vec3(1, 0, 0), 1.0, 0.1, 0.1);
    for (int s = 0; s < 20; ++s) world.advance(kH);
    EXPECT_EQ(world.emitted_count(stars), 3u);  // the parent and its two children
    EXPECT_EQ(world.emitted_count(flashes), children_fire ? 15u : 5u);
  }
}

TEST(SubEmitters, BadDefinitionsAndStaleHandlesAreRefused) {
  World world(WorldDef{kH, 1, 0.05});
  const auto stars = world.add_particle_system(parent_system());
  const auto flashes = world.add_particle_system(target_system());
  SubEmitterDef se;
  se.system = flashes;
  se.count = 0;
  EXPECT_THROW(world.add_sub_emitter(stars, se), std::invalid_argument);
  se.count = 1;
  se.probability = 1.5;
  EXPECT_THROW(world.add_sub_emitter(stars, se), std::invalid_argument);
  se.probability = 1.0;
  se.inherit_velocity = -0.1;
  EXPECT_THROW(world.add_sub_emitter(stars, se), std::invalid_argument);
  se.inherit_velocity = 1.0;
  world.add_sub_emitter(stars, se);
  // A removed target: the sub-emitter is dropped, the parent dies quietly.
  world.remove(flashes);
  EXPECT_THROW(world.add_sub_emitter(stars, se), std::out_of_range);
  world.spawn_particle(stars, Vec3::Zero(), Vec3::Zero(), 1.0, 0.1, 0.01);
  EXPECT_NO_THROW(world.advance(3 * kH));
  EXPECT_EQ(world.particles(stars).count, 0u);
}

}  // namespace
}  // namespace simreel::sim
