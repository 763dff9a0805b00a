// World: handles, validation of definitions, non-finite detection, determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "sim_test_util.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(SimWorld, HandlesNameTheirObjects) {
  World world;
  const auto plane = world.add_plane(PlaneDef{});
  const auto box = world.add_box(BoxDef{});
  const auto ps = world.add_particle_system(test::spawn_only_system("a"));
  const auto ps2 = world.add_particle_system(test::spawn_only_system("b"));
  EXPECT_FALSE(plane.is_null());
  EXPECT_EQ(plane.id.kind, ObjectKind::collider);
  EXPECT_EQ(ps.id.kind, ObjectKind::particle_system);
  EXPECT_NE(plane.id.packed(), box.id.packed());
  EXPECT_NE(ps.id.packed(), plane.id.packed());  // same index, different kind
  EXPECT_EQ(world.definition(ps2).name, "b");
  EXPECT_EQ(world.colliders().size(), 2u);
  EXPECT_EQ(world.colliders()[1], box);
  ASSERT_EQ(world.particle_systems().size(), 2u);
  EXPECT_EQ(world.particle_systems()[0], ps);
  EXPECT_EQ(world.pose(plane).handle, plane.id);
}

TEST(SimWorld, StaleNullAndWrongKindHandlesAreRejected) {
  World world;
  const auto plane = world.add_plane(PlaneDef{});
  const auto ps = world.add_particle_system(test::spawn_only_system());
  EXPECT_THROW((void)world.particles(ParticleSystemHandle{}), std::out_of_range);
  EXPECT_THROW((void)world.pose(ColliderHandle{}), std::out_of_range);
  ParticleSystemHandle stale = ps;
  stale.id.generation = 7;
  EXPECT_THROW((void)world.particles(stale), std::out_of_range);
  EXPECT_THROW((void)world.emitted_count(stale), std::out_of_range);
  ParticleSystemHandle out_of_range = ps;
  out_of_range.id.index = 5;
  EXPECT_THROW((void)world.definition(out_of_range), std::out_of_range);
  // A collider's handle bits smuggled into a particle-system handle.
  const ParticleSystemHandle wrong_kind{plane.id};
  EXPECT_THROW((void)world.particles(wrong_kind), std::out_of_range);
  const ColliderHandle wrong_kind2{ps.id};
  EXPECT_THROW((void)world.pose(wrong_kind2), std::out_of_range);
  EXPECT_THROW(world.spawn_particle(stale, Vec3::Zero(), Vec3::Zero(), 1, 1, 1), std::out_of_range);
  EXPECT_NO_THROW((void)world.particles(ps));
}

TEST(SimWorld, InvalidDefinitionsAreRejected) {
  for (double step : {0.0, -0.01, kNaN, kInf})
    EXPECT_THROW(World(WorldDef{step, 0, 0.05}), std::invalid_argument) << step;
  EXPECT_THROW(World(WorldDef{0.01, 0, -1.0}), std::invalid_argument);

  World world;
  PlaneDef plane;
  plane.normal = Vec3::Zero();
  EXPECT_THROW(world.add_plane(plane), std::invalid_argument);
  for (double e : {-0.1, 1.5, kNaN}) {
    PlaneDef p;
    p.material.restitution = e;
    EXPECT_THROW(world.add_plane(p), std::invalid_argument) << e;
  }
  PlaneDef rough;
  rough.material.friction = -0.2;
  EXPECT_THROW(world.add_plane(rough), std::invalid_argument);
  for (const Vec3& he : {Vec3(1, 0, 1), Vec3(-1, 1, 1), Vec3(1, 1, kNaN)}) {
    BoxDef b;
    b.half_extents = he;
    EXPECT_THROW(world.add_box(b), std::invalid_argument);
  }
  BoxDef bad_material;
  bad_material.material.restitution = 2.0;
  EXPECT_THROW(world.add_box(bad_material), std::invalid_argument);

  auto rejects = [&](auto&& edit, const char* what) {
    ParticleSystemDef d;
    edit(d);
    EXPECT_THROW(world.add_particle_system(d), std::invalid_argument) << what;
  };
  rejects([](ParticleSystemDef& d) { d.emitter.rate = -1.0; }, "negative rate");
  rejects([](ParticleSystemDef& d) { d.emitter.rate = kInf; }, "infinite rate");
  rejects([](ParticleSystemDef& d) { d.emitter.disk_radius = 0.0; }, "zero disk radius");
  rejects([](ParticleSystemDef& d) {
    d.emitter.shape = EmitterShape::quad;
    d.emitter.quad_size = {1.0, 0.0};
  }, "zero quad side");
  rejects([](ParticleSystemDef& d) { d.emitter.color_over_lifetime.clear(); }, "empty gradient");
  rejects([](ParticleSystemDef& d) {
    d.emitter.color_over_lifetime = {ColorKey{0.6, {}}, ColorKey{0.2, {}}};
  }, "gradient out of order");
  rejects([](ParticleSystemDef& d) { d.emitter.color_over_lifetime = {ColorKey{1.5, {}}}; },
          "gradient key beyond 1");
  rejects([](ParticleSystemDef& d) { d.emitter.start_speed.deviation = -1.0; }, "negative deviation");
  rejects([](ParticleSystemDef& d) { d.emitter.lifetime = {1.0, 0.0, 2.0, 1.0}; }, "min > max");
  rejects([](ParticleSystemDef& d) { d.emitter.mass.mean = 0.0; }, "zero mass");
  rejects([](ParticleSystemDef& d) { d.emitter.radius.mean = -0.1; }, "negative radius");
  rejects([](ParticleSystemDef& d) { d.emitter.max_particles = 0; }, "no particles");
  rejects([](ParticleSystemDef& d) { d.drag = -0.5; }, "negative drag");
  rejects([](ParticleSystemDef& d) { d.gravity = Vec3(0, 0, kNaN); }, "NaN gravity");
  rejects([](ParticleSystemDef& d) {
    d.emitter.start_time = 2.0;
    d.emitter.stop_time = 1.0;
  }, "stop before start");
  rejects([](ParticleSystemDef& d) {
    d.emitter.path.keys = {Keyframe{1.0, Vec3::Zero()}, Keyframe{1.0, Vec3::UnitX()}};
  }, "keyframes not increasing");

  const auto ps = world.add_particle_system(test::spawn_only_system());
  EXPECT_THROW(world.spawn_particle(ps, Vec3::Zero(), Vec3::Zero(), 0.0, 0.01, 1.0),
               std::invalid_argument);
  EXPECT_THROW(world.spawn_particle(ps, Vec3::Zero(), Vec3::Zero(), 1.0, -0.01, 1.0),
               std::invalid_argument);
  for (double t : {0.0, -1.0 / 60, kNaN, kInf}) EXPECT_THROW(world.advance(t), std::invalid_argument);
  EXPECT_EQ(world.step_count(), 0u);

  // The message names the field and the value.
  try {
    PlaneDef p;
    p.material.restitution = 1.5;
    world.add_plane(p);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("restitution"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("1.5"), std::string::npos) << e.what();
  }
}

TEST(SimWorld, NonFiniteStateStopsWithSystemStepAndTime) {
  for (const Vec3& bad_v : {Vec3(0, kNaN, 0), Vec3(kInf, 0, 0)}) {
    World world(WorldDef{1.0 / 240, 0, 0.05});
    const auto ok = world.add_particle_system(test::spawn_only_system("calm"));
    const auto ps = world.add_particle_system(test::spawn_only_system("sparks"));
    world.spawn_particle(ok, Vec3::Zero(), Vec3::Zero(), 1.0, 0.01, 10.0);
    world.advance(1.0 / 60);  // 4 good steps
    for (int k = 0; k < 5; ++k) world.spawn_particle(ps, Vec3(k, 0, 0), Vec3::Zero(), 1.0, 0.01, 10.0);
    world.spawn_particle(ps, Vec3::Zero(), bad_v, 1.0, 0.01, 10.0);
    try {
      world.advance(1.0 / 60);
      FAIL() << "no NonFiniteState";
    } catch (const NonFiniteState& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("'sparks'"), std::string::npos) << msg;
      EXPECT_NE(msg.find("id 5"), std::string::npos) << msg;
      EXPECT_NE(msg.find("step 5"), std::string::npos) << msg;
      EXPECT_NE(msg.find("t = 0.0208333"), std::string::npos) << msg;
    }
  }
}

/// A scene with every random draw in play: deviations everywhere, disk and quad, drag, both
/// integrators, a plane and a box.
void build_busy_world(World& world) {
  PlaneDef floor;
  floor.material = {0.6, 0.4};
  world.add_plane(floor);
  BoxDef box;
  box.transform.translation = Vec3(0.5, 0, 0.3);
  box.half_extents = Vec3(0.3, 0.3, 0.3);
  world.add_box(box);
  ParticleSystemDef a;
  a.name = "fountain";
  a.drag = 1e-4;
  a.emitter.rate = 800;
  a.emitter.start_speed = {4.0, 1.0, 0.0};
  a.emitter.spread_deg = {15.0, 10.0, 0.0, 60.0};
  a.emitter.lifetime = {2.0, 0.5, 0.1};
  a.emitter.mass = {1e-3, 2e-4, 1e-4};
  a.emitter.radius = {0.01, 0.003, 0.002};
  a.emitter.color_over_lifetime = {ColorKey{0.0, {1, 1, 0, 1}}, ColorKey{1.0, {0.2, 0.2, 0.2, 0}}};
  world.add_particle_system(a);
  ParticleSystemDef b = a;
  b.name = "rain";
  b.integrator = Integrator::rk4;
  b.emitter.shape = EmitterShape::quad;
  b.emitter.quad_size = {2.0, 2.0};
  b.emitter.transform.translation = Vec3(0, 0, 3);
  b.emitter.transform.rotation = Quat(Eigen::AngleAxisd(3.14159, Vec3::UnitX()));
  world.add_particle_system(b);
}

bool same_state(const World& a, const World& b) {
  const auto sa = a.particle_systems(), sb = b.particle_systems();
  for (std::size_t k = 0; k < sa.size(); ++k) {
    const ParticleView va = a.particles(sa[k]), vb = b.particles(sb[k]);
    if (va.count != vb.count) return false;
    const std::size_t n = va.count;
    if (std::memcmp(va.position, vb.position, 12 * n) || std::memcmp(va.velocity, vb.velocity, 12 * n) ||
        std::memcmp(va.color, vb.color, 16 * n) || std::memcmp(va.radius, vb.radius, 4 * n) ||
        std::memcmp(va.age, vb.age, 4 * n) || std::memcmp(va.lifetime, vb.lifetime, 4 * n) ||
        std::memcmp(va.id, vb.id, 8 * n))
      return false;
  }
  return true;
}

TEST(SimWorld, SameSeedGivesBitIdenticalStateAndAnotherSeedDoesNot) {
  World a(WorldDef{1.0 / 240, 1234, 0.05}), b(WorldDef{1.0 / 240, 1234, 0.05}),
      c(WorldDef{1.0 / 240, 1235, 0.05});
  build_busy_world(a);
  build_busy_world(b);
  build_busy_world(c);
  for (int f = 0; f < 120; ++f) {
    a.advance(1.0 / 60);
    b.advance(1.0 / 60);
    c.advance(1.0 / 60);
  }
  EXPECT_GT(a.particles(a.particle_systems()[0]).count, 1000u);
  EXPECT_TRUE(same_state(a, b));
  EXPECT_FALSE(same_state(a, c));
  // Moving a world keeps its state.
  World moved = std::move(a);
  moved.advance(1.0 / 60);
  b.advance(1.0 / 60);
  EXPECT_TRUE(same_state(moved, b));
}

}  // namespace
}  // namespace simreel::sim
