// The sim -> render glue without GL (scene_list_builder.hpp): the SceneLists built from a scene
// and the engine's output, read as plain data. No render::Context is created in this file.
#include <gtest/gtest.h>

#include <string>
#include <variant>

#include "json_reader.hpp"
#include "scene.hpp"
#include "scene_list_builder.hpp"

using simreel::app::append_frame;
using simreel::app::append_moved;
using simreel::app::build_world;
using simreel::app::initial_scene_list;
using simreel::app::json;
using simreel::app::Scene;
using simreel::app::scene_from_json;
using simreel::app::SceneWorld;
namespace render = simreel::render;
namespace sim = simreel::sim;

namespace {

// A scene file placed in demos/scenes/ so that a mesh collider's "file" resolves like a demo's.
const std::string kSceneFile = std::string(SIMREEL_SOURCE_DIR) + "/demos/scenes/glue_test.json";

Scene scene_of(const char* text) { return scene_from_json(json::parse(text), kSceneFile); }

bool near(const render::Vec3f& a, const sim::Vec3& b) { return (a - b.cast<float>()).norm() < 1e-6f; }
bool near(const render::Mat3f& a, const sim::Mat3& b) { return (a - b.cast<float>()).norm() < 1e-6f; }

}  // namespace

TEST(SceneList, InitialListHasOneAddedPerColliderAndClothInSceneOrder) {
  const Scene scene = scene_of(R"({
    "colliders": [
      {"type": "plane", "point": [0, 0, 0.5], "normal": [0, 0, 2], "draw_half_size": 7, "checker_m": 0.5},
      {"type": "box", "position": [1, 2, 3], "rotation_deg": [0, 0, 90], "half_extents": [0.5, 0.25, 0.125]},
      {"type": "sphere", "position": [-1, 0, 1], "radius": 0.3},
      {"type": "cylinder", "position": [0, -1, 1], "radius": 0.2, "half_height": 0.4},
      {"type": "mesh", "file": "../../assets/models/rock.obj", "position": [0, 0, 0.1], "scale": [2, 1, 1]}
    ],
    "cloths": [{"rows": 4, "columns": 5, "position": [0, 0, 2]}]
  })");
  const SceneWorld sw = build_world(scene);
  const render::SceneList list = initial_scene_list(scene, sw);

  ASSERT_EQ(list.added.size(), 6u);
  EXPECT_TRUE(list.moved.empty());
  EXPECT_TRUE(list.removed.empty());
  EXPECT_TRUE(list.particles.empty());
  EXPECT_TRUE(list.meshes.empty());
  EXPECT_FALSE(list.camera.has_value()) << "the player sets the camera before the drawables";
  for (std::size_t i = 0; i < 5; ++i) EXPECT_EQ(list.added[i].key, sw.colliders[i].id.packed()) << i;
  EXPECT_EQ(list.added[5].key, sw.cloths[0].id.packed());

  // Plane: world-frame desc, unit normal, no transform.
  const auto* plane = std::get_if<render::PlaneDesc>(&list.added[0].desc);
  ASSERT_NE(plane, nullptr);
  EXPECT_FALSE(list.added[0].has_transform);
  EXPECT_TRUE(near(plane->point, sim::Vec3(0, 0, 0.5)));
  EXPECT_TRUE(near(plane->normal, sim::Vec3(0, 0, 1)));
  EXPECT_FLOAT_EQ(plane->half_size, 7.f);
  EXPECT_FLOAT_EQ(plane->checker_m, 0.5f);

  // Box: half extents and the pose the engine reports.
  const auto* box = std::get_if<render::BoxDesc>(&list.added[1].desc);
  ASSERT_NE(box, nullptr);
  EXPECT_TRUE(near(box->half_extents, sim::Vec3(0.5, 0.25, 0.125)));
  EXPECT_TRUE(list.added[1].has_transform);
  const sim::MovedObject box_pose = sw.world.pose(sw.colliders[1]);
  EXPECT_TRUE(near(list.added[1].translation, box_pose.translation));
  EXPECT_TRUE(near(list.added[1].rotation, box_pose.rotation));
  EXPECT_TRUE(near(list.added[1].translation, sim::Vec3(1, 2, 3)));

  // Sphere, cylinder and mesh collider are meshes placed at their pose.
  for (std::size_t i = 2; i < 5; ++i) {
    const auto* mesh = std::get_if<render::MeshDesc>(&list.added[i].desc);
    ASSERT_NE(mesh, nullptr) << i;
    EXPECT_TRUE(list.added[i].has_transform) << i;
    EXPECT_FALSE(mesh->dynamic) << i;
    EXPECT_EQ(mesh->positions.size() % 3, 0u) << i;
    EXPECT_GT(mesh->indices.size(), 0u) << i;
    EXPECT_TRUE(near(list.added[i].translation, sw.world.pose(sw.colliders[i]).translation)) << i;
  }
  // The mesh collider's drawable is the imported file, scaled into the collider's local frame.
  const auto& rock = std::get<render::MeshDesc>(list.added[4].desc);
  const auto& asset = *scene.colliders[4].mesh_asset;
  ASSERT_EQ(rock.positions.size(), 3 * asset.positions.size());
  EXPECT_FLOAT_EQ(rock.positions[0], 2.f * asset.positions[0].x());
  EXPECT_FLOAT_EQ(rock.positions[1], asset.positions[0].y());
  EXPECT_TRUE(rock.material.double_sided);

  // Cloth: a dynamic mesh of rows x columns vertices in the world frame.
  const auto* cloth = std::get_if<render::MeshDesc>(&list.added[5].desc);
  ASSERT_NE(cloth, nullptr);
  EXPECT_FALSE(list.added[5].has_transform);
  EXPECT_TRUE(cloth->dynamic);
  EXPECT_EQ(cloth->positions.size(), 3u * 4u * 5u);
  EXPECT_EQ(cloth->normals.size(), 3u * 4u * 5u);
  EXPECT_EQ(cloth->uvs.size(), 2u * 4u * 5u);
}

TEST(SceneList, MovedHoldsTheKinematicBoxWithThePoseTheWorldReports) {
  const Scene scene = scene_of(R"({
    "colliders": [
      {"type": "plane"},
      {"type": "box", "half_extents": [0.2, 0.2, 0.2],
       "path": {"smooth": false, "keys": [{"time": 0, "position": [0, 0, 1]},
                                          {"time": 1, "position": [3, 0, 1], "rotation_deg": [0, 0, 90]}]}}
    ]
  })");
  SceneWorld sw = build_world(scene);
  render::SceneList list;
  for (int frame = 0; frame < 6; ++frame) {
    list.clear();
    append_moved(sw.world.advance(1.0 / 30.0), list);
  }
  ASSERT_EQ(list.moved.size(), 1u) << "the static plane does not move";
  const sim::MovedObject pose = sw.world.pose(sw.colliders[1]);
  EXPECT_EQ(list.moved[0].key, sw.colliders[1].id.packed());
  EXPECT_TRUE(near(list.moved[0].translation, pose.translation));
  EXPECT_TRUE(near(list.moved[0].rotation, pose.rotation));
  EXPECT_GT(list.moved[0].translation.x(), 0.1f) << "the box travelled along its path";
  EXPECT_TRUE(list.added.empty());
  EXPECT_TRUE(list.removed.empty());
}

TEST(SceneList, FrameListViewsTheWorldsParticlesAndClothsAndFollowsTheCamera) {
  const Scene scene = scene_of(R"({
    "camera": {"position": [6, -6, 3], "target": [0, 0, 0.5], "orbit": {"radius": 5, "period_s": 4}},
    "emitters": [
      {"name": "a", "rate": 600, "render_style": "streak", "streak_s": 0.05},
      {"name": "b", "rate": 300, "render_style": "additive", "position": [1, 0, 0]}
    ],
    "cloths": [{"rows": 3, "columns": 6, "position": [0, 0, 2]}]
  })");
  SceneWorld sw = build_world(scene);
  for (int frame = 0; frame < 5; ++frame) sw.world.advance(1.0 / 30.0);
  const double t = 5.0 / 30.0;
  render::SceneList list;
  append_frame(scene, sw, t, list);

  ASSERT_EQ(list.particles.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const sim::ParticleView v = sw.world.particles(sw.systems[i]);
    const render::SceneList::Particles& p = list.particles[i];
    EXPECT_EQ(p.key, sw.systems[i].id.packed()) << i;
    EXPECT_GT(v.count, 0u) << i;
    EXPECT_EQ(p.batch.count, v.count) << i;
    EXPECT_EQ(p.batch.position, v.position) << i;
    EXPECT_EQ(p.batch.velocity, v.velocity) << i;
    EXPECT_EQ(p.batch.color, v.color) << i;
    EXPECT_EQ(p.batch.radius, v.radius) << i;
    EXPECT_EQ(p.batch.style, scene.emitters[i].style) << i;
    EXPECT_FLOAT_EQ(p.batch.streak_s, scene.emitters[i].streak_s) << i;
  }
  EXPECT_EQ(list.particles[0].batch.style, render::ParticleStyle::streak);
  EXPECT_FLOAT_EQ(list.particles[0].batch.streak_s, 0.05f);
  EXPECT_EQ(list.particles[1].batch.style, render::ParticleStyle::additive);

  ASSERT_EQ(list.meshes.size(), 1u);
  const sim::ClothView cv = sw.world.cloth(sw.cloths[0]);
  EXPECT_EQ(list.meshes[0].key, sw.cloths[0].id.packed());
  EXPECT_EQ(list.meshes[0].positions.size(), 3u * 18u);
  EXPECT_EQ(list.meshes[0].normals.size(), 3u * 18u);
  EXPECT_EQ(list.meshes[0].positions.data(), cv.positions);
  EXPECT_EQ(list.meshes[0].normals.data(), cv.normals);

  ASSERT_TRUE(list.camera.has_value());
  const render::Camera expected = render::camera_at(scene.camera_motion, t);
  EXPECT_EQ(list.camera->position, expected.position);
  EXPECT_EQ(list.camera->target, expected.target);
  EXPECT_FLOAT_EQ(list.camera->fov_deg, expected.fov_deg);
  // The orbit moves the eye: a different time gives a different camera.
  render::SceneList later;
  append_frame(scene, sw, 1.0, later);
  EXPECT_GT((later.camera->position - list.camera->position).norm(), 0.1f);
  EXPECT_TRUE(list.added.empty());
  EXPECT_TRUE(list.moved.empty());
}

TEST(SceneList, ParticleLookKeysAndTheShutterReachTheBatch) {
  // 180 degrees at 30 fps: an exposure of 1/60 s added to every additive particle's trail.
  const Scene scene = scene_of(R"({
    "fps": 30,
    "render": {"shutter_deg": 180},
    "emitters": [
      {"name": "a", "rate": 600, "render_style": "additive", "trail_s": 0.1, "emissive": 2.5, "texture": "flame"},
      {"name": "b", "rate": 300, "render_style": "soft", "texture": "smoke"}
    ]
  })");
  SceneWorld sw = build_world(scene);
  for (int frame = 0; frame < 5; ++frame) sw.world.advance(1.0 / 30.0);
  render::SceneList list;
  append_frame(scene, sw, 5.0 / 30.0, list);
  ASSERT_EQ(list.particles.size(), 2u);
  const render::ParticleBatch& a = list.particles[0].batch;
  const render::ParticleBatch& b = list.particles[1].batch;
  EXPECT_FLOAT_EQ(a.trail_s, 0.1f + 1.f / 60.f);
  EXPECT_FLOAT_EQ(a.emissive, 2.5f);
  EXPECT_EQ(a.texture, render::ParticleTexture::flame);
  EXPECT_EQ(b.texture, render::ParticleTexture::smoke);
  const sim::ParticleView v = sw.world.particles(sw.systems[0]);
  EXPECT_EQ(a.age, v.age);
  EXPECT_EQ(a.lifetime, v.lifetime);
  EXPECT_EQ(a.id, v.id);
  // A flame texture needs an additive style.
  EXPECT_THROW(scene_of(R"({"emitters": [{"render_style": "soft", "texture": "flame"}]})"), std::exception);
}

TEST(SceneList, RemovalsReachTheListOnceAndOnlyForDrawnKinds) {
  Scene scene = scene_of(R"({
    "colliders": [
      {"type": "plane"},
      {"type": "box", "position": [0, 0, 1], "half_extents": [0.5, 0.5, 0.5],
       "path": {"keys": [{"time": 0, "position": [0, 0, 1]}, {"time": 2, "position": [1, 0, 1]}]}}
    ],
    "emitters": [{"name": "a", "rate": 10}],
    "force_fields": [{"type": "uniform", "acceleration": [1, 0, 0]}],
    "cloths": [{"rows": 3, "columns": 3, "position": [0, 0, 2]}]
  })");
  SceneWorld sw = build_world(scene);
  ASSERT_EQ(sw.force_fields.size(), 1u);
  const std::uint64_t box = sw.colliders[1].id.packed();
  const std::uint64_t cloth = sw.cloths[0].id.packed();

  // Advance once: the kinematic box moves and nothing is removed.
  render::SceneList list;
  append_moved(sw.world.advance(1.0 / 30), list);
  ASSERT_EQ(list.moved.size(), 1u);
  EXPECT_EQ(list.moved[0].key, box);
  EXPECT_TRUE(list.removed.empty());

  // Remove the box, the cloth and the field between advances: the next advance reports the two
  // drawn objects as removals (the field has no drawable), and no pose for the box.
  sw.world.remove(sw.colliders[1]);
  sw.world.remove(sw.cloths[0]);
  sw.world.remove(sw.force_fields[0]);
  list.clear();
  append_moved(sw.world.advance(1.0 / 30), list);
  EXPECT_TRUE(list.moved.empty());
  ASSERT_EQ(list.removed.size(), 2u);
  EXPECT_EQ(list.removed[0], box);
  EXPECT_EQ(list.removed[1], cloth);

  // Reported once: the advance after that has nothing to remove.
  list.clear();
  append_moved(sw.world.advance(1.0 / 30), list);
  EXPECT_TRUE(list.removed.empty());
  EXPECT_TRUE(list.moved.empty());
}
