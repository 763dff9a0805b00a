// Convex-hull shapes (ShapeType::convex_hull; quickhull at add time, Coutinho §2.2.4) in the
// World: mass properties from the hull's boundary (App. D) against closed forms, a hull box that
// rests like a box body on the ground and on a box (§4.8), a compound of hulls, particles landing
// on a hull (§3.4, as a closed mesh), and the errors of degenerate point sets.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim_test_util.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

constexpr double kPi = std::numbers::pi;

WorldDef def_with_step(double h) {
  WorldDef d;
  d.max_step = h;
  d.threads = 1;
  return d;
}

/// The 8 corners of a box of half extents e about c, plus `interior` points inside it.
std::vector<Vec3> box_points(const Vec3& e, const Vec3& c = Vec3::Zero(), int interior = 0) {
  std::vector<Vec3> p;
  for (int i = 0; i < 8; ++i)
    p.emplace_back(c + Vec3((i & 1) ? e.x() : -e.x(), (i & 2) ? e.y() : -e.y(), (i & 4) ? e.z() : -e.z()));
  for (int k = 0; k < interior; ++k) {  // a deterministic scatter strictly inside
    const double s = 0.9 * std::sin(1.7 * k + 0.3), t = 0.9 * std::cos(2.3 * k), u = 0.9 * std::sin(0.7 * k + 1.1);
    p.emplace_back(c + Vec3(s * e.x(), t * e.y(), u * e.z()));
  }
  return p;
}

/// n points on a sphere of radius r (Fibonacci lattice).
std::vector<Vec3> sphere_points(double r, int n) {
  std::vector<Vec3> p;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n, rho = std::sqrt(1.0 - z * z);
    p.emplace_back(r * rho * std::cos(golden * i), r * rho * std::sin(golden * i), r * z);
  }
  return p;
}

BodyDef floating(ShapeDef shape, const Vec3& omega = Vec3::Zero()) {
  BodyDef b;
  b.type = BodyType::dynamic;
  b.gravity = Vec3::Zero();
  b.angular_velocity = omega;
  b.shapes.push_back(std::move(shape));
  return b;
}

/// Inertia tensor of a body about its centre of mass, world frame, read through L = I ω
/// (three bodies spinning about x, y and z): the engine's own mass properties, not a re-derivation.
Mat3 inertia_of(const ShapeDef& s) {
  World w;
  Mat3 I;
  for (int k = 0; k < 3; ++k) I.col(k) = w.motion(w.add_body(floating(s, Vec3::Unit(k)))).angular_momentum;
  return I;
}

TEST(HullBodies, CubeCornersWithInteriorPointsHaveTheBoxMassProperties) {
  const Vec3 e(0.5, 1.0, 1.5), c(0.3, -0.2, 0.1);
  const double rho = 700.0;
  ShapeDef s = ShapeDef::convex_hull(box_points(e, c, 50));
  s.density = rho;
  World w;
  const BodyMotion m = w.motion(w.add_body(floating(s)));
  const double mass = rho * 8.0 * e.prod();
  EXPECT_NEAR(m.mass, mass, 1e-9 * mass);
  EXPECT_LT((m.center_of_mass - c).norm(), 1e-9);
  const Mat3 I = inertia_of(s);
  const Vec3 d(mass / 3.0 * (e.y() * e.y() + e.z() * e.z()), mass / 3.0 * (e.x() * e.x() + e.z() * e.z()),
               mass / 3.0 * (e.x() * e.x() + e.y() * e.y()));
  EXPECT_LT((I - Mat3(d.asDiagonal())).cwiseAbs().maxCoeff(), 1e-9 * d.maxCoeff()) << I;
}

TEST(HullBodies, HullOfSpherePointsIsASphereWithinHalfAPercent) {
  const double r = 0.4, rho = 1000.0;
  ShapeDef s = ShapeDef::convex_hull(sphere_points(r, 3000));
  s.density = rho;
  World w;
  const BodyMotion m = w.motion(w.add_body(floating(s)));
  const double mass = rho * 4.0 / 3.0 * kPi * r * r * r;
  EXPECT_NEAR(m.mass, mass, 0.005 * mass);
  EXPECT_LT(m.center_of_mass.norm(), 1e-4 * r);
  const Mat3 I = inertia_of(s);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(I(k, k), 0.4 * mass * r * r, 0.005 * 0.4 * mass * r * r);
}

TEST(HullBodies, CompoundOfTwoHullsCombinesByTheParallelAxisTheorem) {
  // Two unit cubes side by side at x = ±0.5 = one 2 x 1 x 1 box.
  BodyDef b = floating(ShapeDef::convex_hull(box_points(Vec3::Constant(0.5)), Transform{{-0.5, 0, 0}, Quat::Identity()}));
  b.shapes.push_back(ShapeDef::convex_hull(box_points(Vec3::Constant(0.5)), Transform{{0.5, 0, 0}, Quat::Identity()}));
  World w;
  const BodyMotion m = w.motion(w.add_body(b));
  EXPECT_NEAR(m.mass, 2000.0, 1e-9 * 2000.0);
  EXPECT_LT(m.center_of_mass.norm(), 1e-12);
  b.angular_velocity = Vec3::UnitZ();  // I_zz of a 2 x 1 x 1 box: m (4 + 1) / 12
  World w2;
  EXPECT_NEAR(w2.motion(w2.add_body(b)).angular_momentum.z(), 2000.0 / 12.0 * 5.0, 1e-9 * 1000.0);
}

/// Rest height of a body dropped 0.2 m onto the ground plane (and, with `on_box`, onto a static
/// 0.5 m box there), after 4 s.
double rest_height(ShapeDef shape, bool on_box) {
  World w(def_with_step(1.0 / 240.0));
  BodyDef ground;
  ground.shapes.push_back(ShapeDef::plane());
  ground.shapes.back().material = {0.0, 0.5};
  w.add_body(ground);
  double base = 0.0;
  if (on_box) {
    BodyDef box;
    box.pose.translation = {0.0, 0.0, 0.25};
    box.shapes.push_back(ShapeDef::box(Vec3::Constant(0.25)));
    box.shapes.back().material = {0.0, 0.5};
    w.add_body(box);
    base = 0.5;
  }
  BodyDef b;
  b.type = BodyType::dynamic;
  b.pose.translation = {0.0, 0.0, base + 0.2 + 0.2};
  shape.material = {0.0, 0.5};
  b.shapes.push_back(std::move(shape));
  const BodyHandle h = w.add_body(b);
  for (int i = 0; i < 120; ++i) w.advance(1.0 / 30.0);
  return w.pose(h).translation.z() - base;
}

TEST(HullBodies, HullBoxRestsLikeABoxOnTheGroundAndOnABox) {
  const Vec3 e(0.3, 0.25, 0.2);
  for (bool on_box : {false, true}) {
    const double box = rest_height(ShapeDef::box(e), on_box);
    const double hull = rest_height(ShapeDef::convex_hull(box_points(e, Vec3::Zero(), 10)), on_box);
    EXPECT_NEAR(hull, e.z(), 1e-3) << "on a box: " << on_box;
    EXPECT_NEAR(hull, box, 1e-3) << "on a box: " << on_box;
  }
}

/// The top of a stack of three 0.5 m cubes dropped with 1 cm gaps, after 3 s.
Vec3 stack_top(bool hull) {
  World w(def_with_step(1.0 / 240.0));
  BodyDef ground;
  ground.shapes.push_back(ShapeDef::plane());
  w.add_body(ground);
  std::vector<BodyHandle> hs;
  for (int k = 0; k < 3; ++k) {
    BodyDef b;
    b.type = BodyType::dynamic;
    b.pose.translation = {0.0, 0.0, 0.25 + 0.5 * k + 0.01 * k};
    b.shapes.push_back(hull ? ShapeDef::convex_hull(box_points(Vec3::Constant(0.25)))
                            : ShapeDef::box(Vec3::Constant(0.25)));
    hs.push_back(w.add_body(b));
  }
  for (int i = 0; i < 90; ++i) w.advance(1.0 / 30.0);
  return w.pose(hs.back()).translation;
}

TEST(HullBodies, HullBoxesStackLikeBoxes) {
  const Vec3 hull = stack_top(true), box = stack_top(false);
  EXPECT_NEAR(hull.z(), 1.25, 3e-3);
  EXPECT_NEAR(hull.z(), box.z(), 1e-3);
  // Sideways drift of the top: 2.03 mm for both (the same to 1e-6 m: the hull's faces clip like
  // the box's).
  EXPECT_LT(hull.head<2>().norm(), 5e-3);
  EXPECT_NEAR((hull - box).head<2>().norm(), 0.0, 1e-4);
}

TEST(HullBodies, ParticlesLandOnAStaticHull) {
  // A static hull box's top face at z = 1: particles dropped on it stop there.
  World w(def_with_step(1.0 / 240.0));
  BodyDef hull;
  hull.shapes.push_back(ShapeDef::convex_hull(box_points({1.0, 1.0, 0.5}, {0.0, 0.0, 0.5}, 20)));
  hull.shapes.back().material = {0.0, 0.5};
  w.add_body(hull);
  const auto ps = w.add_particle_system(test::spawn_only_system());
  for (int k = 0; k < 10; ++k)
    w.spawn_particle(ps, Vec3(-0.8 + 0.17 * k, 0.3, 1.5), Vec3(0.0, 0.0, -2.0), 0.01, 0.02, 100);
  for (int i = 0; i < 60; ++i) w.advance(1.0 / 30.0);
  const ParticleView v = w.particles(ps);
  ASSERT_EQ(v.count, 10u);
  for (std::size_t i = 0; i < v.count; ++i) EXPECT_NEAR(test::position_of(v, i).z(), 1.02, 2e-3) << i;
}

TEST(HullBodies, DegenerateHullsAreRejectedNamingTheField) {
  World w;
  BodyDef b;
  b.type = BodyType::dynamic;
  b.shapes.push_back(ShapeDef::sphere(0.1));
  b.shapes.push_back(ShapeDef::convex_hull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}));
  try {
    w.add_body(b);
    FAIL() << "coplanar points accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("BodyDef.shapes[1].points: all points are coplanar"), std::string::npos)
        << e.what();
  }
  b.shapes[1] = ShapeDef::convex_hull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  EXPECT_THROW(w.add_body(b), std::invalid_argument);
  b.shapes[1] = ShapeDef::convex_hull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, NAN}});
  EXPECT_THROW(w.add_body(b), std::invalid_argument);
  EXPECT_TRUE(w.colliders().empty());
}

}  // namespace
}  // namespace simreel::sim
