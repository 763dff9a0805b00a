// KeyframePath: interpolation, rotation slerp, clamping, looping, velocity.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "simreel/sim/keyframes.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

KeyframePath two_keys(bool smooth) {
  KeyframePath p;
  p.smooth = smooth;
  p.keys = {Keyframe{1.0, Vec3(0, 0, 0), Quat::Identity()},
            Keyframe{3.0, Vec3(4, -2, 6),
                     Quat(Eigen::AngleAxisd(std::numbers::pi / 2, Vec3::UnitZ()))}};
  return p;
}

TEST(SimKeyframes, LinearPositionAndSlerpRotation) {
  const KeyframePath p = two_keys(false);
  const Transform mid = p.sample(2.0);
  EXPECT_TRUE(mid.translation.isApprox(Vec3(2, -1, 3), 1e-12));
  // Halfway through a 90 degree turn about z: 45 degrees.
  const Vec3 x = mid.rotation * Vec3::UnitX();
  EXPECT_NEAR(x.x(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(x.y(), std::sqrt(0.5), 1e-12);
  const Transform q = p.sample(1.5);
  EXPECT_TRUE(q.translation.isApprox(Vec3(1, -0.5, 1.5), 1e-12));
}

TEST(SimKeyframes, ClampsOutsideTheKeys) {
  const KeyframePath p = two_keys(false);
  EXPECT_TRUE(p.sample(-5.0).translation.isApprox(Vec3(0, 0, 0)));
  EXPECT_TRUE(p.sample(10.0).translation.isApprox(Vec3(4, -2, 6)));
  EXPECT_TRUE(p.velocity(10.0).isZero());
  EXPECT_TRUE(p.velocity(2.0).isApprox(Vec3(2, -1, 3), 1e-6));
}

TEST(SimKeyframes, LoopRepeatsWithThePeriod) {
  KeyframePath p = two_keys(false);
  p.loop = true;
  for (double t : {1.25, 2.0, 2.9}) {
    EXPECT_TRUE(p.sample(t + 2.0).translation.isApprox(p.sample(t).translation, 1e-9)) << t;
    EXPECT_TRUE(p.sample(t - 4.0).translation.isApprox(p.sample(t).translation, 1e-9)) << t;
  }
}

TEST(SimKeyframes, CatmullRomPassesThroughKeysAndIsSmooth) {
  KeyframePath p;
  p.smooth = true;
  p.keys = {Keyframe{0.0, Vec3(0, 0, 0)}, Keyframe{1.0, Vec3(1, 2, 0)},
            Keyframe{2.0, Vec3(2, 0, 0)}, Keyframe{3.0, Vec3(3, 2, 1)}};
  for (const Keyframe& k : p.keys)
    EXPECT_TRUE(p.sample(k.time).translation.isApprox(k.position, 1e-12)) << k.time;
  // C1: velocity continuous across an inner key; the linear path's is not.
  const Vec3 before = p.velocity(1.0 - 1e-3, 1e-5), after = p.velocity(1.0 + 1e-3, 1e-5);
  EXPECT_LT((before - after).norm(), 0.05);
  KeyframePath lin = p;
  lin.smooth = false;
  EXPECT_GT((lin.velocity(1.0 - 1e-3, 1e-5) - lin.velocity(1.0 + 1e-3, 1e-5)).norm(), 3.0);
  // Evenly spaced collinear keys: the spline is the straight line.
  KeyframePath line;
  line.keys = {Keyframe{0.0, Vec3(0, 0, 0)}, Keyframe{1.0, Vec3(1, 1, 1)},
               Keyframe{2.0, Vec3(2, 2, 2)}};
  EXPECT_TRUE(line.sample(0.5).translation.isApprox(Vec3(0.5, 0.5, 0.5), 1e-12));
  EXPECT_TRUE(line.sample(1.7).translation.isApprox(Vec3(1.7, 1.7, 1.7), 1e-12));
}

TEST(SimKeyframes, NonIncreasingKeyTimesAreRejected) {
  World world;
  BoxDef box;
  box.path.keys = {Keyframe{0.0, Vec3::Zero()}, Keyframe{0.0, Vec3::UnitX()}};
  EXPECT_THROW(world.add_box(box), std::invalid_argument);
  box.path.keys = {Keyframe{1.0, Vec3::Zero()}, Keyframe{0.5, Vec3::UnitX()}};
  EXPECT_THROW(world.add_box(box), std::invalid_argument);
}

}  // namespace
}  // namespace simreel::sim
