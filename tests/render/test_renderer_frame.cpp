// The frame around the scene (issue 14 A): HDR bloom, the sky and far ground, transparent
// background, the camera shutter (motion blur).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <memory>
#include <vector>

#include "gl/targets.hpp"
#include "passes/bloom_pass.hpp"
#include "render_test_util.hpp"
#include "simreel/render/context.hpp"
#include "simreel/render/renderer.hpp"

namespace simreel::render {
namespace {

using test::find_blob;
using test::is_warm;

/// SIMREEL_TEST_DUMP=DIR writes the rendered frames there, to look at.
void dump(const Image& img, const char* name) {
  if (const char* dir = std::getenv("SIMREEL_TEST_DUMP")) write_png(std::string(dir) + "/" + name + ".png", img);
}

// ---------------------------------------------------------------------------------------------
// Bloom chain, in linear floats

/// Runs the bloom chain on a w x h RGBA float image; returns up_1 (quarter size) as floats.
std::vector<float> bloom_chain(Context& ctx, int w, int h, const std::vector<float>& rgba, float radius,
                               int* out_w = nullptr, int* out_h = nullptr) {
  const GlTable& gl = ctx.gl();
  GLuint vao = 0;
  gl.GenVertexArrays(1, &vao);
  const GLuint src = detail::make_texture_2d(gl, w, h, GL_RGBA16F, GL_RGBA, GL_FLOAT, GL_NEAREST);
  gl.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA16F, w, h, 0, GL_RGBA, GL_FLOAT, rgba.data());
  detail::BloomPass bloom;
  bloom.create(gl, w, h);
  bloom.draw(src, radius, vao);
  const int rw = bloom.result_width(), rh = bloom.result_height();
  GLuint fbo = 0;
  gl.GenFramebuffers(1, &fbo);
  gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
  gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, bloom.result(), 0);
  std::vector<float> out(std::size_t(rw) * rh * 4);
  gl.ReadBuffer(GL_COLOR_ATTACHMENT0);
  gl.ReadPixels(0, 0, rw, rh, GL_RGBA, GL_FLOAT, out.data());
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
  gl.DeleteFramebuffers(1, &fbo);
  bloom.destroy();
  gl.DeleteTextures(1, &src);
  gl.DeleteVertexArrays(1, &vao);
  detail::check_error(gl, "bloom test");
  if (out_w) *out_w = rw;
  if (out_h) *out_h = rh;
  return out;
}

double channel_sum(const std::vector<float>& rgba, int c) {
  double s = 0.0;
  for (std::size_t i = std::size_t(c); i < rgba.size(); i += 4) s += rgba[i];
  return s;
}

TEST(Bloom, KeepsTheImagesEnergyWithinOnePercent) {
  auto ctx = create_context(Backend::osmesa);
  const int w = 320, h = 180;
  std::vector<float> img(std::size_t(w) * h * 4, 0.f);
  // A dim gradient, a few HDR spots (fire, sparks) and a bright bar: everything in the middle
  // and at the edges of the frame.
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      float* p = &img[(std::size_t(y) * w + x) * 4];
      p[0] = 0.1f + 0.3f * float(x) / w;
      p[1] = 0.2f * float(y) / h;
      p[2] = 0.05f;
      p[3] = 1.f;
    }
  }
  for (const auto& [x, y, v] : {std::tuple{160, 90, 400.f}, {40, 30, 120.f}, {290, 150, 60.f}, {100, 120, 200.f}}) {
    img[(std::size_t(y) * w + x) * 4 + 0] = v;
    img[(std::size_t(y) * w + x) * 4 + 1] = 0.5f * v;
  }
  for (int x = 120; x < 200; ++x) img[(std::size_t(60) * w + x) * 4 + 2] = 8.f;
  for (const float radius : {0.f, 0.7f, 1.f}) {
    int rw = 0, rh = 0;
    const std::vector<float> up = bloom_chain(*ctx, w, h, img, radius, &rw, &rh);
    ASSERT_EQ(rw, w / 4);
    ASSERT_EQ(rh, h / 4);
    for (int c = 0; c < 3; ++c) {
      // up_1 has a sixteenth of the pixels: 16 times its sum is the light it carries.
      const double in = channel_sum(img, c), blurred = 16.0 * channel_sum(up, c);
      EXPECT_NEAR(blurred / in, 1.0, 0.01) << "radius " << radius << " channel " << c;
      // The frame the post pass tone-maps: (1 - intensity) frame + intensity blur.
      const double mixed = 0.96 * in + 0.04 * blurred;
      EXPECT_NEAR(mixed / in, 1.0, 0.001);
    }
  }
}

TEST(Bloom, ABrightPixelSpreadsToItsNeighboursAndBlackStaysBlack) {
  auto ctx = create_context(Backend::osmesa);
  const int w = 128, h = 64;
  std::vector<float> img(std::size_t(w) * h * 4, 0.f);
  const std::vector<float> black = bloom_chain(*ctx, w, h, img, 0.7f);
  for (const float v : black) ASSERT_EQ(v, 0.f);
  img[(std::size_t(32) * w + 64) * 4 + 0] = 100.f;
  int rw = 0;
  const std::vector<float> up = bloom_chain(*ctx, w, h, img, 0.7f, &rw);
  auto red = [&](int x, int y) { return up[(std::size_t(y) * rw + x) * 4]; };
  // The pixel sits at (16, 8) of the quarter-size level; light reaches far beyond it, falling off.
  EXPECT_GT(red(16, 8), red(18, 8));
  EXPECT_GT(red(18, 8), red(22, 8));
  EXPECT_GT(red(22, 8), 0.f);
  EXPECT_GT(red(16, 14), 0.f);
  // With radius 0 the glow stays within the first level's 4 x 4 box.
  const std::vector<float> tight = bloom_chain(*ctx, w, h, img, 0.f);
  EXPECT_EQ(tight[(std::size_t(8) * rw + 17) * 4], 0.f);
  EXPECT_GT(tight[(std::size_t(8) * rw + 16) * 4], 0.f);
}

// ---------------------------------------------------------------------------------------------
// Through the renderer

RenderSettings black_settings() {
  RenderSettings s = test::small_settings();
  s.background = Background::solid;
  s.background_color = Vec3f::Zero();
  return s;
}

Image render_spark(const RenderSettings& s) {
  auto ctx = create_context(Backend::osmesa);
  Renderer r(*ctx, s);
  r.set_camera(test::front_camera());
  // Bright HDR light: many sparks of 0.15 m (2.5 pixels) stacked in one place.
  const int n = 128;
  const float col[] = {1.f, 0.6f, 0.2f, 1.f};
  std::vector<float> p(3 * n, 0.f), c(4 * n), rr(n, 0.15f);
  for (int i = 0; i < n; ++i) std::copy(col, col + 4, &c[4 * i]);
  r.set_particles(1, ParticleBatch{std::size_t(n), p.data(), c.data(), rr.data(), ParticleStyle::additive});
  return r.render();
}

TEST(Bloom, GlowsAroundABrightSparkInTheRenderedFrame) {
  RenderSettings s = black_settings();
  const Image glow = render_spark(s);
  s.bloom.intensity = 0.f;
  const Image plain = render_spark(s);
  dump(glow, "spark_glow");
  dump(plain, "spark_plain");
  const int cx = test::kWidth / 2, cy = test::kHeight / 2;
  EXPECT_GT(plain.pixel(cx, cy)[0], 200);
  // 12 pixels away (the spark is ~2 px wide): black without bloom, lit with it.
  EXPECT_EQ(plain.pixel(cx + 12, cy)[0], 0);
  EXPECT_GT(glow.pixel(cx + 12, cy)[0], 8);
  EXPECT_GT(glow.pixel(cx, cy + 12)[0], 8);
}

TEST(Bloom, AnEmptyBlackFrameStaysBlack) {
  auto ctx = create_context(Backend::osmesa);
  Renderer r(*ctx, black_settings());
  r.set_camera(test::front_camera());
  const Image img = r.render();
  for (std::size_t i = 0; i < img.rgba.size(); i += 4) {
    ASSERT_EQ(img.rgba[i] + img.rgba[i + 1] + img.rgba[i + 2], 0) << i / 4;
  }
}

// ---------------------------------------------------------------------------------------------
// Transparent background

TEST(Transparent, AlphaIsZeroWhereNothingIsDrawnAndOpaqueOnTheBox) {
  auto ctx = create_context(Backend::osmesa);
  RenderSettings s = test::small_settings();
  s.background = Background::transparent;
  Renderer r(*ctx, s);
  r.set_camera(test::front_camera());
  r.add_box(1, BoxDesc{});
  const Image img = r.render();
  dump(img, "transparent");
  int zero = 0, opaque = 0;
  for (std::size_t i = 3; i < img.rgba.size(); i += 4) {
    zero += img.rgba[i] == 0;
    opaque += img.rgba[i] == 255;
  }
  EXPECT_EQ(img.pixel(2, 2)[3], 0);
  EXPECT_EQ(img.pixel(test::kWidth - 3, test::kHeight - 3)[3], 0);
  EXPECT_EQ(img.pixel(test::kWidth / 2, test::kHeight / 2)[3], 255);
  EXPECT_TRUE(is_warm(img.pixel(test::kWidth / 2, test::kHeight / 2)));
  // The box covers ~ (1 m / 7.3 m)^2 of the view: the rest is empty.
  EXPECT_GT(zero, int(0.9 * test::kWidth * test::kHeight));
  EXPECT_GT(opaque, 200);
  // Where nothing is drawn, the colour is black too (no stray dither or bloom).
  EXPECT_EQ(img.pixel(2, 2)[0] + img.pixel(2, 2)[1] + img.pixel(2, 2)[2], 0);
}

TEST(Transparent, AGroundFillingMostOfTheFrameLeavesTheSkyClear) {
  // Bloom blurs the ground over the whole frame; none of it may leak into the empty sky.
  auto ctx = create_context(Backend::osmesa);
  RenderSettings s = test::small_settings();
  s.background = Background::transparent;
  Renderer r(*ctx, s);
  Camera c = test::front_camera();
  c.position = Vec3f(0.f, -10.f, 3.f);
  r.set_camera(c);
  r.add_plane(1, PlaneDesc{});
  const Image img = r.render();
  dump(img, "transparent_ground");
  for (int x = 0; x < img.width; ++x) ASSERT_EQ(img.pixel(x, 0)[3], 0) << x;
  EXPECT_EQ(img.pixel(img.width / 2, img.height - 1)[3], 255);
}

// ---------------------------------------------------------------------------------------------
// Sky and ground

int luma(const std::uint8_t* p) { return (2 * p[0] + 5 * p[1] + p[2]) / 8; }

TEST(Sky, TheGroundMeetsTheHorizonWithoutARim) {
  auto ctx = create_context(Backend::osmesa);
  RenderSettings s = test::small_settings();
  s.height = 240;
  Renderer r(*ctx, s);
  Camera c;
  c.position = Vec3f(0.f, -12.f, 1.6f);
  c.target = Vec3f(0.f, 0.f, 1.6f);  // level: the horizon is the middle row
  r.set_camera(c);
  PlaneDesc ground;
  ground.half_size = 20.f;
  r.add_plane(1, ground);
  const Image img = r.render();
  dump(img, "horizon");
  // Down the middle column from the horizon to the bottom: the ground square's edge (about
  // 32 m away, a few rows under the horizon) must leave no step and no band.
  const int x = s.width / 2;
  int worst = 0;
  for (int y = s.height / 2 - 20; y < s.height / 2 + 30; ++y) {
    worst = std::max(worst, std::abs(luma(img.pixel(x, y + 1)) - luma(img.pixel(x, y))));
  }
  EXPECT_LE(worst, 3);
  // The rows just above and below the horizon have nearly the same colour.
  const std::uint8_t* above = img.pixel(x, s.height / 2 - 2);
  const std::uint8_t* below = img.pixel(x, s.height / 2 + 2);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(above[k], below[k], 6) << k;
}

TEST(Sky, TheSunDiskIsWhereTheLightComesFrom) {
  auto ctx = create_context(Backend::osmesa);
  RenderSettings s = test::small_settings();
  s.bloom.intensity = 0.f;
  Renderer r(*ctx, s);
  Light light;
  light.direction = Vec3f(-0.3f, -1.f, -0.25f);  // from +y, slightly right and above
  r.set_light(light);
  Camera c;
  c.position = Vec3f(0.f, 0.f, 1.f);
  c.target = c.position - light.direction;  // looking straight at the sun
  r.set_camera(c);
  const Image img = r.render();
  dump(img, "sun");
  int best = -1, bx = 0, by = 0;
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      const int v = luma(img.pixel(x, y));
      if (v > best) best = v, bx = x, by = y;
    }
  }
  EXPECT_GT(best, 250);
  EXPECT_NEAR(bx, img.width / 2, 2);
  EXPECT_NEAR(by, img.height / 2, 2);
  // The sky gets lighter towards the sun.
  EXPECT_GT(luma(img.pixel(img.width / 2 + 20, img.height / 2)), luma(img.pixel(img.width - 1, img.height / 2)));
}

// ---------------------------------------------------------------------------------------------
// Motion blur

/// sRGB-encoded 8-bit level -> linear.
double linear(int v) {
  const double c = v / 255.0;
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

/// The middle row of a box on black: its light per column (linear red), summed and its extent.
struct Profile {
  double sum = 0.0;
  int first = -1, last = -1;
};
Profile row_profile(const Image& img) {
  Profile p;
  const int y = img.height / 2;
  double peak = 0.0;
  for (int x = 0; x < img.width; ++x) peak = std::max(peak, linear(img.pixel(x, y)[0]));
  for (int x = 0; x < img.width; ++x) {
    const double v = linear(img.pixel(x, y)[0]);
    p.sum += v;
    // 1/32 of the sharp box's light is one of the 32 sub-frames: count from half of that.
    if (v > 0.01 * peak) {
      if (p.first < 0) p.first = x;
      p.last = x;
    }
  }
  return p;
}

/// A 0.6 m square plate (1 cm thick, so no side face shows) facing the camera, moving 1.5 m
/// along +x between two frames, on black, rendered with `shutter_deg`.
Image moving_box(float shutter_deg, bool move = true) {
  auto ctx = create_context(Backend::osmesa);
  RenderSettings s = black_settings();
  s.shutter_deg = shutter_deg;
  s.shutter_samples = 32;
  s.bloom.intensity = 0.f;
  Renderer r(*ctx, s);
  r.set_camera(test::front_camera());
  BoxDesc box;
  box.half_extents = Vec3f(0.3f, 0.005f, 0.3f);
  r.add_box(1, box);
  r.set_transform(1, Vec3f(-1.5f, 0.f, 0.f), Mat3f::Identity());
  (void)r.render();
  if (move) r.set_transform(1, Vec3f(0.f, 0.f, 0.f), Mat3f::Identity());
  Image img = r.render();
  dump(img, ("box_" + std::to_string(int(shutter_deg)) + (move ? "" : "_still")).c_str());
  return img;
}

TEST(MotionBlur, ABoxMovingAtConstantSpeedSmearsOverTheDistanceTheShutterSaw) {
  const Profile sharp = row_profile(moving_box(0.f));
  const Profile half = row_profile(moving_box(180.f));
  const Profile full = row_profile(moving_box(360.f));
  // 1.5 m at 10 m with a 40 degree vertical field of view on 120 rows: 1.5 / (2 * 10 *
  // tan(20 deg)) * 120 = 24.7 pixels of travel per frame; the shutter sees shutter/360 of it.
  const double travel = 1.5 / (2.0 * 10.0 * std::tan(20.0 * M_PI / 180.0)) * test::kHeight;
  // The leading edge is where the box is now; the trailing edge reaches back along the path.
  EXPECT_NEAR(half.last, sharp.last, 1);
  EXPECT_NEAR(full.last, sharp.last, 1);
  EXPECT_NEAR(sharp.first - half.first, travel / 2.0, 2.0);
  EXPECT_NEAR(sharp.first - full.first, travel, 2.0);
  // The same light, spread: the row's sum is kept.
  EXPECT_NEAR(half.sum / sharp.sum, 1.0, 0.03);
  EXPECT_NEAR(full.sum / sharp.sum, 1.0, 0.03);
  // Nothing moved: the shutter changes nothing, bit for bit.
  EXPECT_EQ(moving_box(180.f, false).rgba, moving_box(0.f, false).rgba);
}

TEST(MotionBlur, IsTheSameBytesEveryRun) {
  EXPECT_EQ(moving_box(180.f).rgba, moving_box(180.f).rgba);
}

}  // namespace
}  // namespace simreel::render
