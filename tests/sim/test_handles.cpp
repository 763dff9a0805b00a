// Handles, removal and the state hash: generational handles from an id pool (stale and null
// handles rejected everywhere), removal of every kind mid-run (the rest goes on exactly as in a
// world that never held the removed object), removals in the moved list, World::state_hash.
#include <gtest/gtest.h>

#include <cstring>
#include <stdexcept>
#include <vector>

#include "core/id_pool.hpp"
#include "sim_test_util.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

ParticleSystemDef fountain(const char* name) {
  ParticleSystemDef d;
  d.name = name;
  d.emitter.rate = 300.0;
  d.emitter.max_particles = 2000;
  d.emitter.start_speed = {3.0, 0.5};
  d.emitter.lifetime = {1.5, 0.3, 0.1, 10.0};
  return d;
}

ClothDef small_cloth(double z) {
  ClothDef d;
  d.rows = d.columns = 6;
  d.transform.translation = Vec3(0, 0, z);
  d.wind.gust_amplitude = 2.0;  // the gust noise is keyed by the cloth's registration serial
  d.wind.velocity = Vec3(1, 0, 0);
  return d;
}

/// Bitwise equality of two views (count, positions, velocities, colours, ids).
void expect_same(const ParticleView& a, const ParticleView& b) {
  ASSERT_EQ(a.count, b.count);
  ASSERT_GT(a.count, 0u);
  EXPECT_EQ(std::memcmp(a.position, b.position, 3 * a.count * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(a.velocity, b.velocity, 3 * a.count * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(a.color, b.color, 4 * a.count * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(a.id, b.id, a.count * sizeof(std::uint64_t)), 0);
}

/// One object of every kind (the attractor spring pulls the system).
struct OneOfEach {
  ParticleSystemHandle ps;
  ColliderHandle box;
  ClothHandle cloth;
  ForceFieldHandle field;
  AttractorSpringHandle spring;

  explicit OneOfEach(World& world)
      : ps(world.add_particle_system(test::spawn_only_system())),
        box(world.add_box({})),
        cloth(world.add_cloth(small_cloth(1.0))),
        field(world.add_force_field({})) {
    AttractorSpringDef a;
    a.system = ps;
    spring = world.add_attractor_spring(a);
  }
  void remove_from(World& world) const {
    world.remove(spring);
    world.remove(field);
    world.remove(cloth);
    world.remove(box);
    world.remove(ps);
  }
};

TEST(IdPool, ReusesFreedSlotsWithABumpedGeneration) {
  detail::IdPool pool;
  const auto a = pool.alloc(), b = pool.alloc();
  EXPECT_EQ(a.index, 0u);
  EXPECT_EQ(b.index, 1u);
  EXPECT_EQ(a.generation, 1u);
  pool.free(a.index);
  EXPECT_FALSE(pool.valid(a.index, a.generation));  // stale at once, before any reuse
  const auto c = pool.alloc();
  EXPECT_EQ(c.index, a.index);
  EXPECT_EQ(c.generation, 2u);
  EXPECT_TRUE(pool.valid(c.index, c.generation));
  EXPECT_FALSE(pool.valid(a.index, a.generation));
  EXPECT_FALSE(pool.valid(0, 0));  // null
  EXPECT_FALSE(pool.valid(7, 1));  // never allocated
}

TEST(Handles, AddRemoveReAddEveryKind) {
  World world;
  for (int round = 0; round < 3; ++round) {
    const OneOfEach o(world);
    for (const Handle& h : {o.ps.id, o.box.id, o.cloth.id, o.field.id, o.spring.id}) {
      EXPECT_EQ(h.index, 0u);  // the one slot of each kind is reused
      EXPECT_EQ(h.generation, round + 1);
    }
    EXPECT_EQ(world.particle_systems().size(), 1u);
    EXPECT_EQ(world.colliders().size(), 1u);
    EXPECT_EQ(world.cloths().size(), 1u);
    world.advance(1.0 / 60);
    o.remove_from(world);
    EXPECT_TRUE(world.particle_systems().empty());
    EXPECT_TRUE(world.colliders().empty());
    EXPECT_TRUE(world.cloths().empty());
  }
}

TEST(Handles, StaleAndNullHandlesAreRejectedEverywhere) {
  World world;
  const OneOfEach old(world);
  old.remove_from(world);
  // Reuse every slot: the old handles must stay stale (generation bumped), not alias the new.
  const OneOfEach fresh(world);
  const auto [ps, box, cloth, field, spring] = old;
  const auto [ps2, box2, cloth2, field2, spring2] = fresh;
  EXPECT_EQ(ps2.id.index, ps.id.index);
  EXPECT_NE(ps2, ps);
  EXPECT_NE(box2, box);
  EXPECT_NE(cloth2, cloth);
  EXPECT_NE(field2, field);
  EXPECT_NE(spring2, spring);

  for (const ParticleSystemHandle h : {ps, ParticleSystemHandle{}}) {
    EXPECT_THROW((void)world.particles(h), std::out_of_range);
    EXPECT_THROW((void)world.definition(h), std::out_of_range);
    EXPECT_THROW((void)world.emitted_count(h), std::out_of_range);
    EXPECT_THROW((void)world.removed_inside_count(h), std::out_of_range);
    EXPECT_THROW((void)world.integrator_steps(h), std::out_of_range);
    EXPECT_THROW((void)world.rejected_steps(h), std::out_of_range);
    EXPECT_THROW(world.spawn_particle(h, Vec3::Zero(), Vec3::Zero(), 1.0, 0.1, 1.0), std::out_of_range);
    EXPECT_THROW(world.add_spring(h, SpringDef{}), std::out_of_range);
    AttractorSpringDef on_stale;
    on_stale.system = h;
    EXPECT_THROW(world.add_attractor_spring(on_stale), std::out_of_range);
    ForceFieldDef f;
    f.systems = {h};
    EXPECT_THROW(world.add_force_field(f), std::out_of_range);
    EXPECT_THROW(world.remove(h), std::out_of_range);
  }
  for (const ColliderHandle h : {box, ColliderHandle{}}) {
    EXPECT_THROW((void)world.pose(h), std::out_of_range);
    EXPECT_THROW(world.remove(h), std::out_of_range);
  }
  for (const ClothHandle h : {cloth, ClothHandle{}}) {
    EXPECT_THROW((void)world.cloth(h), std::out_of_range);
    EXPECT_THROW((void)world.cloth_stats(h), std::out_of_range);
    EXPECT_THROW((void)world.definition(h), std::out_of_range);
    EXPECT_THROW(world.remove(h), std::out_of_range);
  }
  EXPECT_THROW(world.remove(field), std::out_of_range);
  EXPECT_THROW(world.remove(ForceFieldHandle{}), std::out_of_range);
  EXPECT_THROW(world.remove(spring), std::out_of_range);
  EXPECT_THROW(world.remove(AttractorSpringHandle{}), std::out_of_range);
  // The new objects are untouched by all of this.
  EXPECT_NO_THROW((void)world.particles(ps2));
  EXPECT_NO_THROW((void)world.pose(box2));
  EXPECT_NO_THROW((void)world.cloth(cloth2));
  EXPECT_NO_THROW(world.remove(spring2));
  EXPECT_NO_THROW(world.remove(field2));
}

// Two independent particle systems; one is removed mid-run. The other's state must be
// bit-identical to a world that only ever simulated it. Its random streams are keyed by its
// registration serial, so the reference world registers (and at once removes) a placeholder
// where the removed system had its serial.
void removal_leaves_the_other_system_alone(bool remove_first) {
  WorldDef wd;
  wd.seed = 42;
  PlaneDef floor;
  World a(wd), b(wd);
  a.add_plane(floor);
  b.add_plane(floor);
  ParticleSystemHandle gone, kept;
  if (remove_first) {
    gone = a.add_particle_system(fountain("gone"));
    kept = a.add_particle_system(fountain("kept"));
    b.remove(b.add_particle_system(fountain("placeholder")));  // serial 0, never simulated
  } else {
    kept = a.add_particle_system(fountain("kept"));
    gone = a.add_particle_system(fountain("gone"));
  }
  const auto alone = b.add_particle_system(fountain("kept"));
  for (int f = 0; f < 20; ++f) {
    a.advance(1.0 / 60);
    b.advance(1.0 / 60);
  }
  a.remove(gone);
  for (int f = 0; f < 40; ++f) {
    a.advance(1.0 / 60);
    b.advance(1.0 / 60);
  }
  expect_same(a.particles(kept), b.particles(alone));
  EXPECT_EQ(a.emitted_count(kept), b.emitted_count(alone));
  EXPECT_EQ(a.state_hash(), b.state_hash());  // same objects, same state
}

TEST(Removal, ParticleSystemMidRunLastInTheArray) { removal_leaves_the_other_system_alone(false); }
TEST(Removal, ParticleSystemMidRunSwappedIntoItsPlace) { removal_leaves_the_other_system_alone(true); }

TEST(Removal, ColliderClothFieldAndSpringMidRun) {
  // World a holds extra objects that never touch the kept system and cloth (a sphere far away,
  // a cloth far away, a field and an attractor on another system) and removes them mid-run.
  WorldDef wd;
  wd.seed = 7;
  World a(wd), b(wd);
  PlaneDef floor;
  a.add_plane(floor);
  b.add_plane(floor);
  SphereDef far;
  far.transform.translation = Vec3(100, 0, 0);
  const auto sphere = a.add_sphere(far);
  const auto kept_cloth = a.add_cloth(small_cloth(2.0));
  const auto other_cloth = a.add_cloth(small_cloth(50.0));
  const auto kept = a.add_particle_system(fountain("kept"));
  auto other_def = test::spawn_only_system("other");
  const auto other = a.add_particle_system(other_def);
  ForceFieldDef wind;
  wind.acceleration = Vec3(5, 0, 0);
  wind.systems = {other};
  const auto field = a.add_force_field(wind);
  AttractorSpringDef pull;
  pull.system = other;
  const auto spring = a.add_attractor_spring(pull);

  const auto b_cloth = b.add_cloth(small_cloth(2.0));
  const auto b_kept = b.add_particle_system(fountain("kept"));
  for (int f = 0; f < 15; ++f) {
    a.advance(1.0 / 60);
    b.advance(1.0 / 60);
  }
  a.remove(sphere);
  a.remove(other_cloth);
  a.remove(spring);
  a.remove(field);
  a.remove(other);
  for (int f = 0; f < 30; ++f) {
    a.advance(1.0 / 60);
    b.advance(1.0 / 60);
  }
  expect_same(a.particles(kept), b.particles(b_kept));
  const ClothView ca = a.cloth(kept_cloth), cb = b.cloth(b_cloth);
  ASSERT_EQ(ca.vertex_count, cb.vertex_count);
  EXPECT_EQ(std::memcmp(ca.positions, cb.positions, 3 * ca.vertex_count * sizeof(float)), 0);
  EXPECT_EQ(a.state_hash(), b.state_hash());
}

TEST(Removal, FieldAndAttractorStopActing) {
  World world;
  auto def = test::spawn_only_system();
  def.gravity = Vec3::Zero();
  const auto ps = world.add_particle_system(def);
  world.spawn_particle(ps, Vec3::Zero(), Vec3::Zero(), 1.0, 0.01, 100.0);
  ForceFieldDef push;
  push.acceleration = Vec3(1, 0, 0);
  const auto field = world.add_force_field(push);
  AttractorSpringDef pull;
  pull.system = ps;
  pull.anchor = Vec3(0, 5, 0);
  pull.stiffness = 2.0;
  const auto spring = world.add_attractor_spring(pull);
  world.advance(0.1);
  world.remove(field);
  world.remove(spring);
  world.advance(0.1);
  const Vec3 v = test::velocity_of(world.particles(ps), 0);
  EXPECT_GT(v.x(), 0.0);
  EXPECT_GT(v.y(), 0.0);
  world.advance(0.5);  // free flight now: the velocity no longer changes
  EXPECT_EQ(test::velocity_of(world.particles(ps), 0), v);
}

TEST(Removal, AFieldLosesItsOnlySystemAndActsOnNone) {
  World world;
  auto def = test::spawn_only_system();
  def.gravity = Vec3::Zero();
  const auto first = world.add_particle_system(def);
  ForceFieldDef push;
  push.acceleration = Vec3(1, 0, 0);
  push.systems = {first};
  world.add_force_field(push);
  world.remove(first);
  const auto later = world.add_particle_system(def);  // not named by the field
  world.spawn_particle(later, Vec3::Zero(), Vec3::Zero(), 1.0, 0.01, 100.0);
  world.advance(0.5);
  EXPECT_EQ(test::velocity_of(world.particles(later), 0), Vec3::Zero());
}

TEST(Removal, FloorUnderARestingPileWithWarmStartedContacts) {
  World world;
  const auto floor = world.add_plane({});
  auto def = test::spawn_only_system();
  def.collide_particles = true;
  const auto ps = world.add_particle_system(def);
  for (int i = 0; i < 5; ++i)
    world.spawn_particle(ps, Vec3(0.001 * i, 0, 0.05 + 0.1 * i), Vec3::Zero(), 0.01, 0.05, 100.0);
  for (int f = 0; f < 60; ++f) world.advance(1.0 / 60);
  EXPECT_GT(test::position_of(world.particles(ps), 0).z(), 0.0);
  world.remove(floor);  // the warm-start cache held contacts against collider 0
  world.add_box({});    // another collider takes index 0; stale cached impulses must not apply
  for (int f = 0; f < 60; ++f) world.advance(1.0 / 60);
  const ParticleView v = world.particles(ps);
  for (std::size_t i = 0; i < v.count; ++i) EXPECT_TRUE(test::position_of(v, i).allFinite());
}

TEST(Removal, TheMovedListCarriesARemovalOnce) {
  World world;
  BoxDef moving;
  moving.path.keys = {Keyframe{0.0, Vec3::Zero()}, Keyframe{10.0, Vec3(10, 0, 0)}};
  const auto box = world.add_box(moving);
  const auto still = world.add_sphere({});
  const auto ps = world.add_particle_system(test::spawn_only_system());
  const auto& first = world.advance(1.0 / 60);
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(first[0].handle, box.id);
  EXPECT_FALSE(first[0].removed);
  world.remove(still);
  world.remove(ps);
  const auto& second = world.advance(1.0 / 60);
  ASSERT_EQ(second.size(), 3u);
  EXPECT_EQ(second[0].handle, box.id);  // moved entries first
  EXPECT_FALSE(second[0].removed);
  EXPECT_EQ(second[1].handle, still.id);
  EXPECT_TRUE(second[1].removed);
  EXPECT_EQ(second[2].handle, ps.id);
  EXPECT_TRUE(second[2].removed);
  world.remove(box);
  const auto& third = world.advance(1.0 / 60);
  ASSERT_EQ(third.size(), 1u);  // a removed body does not move any more
  EXPECT_EQ(third[0].handle, box.id);
  EXPECT_TRUE(third[0].removed);
  EXPECT_TRUE(world.advance(1.0 / 60).empty());
}

TEST(StateHash, SameWorldSameHashOneParticleNudgedDifferent) {
  auto build = [](float nudge) {
    auto w = std::make_unique<World>(WorldDef{});
    w->add_plane({});
    const auto ps = w->add_particle_system(fountain("f"));
    w->add_cloth(small_cloth(1.0));
    w->spawn_particle(ps, Vec3(0, 0, 1.0 + nudge), Vec3::Zero(), 0.01, 0.02, 10.0);
    for (int f = 0; f < 10; ++f) w->advance(1.0 / 60);
    return w;
  };
  const auto a = build(0.0f), b = build(0.0f), c = build(1e-6f);
  EXPECT_EQ(a->state_hash(), b->state_hash());
  EXPECT_NE(a->state_hash(), c->state_hash());
  const std::uint64_t before = a->state_hash();
  a->advance(1.0 / 60);
  EXPECT_NE(a->state_hash(), before);
}

}  // namespace
}  // namespace simreel::sim
