// Camera motion: keyframed paths pass through their keys exactly and move smoothly between
// them; orbits keep their radius and height and close after one period.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "simreel/render/camera_path.hpp"

namespace simreel::render {
namespace {

CameraMotion three_keys() {
  CameraMotion m;
  m.keys = {CameraKey{0.0, Vec3f(4.f, -4.f, 2.f), Vec3f(0.f, 0.f, 1.f), 40.f},
            CameraKey{1.5, Vec3f(0.f, -6.f, 3.f), Vec3f(0.f, 0.f, 0.5f), 30.f},
            CameraKey{4.0, Vec3f(-5.f, -2.f, 1.f), Vec3f(1.f, 0.f, 0.f), 50.f}};
  return m;
}

TEST(CameraPath, InterpolationHitsEveryKeyExactly) {
  const CameraMotion m = three_keys();
  for (const CameraKey& k : m.keys) {
    const Camera c = camera_at(m, k.time);
    EXPECT_EQ(c.position, k.position) << k.time;
    EXPECT_EQ(c.target, k.target) << k.time;
    EXPECT_EQ(c.fov_deg, k.fov_deg) << k.time;
  }
  // Before the first key and after the last the camera holds still.
  EXPECT_EQ(camera_at(m, -1.0).position, m.keys.front().position);
  EXPECT_EQ(camera_at(m, 9.0).position, m.keys.back().position);
}

TEST(CameraPath, VelocityIsContinuousThroughAMiddleKey) {
  const CameraMotion m = three_keys();
  const double h = 1e-3;
  const double t = m.keys[1].time;
  const Vec3f left = (camera_at(m, t).position - camera_at(m, t - h).position) / float(h);
  const Vec3f right = (camera_at(m, t + h).position - camera_at(m, t).position) / float(h);
  // One-sided differences agree up to O(h) x acceleration; a kink would differ by O(1).
  EXPECT_LT((left - right).norm(), 0.05f) << left.transpose() << " vs " << right.transpose();
  // The tangent there is the mean of the neighbouring segments' slopes (Catmull-Rom).
  const Vec3f expected = 0.5f * ((m.keys[1].position - m.keys[0].position) / 1.5f +
                                 (m.keys[2].position - m.keys[1].position) / 2.5f);
  EXPECT_LT((0.5f * (left + right) - expected).norm(), 0.01f);
}

TEST(CameraPath, TwoKeysEaseInAndOut) {
  CameraMotion m;
  m.keys = {CameraKey{0.0, Vec3f(0.f, -5.f, 1.f), Vec3f::Zero(), 40.f},
            CameraKey{2.0, Vec3f(2.f, -5.f, 1.f), Vec3f::Zero(), 40.f}};
  // Zero end slopes: the smoothstep 3s^2 - 2s^3, halfway at the middle time.
  EXPECT_NEAR(camera_at(m, 1.0).position.x(), 1.f, 1e-6f);
  EXPECT_NEAR(camera_at(m, 0.5).position.x(), 2.f * (3.f * 0.0625f - 2.f * 0.015625f), 1e-6f);
}

TEST(CameraOrbit, KeepsRadiusAndHeightAndClosesAfterAPeriod) {
  CameraMotion m;
  m.orbit = CameraOrbit{Vec3f(1.f, 2.f, 0.5f), 6.f, 2.f, 8.f, -90.f};
  const Camera start = camera_at(m, 0.0);
  EXPECT_NEAR(start.position.x(), 1.f, 1e-5f);  // start_deg -90: on the -y side
  EXPECT_NEAR(start.position.y(), 2.f - 6.f, 1e-5f);
  for (const double t : {0.7, 2.0, 5.3}) {
    const Camera c = camera_at(m, t);
    const Vec3f d = c.position - m.orbit->center;
    EXPECT_NEAR(std::hypot(d.x(), d.y()), 6.f, 1e-4f);
    EXPECT_NEAR(d.z(), 2.f, 1e-6f);
    EXPECT_EQ(c.target, m.orbit->center);
  }
  // A quarter period later it is on the +x side (counter-clockwise seen from above).
  EXPECT_NEAR(camera_at(m, 2.0).position.x(), 7.f, 1e-4f);
  EXPECT_LT((camera_at(m, 8.0).position - start.position).norm(), 1e-4f);
}

TEST(CameraPath, BadMotionIsRejected) {
  CameraMotion m = three_keys();
  m.keys[2].time = 1.5;
  EXPECT_THROW(camera_at(m, 0.0), std::invalid_argument);
  CameraMotion o;
  o.orbit = CameraOrbit{};
  o.orbit->period_s = 0.f;
  EXPECT_THROW(camera_at(o, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace simreel::render
