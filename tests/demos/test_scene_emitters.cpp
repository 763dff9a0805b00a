// Emitter keys of the scene format (README "emitters[i]"): shapes, mesh files, uniform
// distributions, bursts, inherited velocity, size over lifetime and particle split.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "cli_util.hpp"
#include "json_reader.hpp"
#include "scene.hpp"

using simreel::app::json;
using simreel::app::load_scene;
using simreel::app::scene_from_json;
using simreel::app::SceneError;
using simreel::test::run_simreel;
using simreel::test::TempDir;
using simreel::test::write_file;
namespace sim = simreel::sim;

namespace {

std::string errors_of(const std::string& text) {
  try {
    (void)scene_from_json(json::parse(text), "s.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(SceneEmitters, NewKeysAreRead) {
  const auto s = scene_from_json(json::parse(R"({"emitters":[{"shape":"sphere","sphere_radius":0.3,
      "start_speed":{"min":2,"max":6},"bursts":[{"time":0.5,"count":40,"repeat_interval":1,"cycles":0}],
      "inherit_velocity":0.5,"color_deviation":0.1,
      "size_over_lifetime":[{"t":0,"size":1},{"t":1,"size":0.2}],
      "split":{"children":3,"age":0.4,"delay_steps":2,"depth":2,"velocity_fraction":0.8,
               "direction_deviation_deg":15,"size_fraction":0.6,"lifetime_deviation":0.2}}]})"),
                                 "s.json");
  const sim::EmitterDef& em = s.emitters.at(0).system.emitter;
  EXPECT_EQ(em.shape, sim::EmitterShape::sphere);
  EXPECT_DOUBLE_EQ(em.sphere_radius, 0.3);
  EXPECT_TRUE(em.start_speed.uniform);
  EXPECT_DOUBLE_EQ(em.start_speed.min, 2.0);
  EXPECT_DOUBLE_EQ(em.start_speed.max, 6.0);
  ASSERT_EQ(em.bursts.size(), 1u);
  EXPECT_EQ(em.bursts[0].count, 40u);
  EXPECT_EQ(em.bursts[0].cycles, 0u);
  EXPECT_DOUBLE_EQ(em.inherit_velocity, 0.5);
  EXPECT_DOUBLE_EQ(em.color_deviation, 0.1);
  ASSERT_EQ(em.size_over_lifetime.size(), 2u);
  EXPECT_DOUBLE_EQ(em.size_over_lifetime[1].size, 0.2);
  EXPECT_TRUE(em.split.enabled);
  EXPECT_EQ(em.split.children, 3u);
  EXPECT_EQ(em.split.delay_steps, 2u);
  EXPECT_EQ(em.split.depth, 2u);
  EXPECT_DOUBLE_EQ(em.split.size_fraction, 0.6);
  // The engine accepts what the loader produced.
  EXPECT_NO_THROW(simreel::app::build_world(s));
}

TEST(SceneEmitters, BadValuesNamePointerAndExpectation) {
  std::string e = errors_of(R"({"emitters":[{"shape":"cone"}]})");
  EXPECT_NE(e.find("s.json: /emitters/0/shape: expected one of"), std::string::npos) << e;
  e = errors_of(R"({"emitters":[{"split":{"depth":0}}]})");
  EXPECT_NE(e.find("s.json: /emitters/0/split/depth: expected an integer in [1, 32], found 0"), std::string::npos) << e;
  e = errors_of(R"({"emitters":[{"split":{"childs":3}}]})");
  EXPECT_NE(e.find("/emitters/0/split/childs: unknown key \"childs\""), std::string::npos) << e;
  e = errors_of(R"({"emitters":[{"bursts":[{"time":1}]}]})");
  EXPECT_NE(e.find("/emitters/0/bursts/0: expected a \"count\""), std::string::npos) << e;
  e = errors_of(R"({"emitters":[{"bursts":[{"count":5,"cycles":0}]}]})");
  EXPECT_NE(e.find("/emitters/0/bursts/0/cycles: expected cycles >= 1"), std::string::npos) << e;
  e = errors_of(R"({"emitters":[{"inherit_velocity":1.5}]})");
  EXPECT_NE(e.find("/emitters/0/inherit_velocity: expected a number in [0, 1], found 1.5"), std::string::npos) << e;
  e = errors_of(R"({"emitters":[{"size_over_lifetime":[{"t":0.5,"size":1},{"t":0.2,"size":2}]}]})");
  EXPECT_NE(e.find("/emitters/0/size_over_lifetime/1/t: expected keys in increasing t"), std::string::npos) << e;
  e = errors_of(R"({"emitters":[{"mass":{"min":0.002}}]})");
  EXPECT_NE(e.find("/emitters/0/mass: expected a \"mean\""), std::string::npos) << e;
  e = errors_of(R"({"emitters":[{"mass":{"min":0.003,"max":0.001}}]})");
  EXPECT_NE(e.find("/emitters/0/mass/min: expected min <= max"), std::string::npos) << e;
  e = errors_of(R"({"emitters":[{"shape":"mesh"}]})");
  EXPECT_NE(e.find("/emitters/0: expected a \"mesh_file\""), std::string::npos) << e;
  e = errors_of(R"({"emitters":[{"shape":"disk","mesh_file":"a.obj"}]})");
  EXPECT_NE(e.find("/emitters/0/mesh_file: expected \"mesh_file\" only with"), std::string::npos) << e;
}

TEST(SceneEmitters, MeshFileIsLoadedRelativeToTheScene) {
  TempDir d;
  write_file(d / "tri.obj", "v 0 0 0\nv 2 0 0\nv 0 2 0\nf 1 2 3\n");
  write_file(d / "s.json", R"({"emitters":[{"shape":"mesh","mesh_file":"tri.obj"}]})");
  const auto s = load_scene(d / "s.json");
  const sim::EmitterDef& em = s.emitters.at(0).system.emitter;
  EXPECT_EQ(em.shape, sim::EmitterShape::mesh);
  EXPECT_EQ(em.mesh_positions.size(), 9u);
  EXPECT_EQ(em.mesh_triangles.size(), 3u);
  EXPECT_NO_THROW(simreel::app::build_world(s));

  write_file(d / "bad.json", R"({"emitters":[{"shape":"mesh","mesh_file":"missing.obj"}]})");
  const auto r = run_simreel("validate " + (d / "bad.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find((d / "bad.json").string() + ": /emitters/0/mesh_file: cannot load the mesh"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("missing.obj"), std::string::npos) << r.err;
}

TEST(SceneEmitters, BadSplitValueExits2FromTheCli) {
  TempDir d;
  write_file(d / "s.json", R"({"emitters":[{"split":{"size_fraction":0}}]})");
  const auto r = run_simreel("validate " + (d / "s.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find((d / "s.json").string() + ": /emitters/0/split/size_fraction: expected a number"),
            std::string::npos)
      << r.err;
}

TEST(SceneEmitters, RainFollowsTheCamera) {
  // The rain preset's area follows the camera by default (`follow_camera`): a 1 m square rain
  // area centred on the ground point of a camera orbiting at 6 m (a 4 s period, so 9.4 m/s).
  // Drops born in the last frame (within 0.25 m of the release height) must lie in the square
  // around the camera's ground point at that frame, plus the camera's travel over a frame; with
  // "follow_camera": false they stay over the world origin.
  auto scene_text = [](bool follow) {
    return std::string(R"({"fps": 30, "frames": 60,
      "camera": {"orbit": {"center": [0, 0, 0.5], "radius": 6, "height": 2, "period_s": 4}},
      "emitters": [{"effect": "rain", "center": [0, 0, 0], "area_m": [1, 1], "height_m": 3,
                    "intensity_mm_h": 8, "splash": false, "follow_camera": )") +
           (follow ? "true" : "false") + R"(, "overrides": {"collide": false}}]})";
  };
  for (const bool follow : {true, false}) {
    const auto scene = scene_from_json(json::parse(scene_text(follow)), "s.json");
    ASSERT_EQ(scene.emitters.at(0).follow_camera, follow);
    simreel::app::SceneWorld sw = simreel::app::build_world(scene);
    double travelled = 0.0;
    std::size_t checked = 0;
    for (int f = 1; f <= 60; ++f) {
      sw.world.advance(1.0 / 30);
      if (f % 10 != 0) continue;
      const auto eye = simreel::render::camera_at(scene.camera_motion, f / 30.0).position;
      const double cx = follow ? eye.x() : 0.0, cy = follow ? eye.y() : 0.0;
      travelled = std::max(travelled, std::hypot(eye.x(), eye.y() + 6.0));
      const sim::ParticleView v = sw.world.particles(sw.systems.at(0));
      for (std::size_t i = 0; i < v.count; ++i) {
        if (v.position[3 * i + 2] < 3.0 - 0.25) continue;  // older than about a frame
        EXPECT_LT(std::abs(v.position[3 * i] - cx), 0.5 + 0.35) << "frame " << f << " follow " << follow;
        EXPECT_LT(std::abs(v.position[3 * i + 1] - cy), 0.5 + 0.35) << "frame " << f << " follow " << follow;
        ++checked;
      }
    }
    EXPECT_GT(travelled, 10.0);  // the camera went round: following is not trivially true
    EXPECT_GT(checked, 100u);
  }
  // Either a path or following the camera, not both.
  EXPECT_NE(errors_of(R"({"emitters": [{"follow_camera": true, "path": {"keys": [{"time": 0}]}}]})")
                .find("/emitters/0/follow_camera: expected either"),
            std::string::npos);
}
