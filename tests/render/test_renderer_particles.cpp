// Particle styles beyond the basic sprite: depth fade against geometry, velocity streaks,
// opaque droplets, sun-lit smoke, particle shadows, a million particles, and the two
// backends drawing all of it byte for byte alike.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "render_test_util.hpp"
#include "simreel/render/context.hpp"
#include "simreel/render/mesh.hpp"
#include "simreel/render/renderer.hpp"

namespace simreel::render {
namespace {

int luminance(const std::uint8_t* p) { return (2 * p[0] + 5 * p[1] + p[2]) / 8; }

class ParticleScene : public ::testing::Test {
 protected:
  void SetUp() override { make(test::small_settings()); }
  void make(const RenderSettings& s) {
    renderer_.reset();
    if (!context_) context_ = create_context(Backend::osmesa);
    renderer_ = std::make_unique<Renderer>(*context_, s);
    renderer_->set_camera(test::front_camera());
  }
  Renderer& r() { return *renderer_; }
  void one(ObjectKey key, const Vec3f& p, float radius, const Vec4f& color, ParticleStyle style,
           const Vec3f& velocity = Vec3f::Zero(), float streak_s = 0.f) {
    const float pos[] = {p.x(), p.y(), p.z()};
    const float col[] = {color.x(), color.y(), color.z(), color.w()};
    const float vel[] = {velocity.x(), velocity.y(), velocity.z()};
    ParticleBatch b{1, pos, col, &radius, style};
    b.velocity = vel;
    b.streak_s = streak_s;
    r().set_particles(key, b);
  }
  std::unique_ptr<Context> context_;
  std::unique_ptr<Renderer> renderer_;
};

/// Bounding box (width, height) of the pixels that differ from `background` by more than 12.
std::pair<int, int> changed_extent(const Image& img, const Image& background) {
  int x0 = img.width, x1 = -1, y0 = img.height, y1 = -1;
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      int d = 0;
      for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int(img.pixel(x, y)[c]) - int(background.pixel(x, y)[c])));
      if (d > 12) {
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
      }
    }
  }
  return {std::max(x1 - x0 + 1, 0), std::max(y1 - y0 + 1, 0)};
}

TEST_F(ParticleScene, SoftSpriteMeetsAPlaneWithoutAHardLine) {
  // A red smoke ball half sunk into a wall that faces the camera obliquely: where the sphere
  // passes through the wall the sprite must fade out gradually, not end on an edge.
  Camera cam = test::front_camera();
  cam.position = Vec3f(0.f, -10.f, 4.f);
  r().set_camera(cam);
  PlaneDesc ground;  // z = 0, seen from above at ~22 degrees
  ground.checker_m = 0.f;
  ground.color = Vec4f(0.2f, 0.2f, 0.2f, 1.f);
  r().add_plane(1, ground);
  const Image empty = r().render();
  one(2, Vec3f::Zero(), 1.2f, Vec4f(1.f, 0.1f, 0.05f, 0.97f), ParticleStyle::soft);
  const Image img = r().render();
  // Down the sprite's centre column: from the sprite centre to below the sprite, red falls
  // from sprite to ground; no single row may carry a large share of that fall.
  const int x = test::kWidth / 2;
  int top = -1;
  for (int y = 0; y < img.height && top < 0; ++y) {
    if (std::abs(int(img.pixel(x, y)[0]) - int(empty.pixel(x, y)[0])) > 12) top = y;
  }
  ASSERT_GE(top, 0);
  int centre_y = -1, lowest = -1;
  for (int y = img.height - 1; y >= 0 && lowest < 0; --y) {
    if (std::abs(int(img.pixel(x, y)[0]) - int(empty.pixel(x, y)[0])) > 12) lowest = y;
  }
  centre_y = (top + lowest) / 2;
  const int total = int(img.pixel(x, centre_y)[0]) - int(img.pixel(x, lowest + 2)[0]);
  ASSERT_GT(total, 80) << "the sprite should stand out from the ground";
  int worst = 0;
  for (int y = centre_y; y <= lowest + 2; ++y) {
    worst = std::max(worst, std::abs(int(img.pixel(x, y + 1)[0]) - int(img.pixel(x, y)[0])));
  }
  EXPECT_LT(worst, total / 4) << "largest row-to-row step " << worst << " of a total fall of " << total;
}

TEST_F(ParticleScene, StreaksStretchAlongTheirVelocity) {
  const Image empty = r().render();
  const Vec4f white(1.f, 1.f, 1.f, 1.f);
  one(1, Vec3f::Zero(), 0.06f, white, ParticleStyle::streak, Vec3f(8.f, 0.f, 0.f), 0.25f);  // 2 m long
  const auto [wx, hx] = changed_extent(r().render(), empty);
  one(1, Vec3f::Zero(), 0.06f, white, ParticleStyle::streak, Vec3f(0.f, 0.f, -8.f), 0.25f);
  const auto [wz, hz] = changed_extent(r().render(), empty);
  ASSERT_GT(hx, 0);
  ASSERT_GT(wz, 0);
  EXPECT_GE(double(wx) / hx, 5.0) << wx << "x" << hx;
  EXPECT_GE(double(hz) / wz, 5.0) << wz << "x" << hz;
  // The tail trails behind: falling rain (velocity -z) extends above its head.
  one(1, Vec3f::Zero(), 0.06f, white, ParticleStyle::streak, Vec3f(0.f, 0.f, -8.f), 0.25f);
  const Image falling = r().render();
  double sum_y = 0.0;
  int count = 0;
  for (int y = 0; y < falling.height; ++y) {
    for (int x = 0; x < falling.width; ++x) {
      if (std::abs(int(falling.pixel(x, y)[0]) - int(empty.pixel(x, y)[0])) > 12) sum_y += y, ++count;
    }
  }
  ASSERT_GT(count, 0);
  EXPECT_LT(sum_y / count, test::kHeight / 2.0 - 5.0);
  // Without a velocity a streak is a round sprite.
  one(1, Vec3f::Zero(), 0.3f, white, ParticleStyle::streak);
  const auto [w0, h0] = changed_extent(r().render(), empty);
  EXPECT_NEAR(w0, h0, 2) << w0 << "x" << h0;
}

TEST_F(ParticleScene, DropletIsAnOpaqueSunlitSphere) {
  Light sun;
  sun.direction = Vec3f(1.f, 0.f, 0.f);  // travels +x: the droplet's left side is lit
  r().set_light(sun);
  one(1, Vec3f::Zero(), 1.f, Vec4f(0.9f, 0.1f, 0.1f, 0.1f), ParticleStyle::droplet);  // alpha ignored
  const Image img = r().render();
  const int cx = test::kWidth / 2, cy = test::kHeight / 2;
  const std::uint8_t* centre = img.pixel(cx, cy);
  EXPECT_GT(centre[0], centre[2] + 60);
  EXPECT_GT(luminance(img.pixel(cx - 10, cy)), luminance(img.pixel(cx + 10, cy)) + 15);
  // Opaque: a droplet hides a soft particle behind it completely, without sorting.
  one(2, Vec3f(0.f, 3.f, 0.f), 1.f, Vec4f(0.f, 1.f, 0.f, 1.f), ParticleStyle::soft);
  const Image both = r().render();
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(int(both.pixel(cx, cy)[c]), int(centre[c]), 1);
}

TEST_F(ParticleScene, SmokeIsDarkerOnTheSideAwayFromTheSun) {
  Light sun;
  sun.direction = Vec3f(1.f, 0.f, -0.2f);
  r().set_light(sun);
  one(1, Vec3f::Zero(), 1.f, Vec4f(0.7f, 0.7f, 0.7f, 0.6f), ParticleStyle::soft);
  const Image img = r().render();
  const int cx = test::kWidth / 2, cy = test::kHeight / 2;
  EXPECT_GT(luminance(img.pixel(cx - 9, cy)), luminance(img.pixel(cx + 9, cy)) + 15);
}

TEST_F(ParticleScene, DenserSmokeIsMoreOpaque) {
  PlaneDesc wall;  // a dark wall behind, facing the camera
  wall.point = Vec3f(0.f, 3.f, 0.f);
  wall.normal = Vec3f(0.f, -1.f, 0.f);
  wall.checker_m = 0.f;
  wall.color = Vec4f(0.02f, 0.02f, 0.02f, 1.f);
  r().add_plane(1, wall);
  auto centre_luminance = [&](float alpha) {
    one(2, Vec3f::Zero(), 1.f, Vec4f(1.f, 1.f, 1.f, alpha), ParticleStyle::soft);
    const Image img = r().render();
    return luminance(img.pixel(test::kWidth / 2, test::kHeight / 2));
  };
  const int thin = centre_luminance(0.2f), dense = centre_luminance(0.8f);
  EXPECT_GT(dense, thin + 40);
}

TEST_F(ParticleScene, ParticleShadowsAreASetting) {
  Camera top;
  top.position = Vec3f(0.f, 0.f, 10.f);
  top.target = Vec3f::Zero();
  top.up = Vec3f::UnitY();
  PlaneDesc ground;
  ground.checker_m = 0.f;
  std::vector<float> pos, col, rad;
  for (int i = 0; i < 9; ++i) {  // a dense cloud 2 m above the origin
    pos.insert(pos.end(), {0.3f * float(i % 3 - 1), 0.3f * float(i / 3 - 1), 2.f});
    col.insert(col.end(), {0.8f, 0.8f, 0.8f, 1.f});
    rad.push_back(0.3f);
  }
  Light sun;
  sun.direction = Vec3f(0.f, 0.3f, -1.f);  // the shadow falls at y ~ -0.6 m, beside the cloud
  int ground_luminance[2];
  for (const bool shadows : {false, true}) {
    RenderSettings s = test::small_settings();
    s.particle_shadows = shadows;
    make(s);
    r().set_camera(top);
    r().set_light(sun);
    r().add_plane(1, ground);
    r().set_particles(2, ParticleBatch{9, pos.data(), col.data(), rad.data(), ParticleStyle::soft});
    const Image img = r().render();
    // The shadow covers y in [0, 1.2] m on the ground; the cloud itself hides the ground
    // up to y = 0.75 m from this eye, so probe at y = 0.95 m (16 pixels above the centre).
    ground_luminance[shadows] = luminance(img.pixel(test::kWidth / 2, test::kHeight / 2 - 16));
  }
  EXPECT_GT(ground_luminance[0], ground_luminance[1] + 25);
}

TEST(ParticleMillion, OneMillionSoftParticlesRender) {
  const auto context = create_context(Backend::osmesa);
  RenderSettings s;
  s.width = 48;
  s.height = 32;
  s.msaa_samples = 0;
  Renderer r(*context, s);
  r.set_camera(test::front_camera());
  const Image empty = r.render();
  const std::size_t n = 1'000'000;
  std::vector<float> pos(3 * n), col(4 * n), rad(n, 0.01f);
  std::uint32_t state = 12345u;
  auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return float(state >> 8) / float(1u << 24);
  };
  for (std::size_t i = 0; i < n; ++i) {
    pos[3 * i] = 4.f * next() - 2.f;
    pos[3 * i + 1] = 4.f * next() - 2.f;
    pos[3 * i + 2] = 4.f * next() - 2.f;
    col[4 * i] = 1.f, col[4 * i + 1] = 0.5f, col[4 * i + 2] = 0.1f, col[4 * i + 3] = 0.8f;
  }
  r.set_particles(1, ParticleBatch{n, pos.data(), col.data(), rad.data(), ParticleStyle::soft});
  Image img;
  ASSERT_NO_THROW(img = r.render());
  // The 4 m cube of particles covers the frame's centre with orange.
  const std::uint8_t* c = img.pixel(s.width / 2, s.height / 2);
  EXPECT_GT(int(c[0]), int(c[2]) + 60) << int(c[0]) << "," << int(c[1]) << "," << int(c[2]);
  EXPECT_NE(img.rgba, empty.rgba);
}

/// Every new feature in one small frame: both backends must give the same bytes.
Image feature_frame(Backend backend) {
  const auto context = create_context(backend);
  RenderSettings s = test::small_settings();
  s.particle_shadows = true;
  Renderer r(*context, s);
  test::build_small_scene(r);
  r.set_camera(Camera{});
  MeshDesc sphere = make_sphere_mesh(0.4f, 16);
  sphere.material.checker_m = 0.2f;
  r.add_mesh(10, sphere);
  r.set_transform(10, Vec3f(-1.2f, 0.8f, 0.6f), Mat3f::Identity());
  MeshDesc cloth = make_cylinder_mesh(0.3f, 0.5f, 12);
  cloth.material.double_sided = true;
  cloth.material.texture_rgba = {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255};
  cloth.material.texture_width = cloth.material.texture_height = 2;
  cloth.dynamic = true;
  r.add_mesh(11, cloth);
  r.update_mesh(11, cloth.positions);
  r.set_transform(11, Vec3f(1.2f, 1.f, 0.5f), Mat3f::Identity());
  const float pos[] = {0.f, -1.f, 2.5f, 0.3f, -1.2f, 2.2f};
  const float vel[] = {1.f, 0.f, -6.f, 0.f, 0.f, -6.f};
  const float col[] = {0.6f, 0.7f, 0.9f, 0.6f, 0.6f, 0.7f, 0.9f, 0.6f};
  const float rad[] = {0.02f, 0.02f};
  ParticleBatch rain{2, pos, col, rad, ParticleStyle::streak};
  rain.velocity = vel;
  rain.streak_s = 0.05f;
  r.set_particles(20, rain);
  const float dpos[] = {-0.5f, -1.f, 1.f};
  const float drad[] = {0.08f};
  r.set_particles(21, ParticleBatch{1, dpos, col, drad, ParticleStyle::droplet});
  // The particles' look (issue 14): a glowing trail, a textured flame, a textured smoke puff and
  // a sub-pixel spark.
  const float fpos[] = {0.8f, -1.f, 1.8f, -0.8f, -0.5f, 1.6f, 0.2f, -2.f, 1.4f};
  const float fvel[] = {3.f, 0.f, 2.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f};
  const float frad[] = {0.05f, 0.35f, 0.004f};
  const float fage[] = {0.1f, 0.4f, 0.2f};
  const float flife[] = {1.f, 1.f, 1.f};
  ParticleBatch trail{1, fpos, col, frad, ParticleStyle::additive};
  trail.velocity = fvel;
  trail.trail_s = 0.2f;
  trail.emissive = 2.f;
  r.set_particles(22, trail);
  ParticleBatch flame{1, fpos + 3, col, frad + 1, ParticleStyle::additive};
  flame.age = fage + 1;
  flame.lifetime = flife;
  flame.texture = ParticleTexture::flame;
  r.set_particles(23, flame);
  ParticleBatch smoke{1, fpos + 3, col, frad + 1, ParticleStyle::soft};
  smoke.age = fage + 1;
  smoke.lifetime = flife;
  smoke.texture = ParticleTexture::smoke;
  r.set_particles(24, smoke);
  r.set_particles(25, ParticleBatch{1, fpos + 6, col, frad + 2, ParticleStyle::additive});
  return r.render();
}

TEST(ParticleBackends, OsmesaAndEglDrawEveryFeatureAlike) {
  const Image a = feature_frame(Backend::osmesa);
  const Image b = feature_frame(Backend::egl);
  EXPECT_EQ(a.rgba, b.rgba);
}

}  // namespace
}  // namespace simreel::render
