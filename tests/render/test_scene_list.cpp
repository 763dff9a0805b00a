// Renderer::apply(SceneList) draws exactly what the direct calls it stands for draw.
#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Geometry>

#include "render_test_util.hpp"
#include "simreel/render/context.hpp"
#include "simreel/render/mesh.hpp"
#include "simreel/render/renderer.hpp"
#include "simreel/render/scene_list.hpp"

namespace simreel::render {
namespace {

constexpr ObjectKey kPlane = 1, kBox = 2, kCloth = 3, kSmoke = 4, kRain = 5;

/// Three frames of a small scene, as SceneLists: everything added (with poses) in the first,
/// moves, new particles, new cloth vertices and a new camera in the second, the box removed in
/// the third. The arrays the lists view live here.
struct Frames {
  MeshDesc cloth = make_sphere_mesh(0.6f, 12);
  std::vector<float> cloth_moved;
  std::vector<std::vector<float>> pos, col, rad, vel;
  std::vector<std::vector<float>> rain_pos;
  Camera camera2;

  Frames() {
    cloth.dynamic = true;
    cloth.material.base_color = Vec4f(0.3f, 0.6f, 0.35f, 1.f);
    cloth.material.double_sided = true;
    cloth_moved = cloth.positions;
    for (std::size_t i = 2; i < cloth_moved.size(); i += 3) cloth_moved[i] *= 0.6f;  // squashed
    for (int f = 0; f < 3; ++f) {
      const float s = 0.3f * float(f);
      pos.push_back({0.5f + s, -1.f, 1.5f, -1.f, 0.5f, 1.8f - s, 0.2f, 0.f, 1.f});
      col.push_back({0.2f, 0.3f, 0.9f, 0.8f, 0.1f, 0.7f, 0.8f, 0.6f, 0.3f, 0.3f, 0.9f, 0.9f});
      rad.push_back({0.3f, 0.25f + 0.05f * float(f), 0.2f});
      rain_pos.push_back({-2.f + s, 0.f, 2.f, 2.f, 0.5f, 2.5f - s});
      vel.push_back({0.f, 0.f, -8.f, 1.f, 0.f, -9.f});
    }
    camera2 = test::front_camera();
    camera2.position = Vec3f(1.f, -9.f, 2.f);
  }

  ParticleBatch smoke(int f) const {
    return ParticleBatch{3, pos[std::size_t(f)].data(), col[std::size_t(f)].data(),
                         rad[std::size_t(f)].data(), ParticleStyle::soft};
  }
  ParticleBatch rain(int f) const {
    static const float kColor[] = {0.6f, 0.7f, 0.9f, 0.7f, 0.6f, 0.7f, 0.9f, 0.7f};
    static const float kRadius[] = {0.03f, 0.03f};
    ParticleBatch b{2, rain_pos[std::size_t(f)].data(), kColor, kRadius, ParticleStyle::streak};
    b.velocity = vel[std::size_t(f)].data();
    b.streak_s = 0.05f;
    return b;
  }
  static BoxDesc box() {
    BoxDesc b;
    b.half_extents = Vec3f(0.5f, 0.4f, 0.6f);
    b.color = Vec4f(0.9f, 0.4f, 0.1f, 1.f);  // warm: test::is_warm finds it
    return b;
  }
  static Mat3f box_rotation(int f) {
    return Eigen::AngleAxisf(0.3f * float(f + 1), Vec3f::UnitZ()).toRotationMatrix();
  }

  SceneList list(int f) const {
    SceneList l;
    if (f == 0) {
      SceneList::Added plane{kPlane, PlaneDesc{}};
      plane.has_transform = false;
      l.added.push_back(plane);
      l.added.push_back({kBox, box(), Vec3f(-1.2f, 0.f, 0.6f), box_rotation(f)});
      l.added.push_back({kCloth, cloth, Vec3f(1.2f, 0.f, 0.8f), Mat3f::Identity()});
    } else if (f == 1) {
      l.moved.push_back({kBox, Vec3f(-1.f, 0.5f, 0.7f), box_rotation(f)});
      l.moved.push_back({kCloth, Vec3f(1.3f, 0.f, 0.7f), Mat3f::Identity()});
      l.meshes.push_back({kCloth, cloth_moved, {}});
      l.camera = camera2;
    } else {
      l.removed.push_back(kBox);
    }
    l.particles.push_back({kSmoke, smoke(f)});
    l.particles.push_back({kRain, rain(f)});
    return l;
  }

  /// The same frame through the direct calls, in apply()'s documented order.
  void direct(Renderer& r, int f) const {
    if (f == 0) {
      r.add_plane(kPlane, PlaneDesc{});
      r.add_box(kBox, box());
      r.set_transform(kBox, Vec3f(-1.2f, 0.f, 0.6f), box_rotation(f));
      r.add_mesh(kCloth, cloth);
      r.set_transform(kCloth, Vec3f(1.2f, 0.f, 0.8f), Mat3f::Identity());
    } else if (f == 1) {
      r.set_transform(kBox, Vec3f(-1.f, 0.5f, 0.7f), box_rotation(f));
      r.set_transform(kCloth, Vec3f(1.3f, 0.f, 0.7f), Mat3f::Identity());
    } else {
      r.remove(kBox);
    }
    r.set_particles(kSmoke, smoke(f));
    r.set_particles(kRain, rain(f));
    if (f == 1) {
      r.update_mesh(kCloth, cloth_moved);
      r.set_camera(camera2);
    }
  }
};

/// Renders the three frames in a fresh context and renderer, each frame set up by `step`.
std::vector<Image> render_frames(const std::function<void(Renderer&, int)>& step) {
  const std::unique_ptr<Context> context = create_context(Backend::osmesa);
  Renderer r(*context, test::small_settings());
  r.set_camera(test::front_camera());
  std::vector<Image> images;
  for (int f = 0; f < 3; ++f) {
    step(r, f);
    images.push_back(r.render());
  }
  return images;
}

TEST(RenderSceneList, ApplyDrawsTheDirectCallsFramesByteForByte) {
  const Frames frames;
  const std::vector<Image> direct = render_frames([&](Renderer& r, int f) { frames.direct(r, f); });
  const std::vector<Image> applied = render_frames([&](Renderer& r, int f) { r.apply(frames.list(f)); });
  ASSERT_EQ(direct.size(), applied.size());
  for (std::size_t f = 0; f < direct.size(); ++f) {
    EXPECT_TRUE(direct[f].rgba == applied[f].rgba) << "frame " << f;
  }
  // The box shows until its removal; the frames differ, so the comparison has teeth.
  EXPECT_GT(test::find_blob(applied[0], test::is_warm).count, 200);
  EXPECT_GT(test::find_blob(applied[1], test::is_warm).count, 200);
  EXPECT_EQ(test::find_blob(applied[2], test::is_warm).count, 0);
  EXPECT_FALSE(applied[0].rgba == applied[1].rgba);
}

TEST(RenderSceneList, ClearEmptiesEveryList) {
  const Frames frames;
  SceneList l = frames.list(0);
  l.camera = test::front_camera();
  l.removed.push_back(9);
  l.clear();
  EXPECT_TRUE(l.added.empty() && l.moved.empty() && l.removed.empty() && l.particles.empty() &&
              l.meshes.empty() && !l.camera.has_value());
}

}  // namespace
}  // namespace simreel::render
