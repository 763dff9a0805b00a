// Sleeping of dynamic bodies (WorldDef::allow_sleeping; Box2D's island rule, Bullet's
// deactivation): a stack at rest falls asleep as one island and stops moving exactly; it wakes
// when something moving touches it, when World::wake is called, or when what it rests on is
// removed, and then behaves as if it had never slept; a body in steady motion never sleeps.
#include <gtest/gtest.h>

#include <cmath>

#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

WorldDef def(bool sleeping, double h = 1.0 / 60.0) {
  WorldDef d;
  d.max_step = h;
  d.threads = 1;
  d.allow_sleeping = sleeping;
  return d;
}

BodyDef box_at(const Vec3& p, double half = 0.25) {
  BodyDef b;
  b.type = BodyType::dynamic;
  b.pose.translation = p;
  b.shapes.push_back(ShapeDef::box(Vec3::Constant(half)));
  b.shapes[0].material = Material(0.0, 0.5);
  return b;
}

BodyHandle ground(World& w) {
  BodyDef g;
  g.shapes.push_back(ShapeDef::plane());
  g.shapes[0].material = Material(0.0, 0.5);
  return w.add_body(g);
}

struct Stack {
  World world;
  BodyHandle floor;
  std::vector<BodyHandle> boxes;
  explicit Stack(bool sleeping, int n = 5) : world(def(sleeping)) {
    floor = ground(world);
    for (int k = 0; k < n; ++k) boxes.push_back(world.add_body(box_at({0.0, 0.0, 0.25 + 0.5 * k})));
  }
  void run(double seconds) {
    for (int s = 0; s < int(std::lround(seconds * 60)); ++s) (void)world.advance(1.0 / 60.0);
  }
};

TEST(Sleeping, AStackAtRestFallsAsleepAsOneIslandAndStopsExactly) {
  Stack s(true);
  s.run(0.25);
  for (BodyHandle b : s.boxes) EXPECT_TRUE(s.world.is_awake(b)) << "too early to sleep";
  s.run(2.0);
  for (BodyHandle b : s.boxes) EXPECT_FALSE(s.world.is_awake(b));
  const Vec3 top = s.world.pose(s.boxes.back()).translation;
  s.run(5.0);
  EXPECT_EQ(s.world.pose(s.boxes.back()).translation, top) << "asleep: no drift at all";
  EXPECT_TRUE(s.world.velocity(s.boxes.back()).first.isZero(0.0));
  EXPECT_NEAR(top.z(), 0.25 + 0.5 * 4, 0.01);
}

TEST(Sleeping, WithoutSleepingTheSameStackStaysAwakeAndWithinAFewMillimetres) {
  // At 1/60 s the sequential impulses leave this stack swaying sideways by a few mm while it
  // settles (its top box moves < 0.1 mm per frame after 3 s, < 1 um after 8 s); sleeping freezes
  // one moment of that sway. So the two stacks agree to the sway's size (2 mm at the top with
  // contacts kept to 1 mm while touching; 1 mm when corners were dropped at zero separation),
  // not to the solver's tolerance, and the awake stack comes to rest by itself.
  Stack awake(false), asleep(true);
  awake.run(3.0);
  asleep.run(3.0);
  for (std::size_t k = 0; k < awake.boxes.size(); ++k) {
    EXPECT_TRUE(awake.world.is_awake(awake.boxes[k]));
    EXPECT_LT((awake.world.pose(awake.boxes[k]).translation -
               asleep.world.pose(asleep.boxes[k]).translation).norm(), 3e-3);
  }
  awake.run(6.0);
  const Vec3 top = awake.world.pose(awake.boxes.back()).translation;
  awake.run(1.0 / 60.0);
  EXPECT_LT((awake.world.pose(awake.boxes.back()).translation - top).norm(), 1e-5)
      << "the awake stack settles";
  EXPECT_NEAR(top.z(), 0.25 + 0.5 * 4, 0.01);
  EXPECT_LT(std::hypot(top.x(), top.y()), 0.01);
}

TEST(Sleeping, ABoxDroppedOnASleepingStackWakesItWhole) {
  Stack s(true, 3);
  s.run(2.0);
  ASSERT_FALSE(s.world.is_awake(s.boxes[0]));
  // A box falling onto the top: the contact wakes the top box, and the island wakes whole.
  const BodyHandle falling = s.world.add_body(box_at({0.0, 0.0, 3.0}));
  bool all_woke = false;
  for (int k = 0; k < 120 && !all_woke; ++k) {
    (void)s.world.advance(1.0 / 60.0);
    all_woke = s.world.is_awake(s.boxes[0]) && s.world.is_awake(s.boxes[1]) && s.world.is_awake(s.boxes[2]);
  }
  EXPECT_TRUE(all_woke);
  s.run(3.0);
  EXPECT_NEAR(s.world.pose(falling).translation.z(), 0.25 + 0.5 * 3, 0.02) << "lands on the stack";
  for (BodyHandle b : s.boxes) EXPECT_FALSE(s.world.is_awake(b)) << "asleep again";
}

TEST(Sleeping, RemovingTheFloorWakesTheStackAndItFalls) {
  Stack s(true, 2);
  s.run(2.0);
  ASSERT_FALSE(s.world.is_awake(s.boxes[0]));
  const double z0 = s.world.pose(s.boxes[0]).translation.z();
  s.world.remove(s.floor);
  s.run(0.5);
  EXPECT_TRUE(s.world.is_awake(s.boxes[0]));
  // Free fall for 0.5 s from rest: 1.267 m (semi-implicit Euler at 1/60 s: g t (t + h) / 2).
  EXPECT_NEAR(s.world.pose(s.boxes[0]).translation.z(), z0 - 0.5 * 9.81 * 0.5 * (0.5 + 1.0 / 60.0), 1e-6);
}

TEST(Sleeping, WakeByHandleAndAKinematicPusherWake) {
  Stack s(true, 1);
  s.run(2.0);
  ASSERT_FALSE(s.world.is_awake(s.boxes[0]));
  s.world.wake(s.boxes[0]);
  EXPECT_TRUE(s.world.is_awake(s.boxes[0]));
  s.run(2.0);
  ASSERT_FALSE(s.world.is_awake(s.boxes[0]));
  // A kinematic paddle sweeping along x into the sleeping box pushes it.
  BodyDef paddle;
  paddle.type = BodyType::kinematic;
  paddle.shapes.push_back(ShapeDef::box({0.05, 0.5, 0.2}));
  const double t0 = s.world.time();
  paddle.path.smooth = false;
  paddle.path.keys = {{t0, {-1.0, 0.0, 0.25}, Quat::Identity()}, {t0 + 2.0, {1.0, 0.0, 0.25}, Quat::Identity()}};
  (void)s.world.add_body(paddle);
  s.run(1.5);
  EXPECT_GT(s.world.pose(s.boxes[0]).translation.x(), 0.2) << "pushed along by the paddle";
}

TEST(Sleeping, ASlidingOrSpinningBodyNeverSleeps) {
  World w(def(true));
  ground(w);
  BodyDef b = box_at({0.0, 0.0, 0.25});
  b.shapes[0].material = Material(0.0, 0.0);  // frictionless: slides forever
  b.linear_velocity = {0.1, 0.0, 0.0};        // above the 0.05 m/s tolerance
  const BodyHandle h = w.add_body(b);
  for (int k = 0; k < 300; ++k) (void)w.advance(1.0 / 60.0);
  EXPECT_TRUE(w.is_awake(h));
  EXPECT_NEAR(w.pose(h).translation.x(), 0.5, 1e-3);
}

TEST(Sleeping, AFreeBodyDriftingSlowlyKeepsItsMomentum) {
  // No gravity, no contact, 1 cm/s: slower than the tolerance, but nothing holds it, so it must
  // not sleep (sleeping would zero its momentum).
  World w(def(true));
  BodyDef b = box_at({0.0, 0.0, 5.0});
  b.gravity = Vec3::Zero();
  b.linear_velocity = {0.01, 0.0, 0.0};
  const BodyHandle h = w.add_body(b);
  for (int k = 0; k < 180; ++k) (void)w.advance(1.0 / 60.0);
  EXPECT_TRUE(w.is_awake(h));
  EXPECT_NEAR(w.pose(h).translation.x(), 0.03, 1e-9);
}

}  // namespace
}  // namespace simreel::sim
