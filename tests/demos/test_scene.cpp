// Scene loading: every key checked, messages name file + pointer + found + expected.
#include <gtest/gtest.h>

#include <cmath>

#include "json_reader.hpp"
#include "scene.hpp"

using simreel::app::apply_override;
using simreel::app::json;
using simreel::app::parse_json_text;
using simreel::app::scene_from_json;
using simreel::app::SceneError;

namespace {

std::string errors_of(const json& doc) {
  try {
    (void)scene_from_json(doc, "s.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(SceneLoad, EmptyObjectGivesDefaults) {
  const auto s = scene_from_json(json::object(), "s.json");
  EXPECT_EQ(s.frames, 120);
  EXPECT_DOUBLE_EQ(s.fps, 30.0);
  EXPECT_TRUE(s.emitters.empty());
  EXPECT_TRUE(s.colliders.empty());
}

TEST(SceneLoad, EmitterDistributionsAndDirection) {
  const auto doc = json::parse(R"({"emitters":[{"name":"jet","direction":[1,0,0],"rate":12.5,
      "start_speed":{"mean":3,"deviation":0.5},"spread_deg":4,"mass":0.002,
      "particle_radius":{"mean":0.01,"deviation":0.001,"min":0.005,"max":0.02}}]})");
  const auto s = scene_from_json(doc, "s.json");
  ASSERT_EQ(s.emitters.size(), 1u);
  const auto& em = s.emitters[0].system.emitter;
  EXPECT_EQ(s.emitters[0].system.name, "jet");
  EXPECT_DOUBLE_EQ(em.rate, 12.5);
  EXPECT_DOUBLE_EQ(em.start_speed.mean, 3.0);
  EXPECT_DOUBLE_EQ(em.start_speed.deviation, 0.5);
  EXPECT_DOUBLE_EQ(em.spread_deg.mean, 4.0);
  EXPECT_DOUBLE_EQ(em.spread_deg.deviation, 0.0);
  EXPECT_DOUBLE_EQ(em.radius.min, 0.005);
  EXPECT_DOUBLE_EQ(em.radius.max, 0.02);
  // The emitter's +z axis is turned onto the given direction.
  const auto axis = em.transform.rotation * simreel::sim::Vec3::UnitZ();
  EXPECT_NEAR(axis.x(), 1.0, 1e-12);
  EXPECT_NEAR(axis.z(), 0.0, 1e-12);
}

TEST(SceneLoad, WrongTypeNamesPointerFoundAndExpected) {
  const std::string e = errors_of(json::parse(R"({"emitters":[{"rate":"fast"}]})"));
  EXPECT_NE(e.find("s.json: /emitters/0/rate: expected a number"), std::string::npos) << e;
  EXPECT_NE(e.find("found \"fast\" (string)"), std::string::npos) << e;
}

TEST(SceneLoad, OutOfRangeIsAnError) {
  const std::string e = errors_of(json::parse(R"({"colliders":[{"type":"plane","restitution":1.5}]})"));
  EXPECT_NE(e.find("/colliders/0/restitution: expected a number in [0, 1], found 1.5"), std::string::npos) << e;
}

TEST(SceneLoad, UnknownKeyGetsDidYouMean) {
  const std::string e = errors_of(json::parse(R"({"emitters":[{"rat":5}], "fsp": 30})"));
  EXPECT_NE(e.find("/emitters/0/rat: unknown key \"rat\"; did you mean \"rate\"?"), std::string::npos) << e;
  EXPECT_NE(e.find("/fsp: unknown key \"fsp\"; did you mean \"fps\"?"), std::string::npos) << e;
}

TEST(SceneLoad, AllErrorsAreCollected) {
  try {
    (void)scene_from_json(json::parse(R"({"fps":-1,"frames":"x","camera":{"fov_deg":500}})"), "s.json");
    FAIL() << "expected SceneError";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.messages().size(), 3u) << e.what();
  }
}

TEST(SceneLoad, KeyframeTimesMustIncrease) {
  const std::string e = errors_of(json::parse(
      R"({"colliders":[{"type":"box","path":{"keys":[{"time":1},{"time":1}]}}]})"));
  EXPECT_NE(e.find("/colliders/0/path/keys/1/time: expected times strictly increasing"), std::string::npos) << e;
}

TEST(SceneLoad, InvalidJsonReportsLineAndColumn) {
  try {
    (void)parse_json_text("{\n  \"fps\": 30,\n  \"frames\": ,\n}", "bad.json");
    FAIL() << "expected SceneError";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.json:3:13: invalid JSON"), std::string::npos) << e.what();
  }
}

TEST(SceneOverride, ReplacesExistingValueReadAsJson) {
  json doc = json::parse(R"({"emitters":[{"rate":10}]})");
  apply_override(doc, "/emitters/0/rate=500", "s.json");
  EXPECT_EQ(doc["emitters"][0]["rate"], 500);
  apply_override(doc, "/emitters/0/name=spray", "s.json");  // bare word -> string
  EXPECT_EQ(doc["emitters"][0]["name"], "spray");
  apply_override(doc, "/emitters/0/position=[1,2,3]", "s.json");
  EXPECT_EQ(doc["emitters"][0]["position"], json::parse("[1,2,3]"));
}

TEST(SceneOverride, PointerThatNamesNothingIsAnError) {
  json doc = json::parse(R"({"emitters":[{"rate":10}]})");
  EXPECT_THROW(apply_override(doc, "/emitters/3/rate=1", "s.json"), SceneError);
  EXPECT_THROW(apply_override(doc, "/chains/0/links=3", "s.json"), SceneError);  // no array made up
  EXPECT_THROW(apply_override(doc, "/emitters/0/rate/x=1", "s.json"), SceneError);  // under a number
  EXPECT_THROW(apply_override(doc, "emitters=1", "s.json"), SceneError);
  EXPECT_THROW(apply_override(doc, "/emitters/0/rate", "s.json"), SceneError);
  EXPECT_EQ(doc, json::parse(R"({"emitters":[{"rate":10}]})")) << "a refused --set leaves the scene";
}

TEST(SceneOverride, KeyOfABlockTheSceneLeavesOutMakesTheBlock) {
  // The message of a diverged run suggests --set /simulation/max_step=...: on a scene without a
  // "simulation" block (its defaults) that must work, as writing the block by hand would.
  json doc = json::parse(R"({"emitters":[{"rate":10}]})");
  apply_override(doc, "/simulation/max_step=0.001", "s.json");
  apply_override(doc, "/camera/fov_deg=30", "s.json");
  apply_override(doc, "/emitters/0/split/count=3", "s.json");
  EXPECT_EQ(doc, json::parse(R"({"emitters":[{"rate":10,"split":{"count":3}}],
                                 "simulation":{"max_step":0.001},"camera":{"fov_deg":30}})"));
}

TEST(SceneLoad, SphereCylinderAndMeshColliders) {
  const auto s = simreel::app::load_scene(std::filesystem::path(SIMREEL_SOURCE_DIR) / "demos/scenes/pour.json");
  ASSERT_GE(s.colliders.size(), 5u);
  const auto& bowl = s.colliders[1];
  EXPECT_EQ(bowl.type, simreel::app::ColliderScene::Type::mesh);
  EXPECT_EQ(bowl.mesh.triangles.size(), 3072u);
  EXPECT_DOUBLE_EQ(bowl.mesh.material.static_friction, 0.6);
  EXPECT_FLOAT_EQ(bowl.color[0], 0.85f);
  EXPECT_EQ(s.colliders[4].type, simreel::app::ColliderScene::Type::cylinder);
  EXPECT_TRUE(s.emitters[0].system.collide_particles);
  const auto doc = json::parse(R"({"colliders":[{"type":"sphere","radius":0.25,"position":[1,2,3],
      "on_hit":"split","split":{"count":7}},{"type":"mesh","file":"missing.obj"}]})");
  const std::string err = errors_of(doc);
  EXPECT_NE(err.find("s.json: /colliders/1/file: missing.obj: cannot import mesh: no such file"), std::string::npos) << err;
  const auto ok = scene_from_json(json::parse(R"({"colliders":[{"type":"sphere","radius":0.25,
      "on_hit":"split","split":{"count":7}}]})"), "s.json");
  EXPECT_EQ(ok.colliders[0].sphere.material.on_hit, simreel::sim::HitAction::split);
  EXPECT_EQ(ok.colliders[0].sphere.material.split.count, 7);
}

// --- camera path / orbit and render background (renderer-quality half of issue 7) ---

TEST(SceneCamera, PathKeysAndOrbitAreRead) {
  const auto s = scene_from_json(json::parse(R"({"camera":{"position":[5,-5,2],"target":[0,0,1],
      "path":[{"time":0,"position":[4,-4,2]},{"time":2,"position":[0,-6,3],"target":[0,0,0.5],"fov_deg":30}]},
      "render":{"background":[0.1,0.1,0.1],"particle_shadows":true},
      "emitters":[{"render_style":"streak","streak_s":0.05}]})"), "s.json");
  ASSERT_EQ(s.camera_motion.keys.size(), 2u);
  EXPECT_FLOAT_EQ(s.camera_motion.keys[0].target.z(), 1.f);  // defaults to the camera's target
  EXPECT_FLOAT_EQ(s.camera_motion.keys[1].fov_deg, 30.f);
  EXPECT_EQ(s.render.background, simreel::render::Background::solid);
  EXPECT_TRUE(s.render.particle_shadows);
  EXPECT_EQ(s.emitters[0].style, simreel::render::ParticleStyle::streak);
  EXPECT_FLOAT_EQ(s.emitters[0].streak_s, 0.05f);
  const auto o = scene_from_json(json::parse(R"({"camera":{"orbit":{"center":[0,0,1],"radius":5,"period_s":8}}})"), "s.json");
  ASSERT_TRUE(o.camera_motion.orbit.has_value());
  EXPECT_FLOAT_EQ(o.camera_motion.orbit->radius, 5.f);
}

TEST(SceneCamera, BadPathAndOrbitValuesNamePointers) {
  std::string e = errors_of(json::parse(R"({"camera":{"path":[{"time":1},{"time":1}]}})"));
  EXPECT_NE(e.find("s.json: /camera/path/1/time: expected times strictly increasing"), std::string::npos) << e;
  // Times closer than a microsecond read as themselves, not as "0.000000 after 0.000000".
  e = errors_of(json::parse(R"({"camera":{"path":[{"time":2e-7},{"time":1e-7}]}})"));
  EXPECT_NE(e.find("found 1e-07 after 2e-07"), std::string::npos) << e;
  e = errors_of(json::parse(R"({"camera":{"orbit":{"radius":0}}})"));
  EXPECT_NE(e.find("s.json: /camera/orbit/radius: expected a number in (0, 1000000]"), std::string::npos) << e;
  e = errors_of(json::parse(R"({"camera":{"path":[{"position":[1,2,3]}], "orbit":{}}})"));
  EXPECT_NE(e.find("not both"), std::string::npos) << e;
  EXPECT_NE(e.find("/camera/path/0: expected a \"time\""), std::string::npos) << e;
  e = errors_of(json::parse(R"({"render":{"background":"night"}})"));
  EXPECT_NE(e.find("s.json: /render/background: expected \"sky\", \"transparent\" or a colour"), std::string::npos) << e;
}

// --- the frame (issue 14 A): bloom, shutter, transparent background ---

TEST(SceneRender, BloomShutterAndTransparentBackgroundAreRead) {
  const auto d = scene_from_json(json::parse(R"({})"), "s.json");
  EXPECT_FLOAT_EQ(d.render.bloom.intensity, 0.04f);  // on by default
  EXPECT_FLOAT_EQ(d.render.shutter_deg, 0.f);        // motion blur off by default
  const auto s = scene_from_json(json::parse(R"({"render":{"background":"transparent",
      "bloom":{"intensity":0.1,"radius":0.5},"shutter_deg":180,"shutter_samples":12}})"), "s.json");
  EXPECT_EQ(s.render.background, simreel::render::Background::transparent);
  EXPECT_FLOAT_EQ(s.render.bloom.intensity, 0.1f);
  EXPECT_FLOAT_EQ(s.render.bloom.radius, 0.5f);
  EXPECT_FLOAT_EQ(s.render.shutter_deg, 180.f);
  EXPECT_EQ(s.render.shutter_samples, 12);
  std::string e = errors_of(json::parse(R"({"render":{"shutter_deg":400}})"));
  EXPECT_NE(e.find("s.json: /render/shutter_deg: expected a number in [0, 360]"), std::string::npos) << e;
  e = errors_of(json::parse(R"({"render":{"bloom":{"intensity":2,"glow":1}}})"));
  EXPECT_NE(e.find("s.json: /render/bloom/intensity"), std::string::npos) << e;
  EXPECT_NE(e.find("/render/bloom/glow"), std::string::npos) << e;
}

TEST(SceneCloth, ParticleContactKeysAreReadAndChecked) {
  const auto s = scene_from_json(json::parse(R"({"cloths":[{"collide_particles":false,"restitution":0.4}]})"), "s.json");
  ASSERT_EQ(s.cloths.size(), 1u);
  EXPECT_FALSE(s.cloths[0].def.collide_particles);
  EXPECT_DOUBLE_EQ(s.cloths[0].def.restitution, 0.4);
  const std::string e = errors_of(json::parse(R"({"cloths":[{"restitution":2,"collide_particles":"yes"}]})"));
  EXPECT_NE(e.find("s.json: /cloths/0/restitution: expected a number in [0, 1]"), std::string::npos) << e;
  EXPECT_NE(e.find("s.json: /cloths/0/collide_particles: expected"), std::string::npos) << e;
}
