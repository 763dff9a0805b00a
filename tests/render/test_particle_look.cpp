// The particles' look (issue 14 B), measured in the image: a spark under a pixel keeps its light
// in proportion to its area (coverage) instead of vanishing or flickering, an additive trail is a
// line of the length the motion gives and carries the light of the dot it replaces, smoke and
// flame textures are deterministic and change the picture.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "render_test_util.hpp"
#include "simreel/render/context.hpp"
#include "simreel/render/renderer.hpp"

namespace simreel::render {
namespace {

constexpr int kW = 320;
constexpr int kH = 240;

double srgb_to_linear(std::uint8_t v) {
  const double c = v / 255.0;
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

class ParticleLook : public ::testing::Test {
 protected:
  void SetUp() override {
    context_ = create_context(Backend::osmesa);
    RenderSettings s;
    s.width = kW;
    s.height = kH;
    s.background = Background::solid;
    s.background_color = Vec3f::Zero();
    renderer_ = std::make_unique<Renderer>(*context_, s);
    renderer_->set_camera(test::front_camera());
    empty_ = renderer_->render();
  }
  /// Projected pixels per metre at the origin (the camera is 10 m away, 40 degrees vertical).
  static double pixels_per_m() { return 0.5 * kH / (10.0 * std::tan(20.0 * 3.14159265358979 / 180.0)); }
  void one(const Vec3f& p, float radius, float brightness, const Vec3f& velocity = Vec3f::Zero(),
           float trail_s = 0.f, ParticleTexture texture = ParticleTexture::none) {
    const float pos[] = {p.x(), p.y(), p.z()};
    const float col[] = {brightness, brightness, brightness, 1.f};
    const float vel[] = {velocity.x(), velocity.y(), velocity.z()};
    ParticleBatch b{1, pos, col, &radius, ParticleStyle::additive};
    b.velocity = vel;
    b.trail_s = trail_s;
    b.texture = texture;
    renderer_->set_particles(1, b);
  }
  /// Sum over the image of the linear red channel above the empty frame.
  double light(const Image& img) const {
    double sum = 0.0;
    for (int y = 0; y < kH; ++y) {
      for (int x = 0; x < kW; ++x) sum += srgb_to_linear(img.pixel(x, y)[0]) - srgb_to_linear(empty_.pixel(x, y)[0]);
    }
    return sum;
  }
  std::unique_ptr<Context> context_;
  std::unique_ptr<Renderer> renderer_;
  Image empty_;
};

// A spark's light is its brightness times its projected area; under a pixel it is drawn one pixel
// wide with the brightness scaled by its coverage, so light / area does not depend on its size
// (nor on where it falls between pixel centres: no twinkling as it moves) and matches sparks drawn
// at their true size. Each spark gets brightness 0.5 / r_px^2 so every image is well above the
// 8-bit quantisation.
TEST_F(ParticleLook, SubpixelSparkKeepsItsLightInProportionToItsArea) {
  const double ppm = pixels_per_m();
  std::vector<double> below, above;
  for (const double offset_px : {0.0, 0.25, 0.5}) {
    for (const double r_px : {0.1, 0.2, 0.3, 0.5, 0.7, 0.9, 1.2, 1.5, 1.8, 2.5, 3.0}) {
      one(Vec3f(float(offset_px / ppm), 0.f, float(0.37 * offset_px / ppm)), float(r_px / ppm), float(0.5 / (r_px * r_px)));
      const double per_area = light(renderer_->render());
      (r_px < 1.0 ? below : above).push_back(per_area);
    }
  }
  const auto [lo, hi] = std::minmax_element(below.begin(), below.end());
  std::printf("light / r_px^2 below a pixel: %.4f .. %.4f (ratio %.4f)\n", *lo, *hi, *hi / *lo);
  EXPECT_LT(*hi / *lo, 1.05) << "below a pixel: " << *lo << " .. " << *hi;
  double mean_below = 0.0, mean_above = 0.0;
  for (double v : below) mean_below += v / double(below.size());
  for (double v : above) mean_above += v / double(above.size());
  // 0.5 x the glow's integral over the unit disc (0.6123) per pixel^2 of r^2.
  EXPECT_NEAR(mean_below, 0.5 * 0.6123, 0.05 * 0.5 * 0.6123);
  const auto [alo, ahi] = std::minmax_element(above.begin(), above.end());
  std::printf("mean below %.4f, at 1.2..3 px %.4f (%.4f .. %.4f)\n", mean_below, mean_above, *alo, *ahi);
  EXPECT_LT(*ahi / *alo, 1.15) << "1.2..3 px: " << *alo << " .. " << *ahi;
  EXPECT_NEAR(mean_above / mean_below, 1.0, 0.05) << mean_above << " vs " << mean_below;
}

// A dot moving at 8 m/s with trail_s 0.25 s leaves a 2 m line behind it (65.9 pixels here),
// horizontal, behind the head, carrying the light of the dot.
TEST_F(ParticleLook, TrailIsALineOfTheExpectedLengthWithTheDotsLight) {
  const double ppm = pixels_per_m();
  const float radius = 0.06f;  // 1.98 px
  one(Vec3f::Zero(), radius, 0.5f);
  const double dot = light(renderer_->render());
  one(Vec3f::Zero(), radius, 0.5f, Vec3f(8.f, 0.f, 0.f), 0.25f);
  const Image img = renderer_->render();
  int x0 = kW, x1 = -1, y0 = kH, y1 = -1;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      if (srgb_to_linear(img.pixel(x, y)[0]) > 0.0015) {
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
      }
    }
  }
  const double expected = 2.0 * ppm + 2.0 * radius * ppm;  // the line plus the dot's two radii
  EXPECT_NEAR(x1 - x0 + 1, expected, 4.0) << "x " << x0 << ".." << x1;
  EXPECT_LE(y1 - y0 + 1, 6) << "y " << y0 << ".." << y1;
  EXPECT_LT(x0, kW / 2 - 50);  // the tail lies behind (-x of) the head at the centre
  std::printf("trail %d x %d px (expected length %.1f), light / dot %.4f\n", x1 - x0 + 1, y1 - y0 + 1, expected,
              light(img) / dot);
  EXPECT_NEAR(light(img) / dot, 1.0, 0.05);
  // Without a trail the same particle is a dot.
  one(Vec3f::Zero(), radius, 0.5f, Vec3f(8.f, 0.f, 0.f), 0.f);
  EXPECT_NEAR(light(renderer_->render()) / dot, 1.0, 1e-9);
}

// Crackle (fireworks): an additive particle with strobe_hz flashes on and off as it ages, at a
// phase of its own (its id's random number), the same bytes every time. 12 Hz at 35 % lit,
// sampled at 30 fps: over 15 frames a particle is seen both lit at full light and dark, and
// consecutive frames jump between the two; with strobe_hz 0 it is steady.
TEST_F(ParticleLook, StrobeFlashesOnAndOffPerParticleAndDeterministically) {
  const float pos[] = {0.f, 0.f, 0.f}, col[] = {0.5f, 0.5f, 0.5f, 1.f}, radius = 0.06f, life = 10.f;
  auto frame = [&](float age, std::uint64_t id, float hz) {
    ParticleBatch b{1, pos, col, &radius, ParticleStyle::additive};
    b.age = &age;
    b.lifetime = &life;
    b.id = &id;
    b.emissive = 3.f;
    b.strobe_hz = hz;
    b.strobe_duty = 0.35f;
    renderer_->set_particles(1, b);
    return renderer_->render();
  };
  const double steady = light(frame(0.f, 7, 0.f));
  ASSERT_GT(steady, 1.0);
  for (std::uint64_t id : {std::uint64_t{7}, std::uint64_t{8}, std::uint64_t{1234}}) {
    std::vector<double> seen;
    int lit = 0, dark = 0, jumps = 0;
    for (int k = 0; k < 15; ++k) {
      const double l = light(frame(float(k) / 30.f, id, 12.f)) / steady;
      seen.push_back(l);
      lit += l > 0.95;
      dark += l < 0.01;
      EXPECT_TRUE(l > 0.95 || l < 0.01) << "id " << id << " frame " << k << ": " << l << " (on or off, nothing between)";
      if (k > 0) jumps += std::abs(l - seen[std::size_t(k - 1)]) > 0.9;
      EXPECT_NEAR(light(frame(float(k) / 30.f, id, 0.f)) / steady, 1.0, 1e-9) << "no strobe: steady";
    }
    std::printf("id %llu: %d lit, %d dark, %d jumps of 15 frames\n", (unsigned long long)id, lit, dark, jumps);
    EXPECT_GE(lit, 3) << "id " << id;
    EXPECT_GE(dark, 5) << "id " << id;
    EXPECT_GE(jumps, 4) << "id " << id;
  }
  // The same age and id give the same bytes; other ids are lit in other frames.
  EXPECT_EQ(frame(0.3f, 7, 12.f).rgba, frame(0.3f, 7, 12.f).rgba);
  int differ = 0;
  for (int k = 0; k < 15; ++k)
    differ += (light(frame(float(k) / 30.f, 7, 12.f)) > 0.5 * steady) != (light(frame(float(k) / 30.f, 8, 12.f)) > 0.5 * steady);
  EXPECT_GE(differ, 2) << "two particles strobe in step: no phase of their own";
}

}  // namespace
}  // namespace simreel::render
