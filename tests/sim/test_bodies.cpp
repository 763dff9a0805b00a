// Bodies apart from shapes (body.hpp): World::add_body with several shapes at offsets, kinematic
// bodies whose shapes all follow the path and are reported once, removal of every shape with one
// report, stale handles, one-shape bodies bit-identical to the single-collider wrappers, and the
// rejection of invalid definitions naming the field.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "sim_test_util.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

using test::position_of;
using test::velocity_of;

constexpr double kR = 0.01;  // particle radius (m)

Material bouncy() { return Material(1.0, 0.0); }

ParticleSystemDef probes(bool gravity) {
  ParticleSystemDef def = test::spawn_only_system();
  if (!gravity) def.gravity = Vec3::Zero();
  return def;
}

Transform at(const Vec3& t, const Quat& q = Quat::Identity()) { return Transform{t, q}; }

Quat about_z(double deg) {
  return Quat(Eigen::AngleAxisd(deg * std::numbers::pi / 180.0, Vec3::UnitZ()));
}

/// Two spheres of radius 0.2 at ±0.5 m along the body's x axis, elastic, frictionless.
BodyDef dumbbell() {
  BodyDef b;
  b.name = "dumbbell";
  for (double x : {-0.5, 0.5}) {
    b.shapes.push_back(ShapeDef::sphere(0.2, at(Vec3(x, 0, 0))));
    b.shapes.back().material = bouncy();
  }
  return b;
}

/// Drops probes straight down at 5 m/s (no gravity) from z = 1 at each (x, y); after `t` seconds
/// a probe that hit a surface at height z_top (top of a shape + kR) moves up at 5 m/s.
std::vector<double> vertical_speeds_after(World& world, const std::vector<Vec3>& xy, double t) {
  const auto ps = world.add_particle_system(probes(false));
  for (const Vec3& p : xy) world.spawn_particle(ps, Vec3(p.x(), p.y(), 1.0), Vec3(0, 0, -5), 0.01, kR, 100);
  for (int f = 0; f < int(std::lround(t * 60)); ++f) world.advance(1.0 / 60);
  std::vector<double> vz;
  const ParticleView v = world.particles(ps);
  for (std::size_t i = 0; i < v.count; ++i) vz.push_back(velocity_of(v, i).z());
  return vz;
}

TEST(Bodies, TwoShapeBodyCollidesAtBothShapesWorldPositions) {
  // The body is turned 90 degrees about z and moved to (1, 0, 0): its spheres sit at
  // (1, -0.5, 0) and (1, 0.5, 0). Probes over them bounce; probes over the untransformed offsets
  // (1 ± 0.5, 0) and between the spheres fall through.
  World world;
  BodyDef b = dumbbell();
  b.pose = at(Vec3(1, 0, 0), about_z(90));
  const BodyHandle h = world.add_body(b);
  const std::vector<double> vz = vertical_speeds_after(
      world, {Vec3(1, -0.5, 0), Vec3(1, 0.5, 0), Vec3(0.5, 0, 0), Vec3(1.5, 0, 0), Vec3(1, 0, 0)},
      0.5);
  ASSERT_EQ(vz.size(), 5u);
  EXPECT_NEAR(vz[0], 5.0, 1e-5);
  EXPECT_NEAR(vz[1], 5.0, 1e-5);
  for (int i = 2; i < 5; ++i) EXPECT_NEAR(vz[std::size_t(i)], -5.0, 1e-5) << i;
  // The body's pose is its frame, not either shape's.
  const MovedObject p = world.pose(h);
  EXPECT_EQ(p.translation, Vec3(1, 0, 0));
  EXPECT_LT((p.rotation - about_z(90).toRotationMatrix()).norm(), 1e-15);
}

TEST(Bodies, BoxWithASphereOnTopHitsAtTheSphereTopAtTheAnalyticTime) {
  // A box (half height 0.1) with a sphere of radius 0.1 whose centre is 0.2 above it: a probe
  // over the sphere turns at z = 0.3 + kR, one over the box's edge region at z = 0.1 + kR.
  World world;
  BodyDef b;
  b.shapes.push_back(ShapeDef::box(Vec3(0.5, 0.5, 0.1)));
  b.shapes.push_back(ShapeDef::sphere(0.1, at(Vec3(0, 0, 0.2))));
  for (ShapeDef& s : b.shapes) s.material = bouncy();
  world.add_body(b);
  const auto ps = world.add_particle_system(probes(false));
  world.spawn_particle(ps, Vec3(0, 0, 1), Vec3(0, 0, -5), 0.01, kR, 100);
  world.spawn_particle(ps, Vec3(0.4, 0, 1), Vec3(0, 0, -5), 0.01, kR, 100);
  world.advance(0.2);  // both have turned: (1 - 0.31) / 5 = 0.138 s, (1 - 0.11) / 5 = 0.178 s
  const ParticleView v = world.particles(ps);
  EXPECT_NEAR(position_of(v, 0).z(), 0.31 + 5.0 * (0.2 - 0.69 / 5), 1e-5);
  EXPECT_NEAR(position_of(v, 1).z(), 0.11 + 5.0 * (0.2 - 0.89 / 5), 1e-5);
}

TEST(Bodies, KinematicMultiShapeBodyMovesEveryShapeAndIsReportedOnce) {
  // Two plates at ±1 m along x lift by 0.5 m in 1 s; a probe resting on each is carried.
  World world;
  BodyDef b;
  b.type = BodyType::kinematic;
  b.path.smooth = false;
  b.path.keys = {Keyframe{0.0, Vec3::Zero(), Quat::Identity()},
                 Keyframe{1.0, Vec3(0, 0, 0.5), Quat::Identity()}};
  for (double x : {-1.0, 1.0}) {
    b.shapes.push_back(ShapeDef::box(Vec3(0.4, 0.4, 0.05), at(Vec3(x, 0, 0))));
    b.shapes.back().material = Material(0.0, 0.5);
  }
  const BodyHandle h = world.add_body(b);
  const auto ps = world.add_particle_system(probes(true));
  world.spawn_particle(ps, Vec3(-1, 0, 0.05 + kR), Vec3::Zero(), 0.01, kR, 100);
  world.spawn_particle(ps, Vec3(1.2, 0, 0.05 + kR), Vec3::Zero(), 0.01, kR, 100);
  for (int f = 1; f <= 60; ++f) {
    const std::vector<MovedObject>& moved = world.advance(1.0 / 60);
    ASSERT_EQ(moved.size(), 1u) << f;  // one entry for the body, not one per shape
    EXPECT_EQ(moved[0].handle, h.id);
    EXPECT_NEAR(moved[0].translation.z(), 0.5 * f / 60.0, 1e-12);
    EXPECT_EQ(moved[0].translation.x(), 0.0);  // the body origin, between the shapes
  }
  const ParticleView v = world.particles(ps);
  EXPECT_NEAR(position_of(v, 0).z(), 0.55 + kR, 2e-3);
  EXPECT_NEAR(position_of(v, 1).z(), 0.55 + kR, 2e-3);
  EXPECT_NEAR(position_of(v, 1).x(), 1.2, 1e-5);
  world.advance(1.0 / 60);  // the path has ended: the body no longer moves
  EXPECT_TRUE(world.advance(1.0 / 60).empty());
}

TEST(Bodies, TurningKinematicBodyCarriesItsOffsetShapeAround) {
  // A sphere 1 m along the body's x axis; the body turns 90 degrees about z in 1 s, so the
  // sphere ends at (0, 1, 0). A probe dropped there then bounces; one over (1, 0, 0) falls.
  World world;
  BodyDef b;
  b.type = BodyType::kinematic;
  b.path.smooth = false;
  b.path.keys = {Keyframe{0.0, Vec3::Zero(), Quat::Identity()}, Keyframe{1.0, Vec3::Zero(), about_z(90)}};
  b.shapes.push_back(ShapeDef::sphere(0.2, at(Vec3(1, 0, 0))));
  b.shapes.back().material = bouncy();
  world.add_body(b);
  world.advance(1.0);
  const std::vector<double> vz = vertical_speeds_after(world, {Vec3(0, 1, 0), Vec3(1, 0, 0)}, 0.5);
  ASSERT_EQ(vz.size(), 2u);
  EXPECT_NEAR(vz[0], 5.0, 1e-5);
  EXPECT_NEAR(vz[1], -5.0, 1e-5);
}

TEST(Bodies, RemovingAMultiShapeBodyStopsEveryShapeAndReportsOnce) {
  World world;
  const BodyHandle first = world.add_sphere(SphereDef{at(Vec3(3, 0, 0)), 0.2, {}, bouncy()});
  const BodyHandle h = world.add_body(dumbbell());
  const BodyHandle last = world.add_sphere(SphereDef{at(Vec3(-3, 0, 0)), 0.2, {}, bouncy()});
  world.advance(1.0 / 60);
  world.remove(h);
  const std::vector<MovedObject>& moved = world.advance(1.0 / 60);
  ASSERT_EQ(moved.size(), 1u);
  EXPECT_EQ(moved[0].handle, h.id);
  EXPECT_TRUE(moved[0].removed);
  EXPECT_EQ(world.colliders().size(), 2u);
  // The stale handle is rejected; the other bodies keep theirs and still collide.
  EXPECT_THROW((void)world.pose(h), std::out_of_range);
  EXPECT_THROW(world.remove(h), std::out_of_range);
  EXPECT_EQ(world.pose(first).translation, Vec3(3, 0, 0));
  EXPECT_EQ(world.pose(last).translation, Vec3(-3, 0, 0));
  const std::vector<double> vz = vertical_speeds_after(
      world, {Vec3(-0.5, 0, 0), Vec3(0.5, 0, 0), Vec3(3, 0, 0), Vec3(-3, 0, 0)}, 0.5);
  ASSERT_EQ(vz.size(), 4u);
  EXPECT_NEAR(vz[0], -5.0, 1e-5);
  EXPECT_NEAR(vz[1], -5.0, 1e-5);
  EXPECT_NEAR(vz[2], 5.0, 1e-5);
  EXPECT_NEAR(vz[3], 5.0, 1e-5);
  // A new body may take the slot: the old handle stays stale.
  const BodyHandle again = world.add_body(dumbbell());
  EXPECT_EQ(again.id.index, h.id.index);
  EXPECT_NE(again.id.generation, h.id.generation);
  EXPECT_THROW((void)world.pose(h), std::out_of_range);
  EXPECT_THROW((void)world.pose(BodyHandle{}), std::out_of_range);
}

TEST(Bodies, RestingContactsFollowTheShapesWhenAnEarlierBodyIsRemoved) {
  // Particles rest (warm-started contacts, keyed by shape index) on the second shape of a body
  // registered after another; removing the first body moves the shapes down the array. The pile
  // must stay where it is, as in a world that never held the removed body.
  auto run = [](bool with_extra) {
    World world;
    BodyHandle extra;
    if (with_extra) extra = world.add_sphere(SphereDef{at(Vec3(10, 0, 0)), 0.2, {}, {}});
    BodyDef b;
    b.shapes.push_back(ShapeDef::box(Vec3(0.5, 0.5, 0.1), at(Vec3(-2, 0, 0))));
    b.shapes.push_back(ShapeDef::box(Vec3(0.5, 0.5, 0.1)));
    world.add_body(b);
    ParticleSystemDef def = probes(true);
    def.collide_particles = true;
    const auto ps = world.add_particle_system(def);
    for (int i = 0; i < 5; ++i)
      world.spawn_particle(ps, Vec3(0.001 * i, 0, 0.15 + 0.1 * i), Vec3::Zero(), 0.01, 0.05, 100);
    for (int f = 0; f < 60; ++f) world.advance(1.0 / 60);
    if (with_extra) world.remove(extra);
    for (int f = 0; f < 60; ++f) world.advance(1.0 / 60);
    return world.state_hash();
  };
  EXPECT_EQ(run(true), run(false));
}

// ---------------------------------------------------------------------------------------------
// One-shape bodies are the single colliders, bit for bit

/// Rain on every kind of collider, a kinematic turning one included, built by `build`.
template <class Build>
std::uint64_t rain_hash(Build build, std::vector<MovedObject>* poses = nullptr) {
  WorldDef wd;
  wd.seed = 3;
  World world(wd);
  const std::vector<BodyHandle> bodies = build(world);
  ParticleSystemDef rain;
  rain.emitter.rate = 400.0;
  rain.emitter.max_particles = 4000;
  rain.emitter.transform.translation = Vec3(0, 0, 2.0);
  rain.emitter.start_speed = {1.0, 0.5};
  rain.emitter.spread_deg = {60.0, 20.0, 0.0, 180.0};
  rain.emitter.disk_radius = 0.8;
  rain.collide_particles = true;
  world.add_particle_system(rain);
  for (int f = 0; f < 90; ++f)
    for (const MovedObject& m : world.advance(1.0 / 60))
      if (poses != nullptr) poses->push_back(m);
  if (poses != nullptr)
    for (const BodyHandle& h : bodies) poses->push_back(world.pose(h));
  return world.state_hash();
}

KeyframePath turning_path() {
  KeyframePath p;
  p.keys = {Keyframe{0.0, Vec3(0.3, 0, 0.4), Quat::Identity()},
            Keyframe{1.0, Vec3(-0.3, 0.1, 0.5), Quat(Eigen::AngleAxisd(1.0, Vec3(1, 2, 3).normalized()))}};
  return p;
}

TEST(Bodies, OneShapeAddBodyEqualsTheWrappersBitForBit) {
  PlaneDef plane{Vec3(0, 0, -0.2), Vec3(0.1, 0, 1), Material(0.4, 0.3)};
  BoxDef box;
  box.transform = at(Vec3(0.6, 0, 0.1), about_z(20));
  box.half_extents = Vec3(0.2, 0.3, 0.1);
  box.material = Material(0.2, 0.6);
  SphereDef sphere;
  sphere.radius = 0.25;
  sphere.path = turning_path();
  sphere.material = Material(0.7, 0.1);
  CylinderDef cyl;
  cyl.transform = at(Vec3(-0.6, 0.2, 0.1), Quat(0.9, 0.1, 0.2, 0.3));  // not normalised
  cyl.radius = 0.15;
  cyl.half_height = 0.3;
  cyl.material = Material(0.1, 0.9);
  MeshDef mesh;
  mesh.vertices = {Vec3(-1, -1, 0), Vec3(1, -1, 0), Vec3(0, 1, 0.2)};
  mesh.triangles = {{0, 1, 2}};
  mesh.transform = at(Vec3(0, -0.8, -0.1));
  mesh.material = Material(0.9, 0.0);

  std::vector<MovedObject> old_poses, new_poses;
  const std::uint64_t old_hash = rain_hash(
      [&](World& w) {
        return std::vector<BodyHandle>{w.add_plane(plane), w.add_box(box), w.add_sphere(sphere),
                                       w.add_cylinder(cyl), w.add_mesh(mesh)};
      },
      &old_poses);
  const std::uint64_t new_hash = rain_hash(
      [&](World& w) {
        auto body = [](const ShapeDef& s, const Material& m, const Transform& pose) {
          BodyDef b;
          b.pose = pose;
          b.shapes = {s};
          b.shapes[0].material = m;
          return b;
        };
        ShapeDef m;
        m.type = ShapeType::mesh;
        m.vertices = mesh.vertices;
        m.triangles = mesh.triangles;
        BodyDef moving = body(ShapeDef::sphere(0.25), sphere.material, {});
        moving.type = BodyType::kinematic;
        moving.path = turning_path();
        return std::vector<BodyHandle>{
            w.add_body(body(ShapeDef::plane(plane.normal), plane.material, at(plane.point))),
            w.add_body(body(ShapeDef::box(box.half_extents), box.material, box.transform)),
            w.add_body(moving),
            w.add_body(body(ShapeDef::cylinder(0.15, 0.3), cyl.material, cyl.transform)),
            w.add_body(body(m, mesh.material, mesh.transform))};
      },
      &new_poses);
  EXPECT_EQ(old_hash, new_hash);
  ASSERT_EQ(old_poses.size(), new_poses.size());
  ASSERT_EQ(old_poses.size(), 60u + 5u);  // the kinematic sphere moved every frame of its path
  for (std::size_t i = 0; i < old_poses.size(); ++i) {
    EXPECT_EQ(old_poses[i].handle, new_poses[i].handle) << i;
    EXPECT_EQ(old_poses[i].translation, new_poses[i].translation) << i;
    EXPECT_EQ(old_poses[i].rotation, new_poses[i].rotation) << i;
  }
  // And the hash sees the colliders: a world without the box differs.
  EXPECT_NE(old_hash, rain_hash([&](World& w) {
              return std::vector<BodyHandle>{w.add_plane(plane), w.add_sphere(sphere),
                                             w.add_cylinder(cyl), w.add_mesh(mesh)};
            }));
}

// ---------------------------------------------------------------------------------------------
// Invalid definitions

std::string message_of(const BodyDef& def) {
  World world;
  try {
    world.add_body(def);
  } catch (const std::invalid_argument& e) {
    EXPECT_TRUE(world.colliders().empty()) << "a rejected body must leave the world unchanged";
    return e.what();
  }
  return "(no exception)";
}

void expect_rejected(const BodyDef& def, const std::string& names) {
  const std::string m = message_of(def);
  EXPECT_NE(m.find(names), std::string::npos) << "expected '" << names << "' in: " << m;
}

TEST(Bodies, InvalidDefinitionsAreRejectedNamingTheField) {
  BodyDef none;
  expect_rejected(none, "BodyDef.shapes must hold at least one shape");

  BodyDef dynamic = dumbbell();
  dynamic.type = BodyType::dynamic;
  dynamic.shapes[0].density = -1.0;
  expect_rejected(dynamic, "BodyDef.shapes[0].density must be > 0");

  BodyDef conveyor = dumbbell();
  conveyor.linear_velocity = Vec3(1, 0, 0);
  expect_rejected(conveyor, "BodyDef.linear_velocity must be zero for a static body");
  BodyDef spinning = dumbbell();
  spinning.angular_velocity = Vec3(0, 0, 1);
  expect_rejected(spinning, "BodyDef.angular_velocity must be zero for a static body");

  BodyDef pathless = dumbbell();
  pathless.type = BodyType::kinematic;
  expect_rejected(pathless, "BodyDef.path must not be empty for a kinematic body");
  BodyDef pushed = dumbbell();
  pushed.type = BodyType::kinematic;
  pushed.path = turning_path();
  pushed.linear_velocity = Vec3(0, 1, 0);
  expect_rejected(pushed, "BodyDef.linear_velocity must be zero for a kinematic body");
  BodyDef static_path = dumbbell();
  static_path.path = turning_path();
  expect_rejected(static_path, "BodyDef.path must be empty for a static body");

  BodyDef damped = dumbbell();
  damped.linear_damping = -1.0;
  expect_rejected(damped, "BodyDef.linear_damping");

  BodyDef small = dumbbell();
  small.shapes[1].radius = 0.0;
  expect_rejected(small, "BodyDef.shapes[1].radius");
  BodyDef flat = dumbbell();
  flat.shapes.push_back(ShapeDef::box(Vec3(1, 1, -1)));
  expect_rejected(flat, "BodyDef.shapes[2].half_extents[2]");
  BodyDef pill = dumbbell();
  pill.shapes[0] = ShapeDef::capsule(0.1, std::nan(""));
  expect_rejected(pill, "BodyDef.shapes[0].half_height");
  BodyDef slippery = dumbbell();
  slippery.shapes[1].material.restitution = 1.5;
  expect_rejected(slippery, "BodyDef.shapes[1].material.restitution");
  BodyDef offset = dumbbell();
  offset.shapes[0].offset.translation.x() = INFINITY;
  expect_rejected(offset, "BodyDef.shapes[0].offset");
  BodyDef mesh;
  mesh.shapes.emplace_back();
  mesh.shapes[0].type = ShapeType::mesh;
  mesh.shapes[0].vertices = {Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY()};
  mesh.shapes[0].triangles = {{0, 1, 3}};
  expect_rejected(mesh, "BodyDef.shapes[0].triangles[0] refers to vertex 3 of 3");

  BodyDef moving_plane;
  moving_plane.type = BodyType::kinematic;
  moving_plane.path = turning_path();
  moving_plane.shapes = {ShapeDef::plane()};
  expect_rejected(moving_plane, "BodyDef.shapes[0]: a plane may only belong to a static body");
  BodyDef no_normal;
  no_normal.shapes = {ShapeDef::plane(Vec3::Zero())};
  expect_rejected(no_normal, "BodyDef.shapes[0].normal must be finite and non-zero");

  // The wrappers keep naming their own definitions.
  World world;
  try {
    world.add_sphere(SphereDef{{}, -1.0, {}, {}});
    ADD_FAILURE() << "negative radius accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("SphereDef.radius"), std::string::npos) << e.what();
  }
}

TEST(Bodies, APlaneOffsetMovesAndTurnsThePlane) {
  // A plane turned by its offset (normal (0, 0, 1) turned 90 degrees about x: now along -y) and
  // moved by the body pose: the probe moving towards -y hits it at y = 0.5 + kR.
  World world;
  BodyDef b;
  b.pose = at(Vec3(0, 0.5, 0));
  b.shapes = {ShapeDef::plane(Vec3::UnitZ(), at(Vec3::Zero(), Quat(Eigen::AngleAxisd(
                                                                   std::numbers::pi / 2, Vec3::UnitX()))))};
  b.shapes[0].material = bouncy();
  world.add_body(b);
  const auto ps = world.add_particle_system(probes(false));
  world.spawn_particle(ps, Vec3(0, 0, 0), Vec3(0, 2, 0), 0.01, kR, 100);
  world.advance(0.5);  // reaches y = 0.5 - kR at 0.245 s, then back at 2 m/s
  const Vec3 x = position_of(world.particles(ps), 0);
  EXPECT_NEAR(x.y(), 0.5 - kR - 2.0 * (0.5 - (0.5 - kR) / 2.0), 1e-5);
  EXPECT_NEAR(velocity_of(world.particles(ps), 0).y(), -2.0, 1e-5);
}

}  // namespace
}  // namespace simreel::sim
