// What the renderer draws: orientation of the returned image, boxes, particles, errors.
#include <gtest/gtest.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "render_test_util.hpp"
#include "simreel/render/context.hpp"
#include "simreel/render/renderer.hpp"

namespace simreel::render {
namespace {

using test::Blob;
using test::find_blob;
using test::is_warm;

int luminance(const std::uint8_t* p) { return (2 * p[0] + 5 * p[1] + p[2]) / 8; }
bool is_red(const std::uint8_t* p) { return int(p[0]) > int(p[1]) + 60 && int(p[0]) > int(p[2]) + 60; }

class RenderScene : public ::testing::Test {
 protected:
  void SetUp() override {
    context_ = create_context(Backend::osmesa);
    renderer_ = std::make_unique<Renderer>(*context_, test::small_settings());
    renderer_->set_camera(test::front_camera());
  }
  Renderer& r() { return *renderer_; }
  void add_box_at(ObjectKey key, const Vec3f& t, float half = 0.5f) {
    BoxDesc box;
    box.half_extents = Vec3f::Constant(half);
    r().add_box(key, box);
    r().set_transform(key, t, Mat3f::Identity());
  }
  void add_particle(ObjectKey key, const Vec3f& p, float radius, const Vec4f& color,
                    ParticleStyle style) {
    const float pos[] = {p.x(), p.y(), p.z()};
    const float col[] = {color.x(), color.y(), color.z(), color.w()};
    r().set_particles(key, ParticleBatch{1, pos, col, &radius, style});
  }
  const std::uint8_t* centre(const Image& img) { return img.pixel(img.width / 2, img.height / 2); }

  std::unique_ptr<Context> context_;
  std::unique_ptr<Renderer> renderer_;
};

TEST_F(RenderScene, ImageHasTheSettingsSizeAndOpaqueAlpha) {
  const Image img = r().render();
  ASSERT_EQ(img.width, test::kWidth);
  ASSERT_EQ(img.height, test::kHeight);
  ASSERT_EQ(img.rgba.size(), std::size_t(test::kWidth) * test::kHeight * 4);
  for (std::size_t i = 3; i < img.rgba.size(); i += 4) ASSERT_EQ(img.rgba[i], 255) << i;
}

TEST_F(RenderScene, SkyTopRowIsBluerThanBottomRow) {
  const Image img = r().render();
  auto blueness = [&](int y) {
    long sum = 0;
    for (int x = 0; x < img.width; ++x) sum += int(img.pixel(x, y)[2]) - int(img.pixel(x, y)[0]);
    return double(sum) / img.width;
  };
  EXPECT_GT(blueness(0), blueness(img.height - 1) + 20.0);
}

TEST_F(RenderScene, BoxHighInTheViewIsInTheTopRows) {
  add_box_at(10, Vec3f(0.f, 0.f, 2.2f));
  const Blob b = find_blob(r().render(), is_warm);
  ASSERT_GT(b.count, 20);
  EXPECT_LT(b.y, test::kHeight * 0.25);
  EXPECT_NEAR(b.x, test::kWidth / 2.0, 3.0);
}

TEST_F(RenderScene, BoxOnTheLeftIsOnTheLeft) {
  add_box_at(10, Vec3f(-2.5f, 0.f, 0.f));
  const Blob b = find_blob(r().render(), is_warm);
  ASSERT_GT(b.count, 20);
  EXPECT_LT(b.x, test::kWidth * 0.3);
  EXPECT_NEAR(b.y, test::kHeight / 2.0, 3.0);
}

TEST_F(RenderScene, SetTransformMovesTheBox) {
  add_box_at(10, Vec3f(0.f, 0.f, 0.f));
  const Blob before = find_blob(r().render(), is_warm);
  r().set_transform(10, Vec3f(1.f, 0.f, -0.5f), Mat3f::Identity());
  const Blob after = find_blob(r().render(), is_warm);
  ASSERT_GT(before.count, 20);
  ASSERT_GT(after.count, 20);
  EXPECT_GT(after.x - before.x, 5.0);  // +x is to the right
  EXPECT_GT(after.y - before.y, 2.0);  // -z is down the image
}

TEST_F(RenderScene, RemovedBoxIsNotDrawn) {
  add_box_at(10, Vec3f::Zero());
  ASSERT_GT(find_blob(r().render(), is_warm).count, 20);
  r().remove(10);
  EXPECT_EQ(find_blob(r().render(), is_warm).count, 0);
  EXPECT_NO_THROW(r().remove(10));  // removing twice is harmless
}

TEST_F(RenderScene, SoftRedParticleAtTheCentreIsRed) {
  add_particle(20, Vec3f::Zero(), 0.5f, Vec4f(1.f, 0.f, 0.f, 1.f), ParticleStyle::soft);
  const Image img = r().render();
  EXPECT_TRUE(is_red(centre(img))) << int(centre(img)[0]) << "," << int(centre(img)[1]) << ","
                                   << int(centre(img)[2]);
}

TEST_F(RenderScene, ParticleGrowsWithItsRadius) {
  add_particle(20, Vec3f::Zero(), 0.4f, Vec4f(1.f, 0.f, 0.f, 1.f), ParticleStyle::soft);
  const int small = find_blob(r().render(), is_red).count;
  add_particle(20, Vec3f::Zero(), 0.8f, Vec4f(1.f, 0.f, 0.f, 1.f), ParticleStyle::soft);
  const int large = find_blob(r().render(), is_red).count;
  ASSERT_GT(small, 10);
  EXPECT_GT(large, 3 * small);  // area ~ radius^2
}

TEST_F(RenderScene, EmptyParticleBatchDrawsNothing) {
  const Image empty = r().render();
  r().set_particles(20, ParticleBatch{0, nullptr, nullptr, nullptr, ParticleStyle::soft});
  EXPECT_EQ(r().render().rgba, empty.rgba);
  add_particle(20, Vec3f::Zero(), 0.5f, Vec4f(1.f, 0.f, 0.f, 1.f), ParticleStyle::soft);
  EXPECT_NE(r().render().rgba, empty.rgba);
  r().set_particles(20, ParticleBatch{0, nullptr, nullptr, nullptr, ParticleStyle::soft});
  EXPECT_EQ(r().render().rgba, empty.rgba);
}

TEST_F(RenderScene, AdditiveParticleBrightensTheBackground) {
  const Image before = r().render();
  add_particle(20, Vec3f::Zero(), 0.8f, Vec4f(1.f, 0.6f, 0.2f, 1.f), ParticleStyle::additive);
  const Image after = r().render();
  EXPECT_GT(luminance(centre(after)), luminance(centre(before)) + 15);
  for (int c = 0; c < 3; ++c) EXPECT_GE(centre(after)[c], centre(before)[c]) << c;
}

TEST_F(RenderScene, SoftParticlesAreSortedBackToFront) {
  // Far green behind near red, given far-last: the near red one must still cover the centre.
  const float pos[] = {0.f, -2.f, 0.f, 0.f, 2.f, 0.f};
  const float col[] = {1.f, 0.f, 0.f, 1.f, 0.f, 1.f, 0.f, 1.f};
  const float rad[] = {0.5f, 0.5f};
  r().set_particles(20, ParticleBatch{2, pos, col, rad, ParticleStyle::soft});
  EXPECT_TRUE(is_red(centre(r().render())));
  // The same split over two batches, the far one under the larger key.
  r().set_particles(20, ParticleBatch{1, pos, col, rad, ParticleStyle::soft});
  r().set_particles(21, ParticleBatch{1, pos + 3, col + 4, rad + 1, ParticleStyle::soft});
  EXPECT_TRUE(is_red(centre(r().render())));
}

TEST_F(RenderScene, BoxHidesParticleBehindIt) {
  add_box_at(10, Vec3f::Zero(), 0.6f);
  add_particle(20, Vec3f(0.f, 3.f, 0.f), 0.4f, Vec4f(0.f, 0.f, 1.f, 1.f), ParticleStyle::soft);
  EXPECT_TRUE(is_warm(centre(r().render())));
}

// Blended particles are drawn after the multisampled scene is resolved, their depth test in
// their shaders against a single-sample copy of the scene depth (ParticlePass::draw_blended): a
// soft particle or a rain streak in front of the box covers it, one behind it is hidden, with
// and without multisampling.
TEST_F(RenderScene, BlendedParticlesMeetTheBoxesDepthAfterTheResolve) {
  for (const int samples : {4, 0}) {
    for (const ParticleStyle style : {ParticleStyle::soft, ParticleStyle::streak}) {
      SCOPED_TRACE(testing::Message() << "samples " << samples << ", style " << int(style));
      RenderSettings s = test::small_settings();
      s.msaa_samples = samples;
      renderer_ = std::make_unique<Renderer>(*context_, s);
      r().set_camera(test::front_camera());
      add_box_at(10, Vec3f::Zero(), 0.6f);
      auto blue = [](const std::uint8_t* p) { return int(p[2]) > int(p[0]) + 60; };
      for (const float y : {-2.f, 3.f}) {
        if (style == ParticleStyle::soft) {
          add_particle(20, Vec3f(0.f, y, 0.f), 0.4f, Vec4f(0.f, 0.f, 1.f, 1.f), style);
        } else {
          // Falling at 20 m/s: the streak runs from its head 0.2 m below the centre to 0.2 m above.
          const float pos[] = {0.f, y, -0.2f}, col[] = {0.f, 0.f, 1.f, 1.f}, vel[] = {0.f, 0.f, -20.f};
          const float radius = 0.3f;
          ParticleBatch batch{1, pos, col, &radius, style};
          batch.velocity = vel;
          r().set_particles(20, batch);
        }
        const Image img = r().render();
        const std::uint8_t* c = centre(img);
        if (y < 0.f) {
          EXPECT_TRUE(blue(c)) << "in front: " << int(c[0]) << " " << int(c[1]) << " " << int(c[2]);
        } else {
          EXPECT_TRUE(is_warm(c)) << "behind: " << int(c[0]) << " " << int(c[1]) << " " << int(c[2]);
        }
      }
    }
  }
}

TEST_F(RenderScene, RenderingIsDeterministic) {
  test::build_small_scene(r());
  r().set_camera(Camera{});
  const Image a = r().render();
  const Image b = r().render();
  EXPECT_EQ(a.rgba, b.rgba);
}

TEST_F(RenderScene, KeyErrors) {
  add_box_at(10, Vec3f::Zero());
  EXPECT_THROW(r().set_transform(99, Vec3f::Zero(), Mat3f::Identity()), std::out_of_range);
  EXPECT_THROW(r().add_box(10, BoxDesc{}), std::invalid_argument);
  EXPECT_THROW(r().add_plane(10, PlaneDesc{}), std::invalid_argument);
  add_particle(20, Vec3f::Zero(), 0.5f, Vec4f::Ones(), ParticleStyle::soft);
  EXPECT_THROW(r().add_box(20, BoxDesc{}), std::invalid_argument);
  EXPECT_THROW(add_particle(10, Vec3f::Zero(), 0.5f, Vec4f::Ones(), ParticleStyle::soft),
               std::invalid_argument);
  EXPECT_THROW(r().set_particles(21, ParticleBatch{2, nullptr, nullptr, nullptr}),
               std::invalid_argument);
}

TEST_F(RenderScene, BadCameraIsRejected) {
  Camera c = test::front_camera();
  c.fov_deg = 180.f;
  EXPECT_THROW(r().set_camera(c), std::invalid_argument);
  c = test::front_camera();
  c.target = c.position;
  EXPECT_THROW(r().set_camera(c), std::invalid_argument);
}

TEST(RenderSettingsCheck, ZeroSizeIsRejected) {
  const auto context = create_context(Backend::osmesa);
  RenderSettings s = test::small_settings();
  s.width = 0;
  EXPECT_THROW(Renderer(*context, s), std::invalid_argument);
}

TEST(RenderSettingsCheck, FramebufferBeyondTheLimitIsAContextError) {
  const auto context = create_context(Backend::osmesa);
  RenderSettings s = test::small_settings();
  s.width = 1 << 20;  // above any GL_MAX_TEXTURE_SIZE / GL_MAX_RENDERBUFFER_SIZE
  s.height = 1;
  try {
    Renderer r(*context, s);
    FAIL() << "a 2^20-pixel-wide framebuffer was accepted";
  } catch (const ContextError& e) {
    EXPECT_NE(std::string(e.what()).find("framebuffer"), std::string::npos) << e.what();
  }
  // The context is still usable afterwards.
  Renderer ok(*context, test::small_settings());
  EXPECT_EQ(ok.render().width, test::kWidth);
}

TEST(RenderSettingsCheck, WithoutMultisamplingStillRenders) {
  const auto context = create_context(Backend::osmesa);
  RenderSettings s = test::small_settings();
  s.msaa_samples = 0;
  Renderer r(*context, s);
  r.set_camera(test::front_camera());
  BoxDesc box;
  r.add_box(1, box);
  EXPECT_TRUE(is_warm(r.render().pixel(test::kWidth / 2, test::kHeight / 2)));
}

}  // namespace
}  // namespace simreel::render
