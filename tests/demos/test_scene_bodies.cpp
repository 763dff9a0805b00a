// Scene keys of dynamic colliders ("motion": "dynamic"; README "Rigid bodies", Coutinho Ch. 4):
// parsed into the engine's BodyDef (deg/s -> rad/s), defaults, every bad value reported with the
// file and JSON pointer, and a box dropped on a plane that comes to rest through the sim ->
// SceneList glue (no GL).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <string>

#include "json_reader.hpp"
#include "scene.hpp"
#include "scene_list_builder.hpp"

namespace {

using simreel::app::append_moved;
using simreel::app::build_world;
using simreel::app::dynamic_body_def;
using simreel::app::json;
using simreel::app::load_scene;
using simreel::app::Scene;
using simreel::app::scene_from_json;
using simreel::app::SceneError;
using simreel::app::SceneWorld;
namespace render = simreel::render;
namespace sim = simreel::sim;
namespace fs = std::filesystem;

std::string errors_of(const char* text) {
  try {
    (void)scene_from_json(json::parse(text), "s.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

/// The loader's messages for one collider object (given as JSON text).
std::string collider_errors(const std::string& collider) {
  return errors_of(("{\"colliders\": [" + collider + "]}").c_str());
}

constexpr double kDeg = std::numbers::pi / 180.0;

}  // namespace

TEST(SceneBodies, KeysReachTheBodyDefInEngineUnits) {
  const Scene s = scene_from_json(json::parse(R"({
    "simulation": {"gravity": [0, 0, -5]},
    "colliders": [
      {"type": "plane"},
      {"type": "box", "name": "crate", "motion": "dynamic", "density": 600, "position": [1, 2, 3],
       "rotation_deg": [0, 0, 90], "half_extents": [0.1, 0.2, 0.3], "velocity": [1, -2, 0.5],
       "angular_velocity_deg": [90, 0, -180], "linear_damping": 0.25, "angular_damping": 0.5,
       "restitution": 0.3, "friction": 0.7},
      {"type": "sphere", "motion": "dynamic", "mass": 2.5, "radius": 0.2},
      {"type": "cylinder", "motion": "dynamic", "radius": 0.1, "half_height": 0.4}
    ]})"),
                                  "s.json");
  ASSERT_EQ(s.colliders.size(), 4u);
  EXPECT_FALSE(s.colliders[0].dynamic.enabled);

  const sim::BodyDef box = dynamic_body_def(s.colliders[1]);
  EXPECT_EQ(box.type, sim::BodyType::dynamic);
  EXPECT_EQ(box.name, "crate");
  EXPECT_TRUE(box.pose.translation.isApprox(sim::Vec3(1, 2, 3)));
  EXPECT_TRUE(box.pose.rotation.toRotationMatrix().isApprox(
      sim::Quat(Eigen::AngleAxisd(90 * kDeg, sim::Vec3::UnitZ())).toRotationMatrix(), 1e-12));
  ASSERT_EQ(box.shapes.size(), 1u);
  EXPECT_EQ(box.shapes[0].type, sim::ShapeType::box);
  EXPECT_TRUE(box.shapes[0].half_extents.isApprox(sim::Vec3(0.1, 0.2, 0.3)));
  EXPECT_DOUBLE_EQ(box.shapes[0].density, 600.0);
  EXPECT_DOUBLE_EQ(box.shapes[0].material.restitution, 0.3);
  EXPECT_DOUBLE_EQ(box.shapes[0].material.friction, 0.7);
  EXPECT_DOUBLE_EQ(box.mass, 0.0) << "no mass key: the mass comes from the density";
  EXPECT_TRUE(box.linear_velocity.isApprox(sim::Vec3(1, -2, 0.5)));
  EXPECT_NEAR(box.angular_velocity.x(), std::numbers::pi / 2, 1e-12) << "deg/s -> rad/s";
  EXPECT_DOUBLE_EQ(box.angular_velocity.y(), 0.0);
  EXPECT_NEAR(box.angular_velocity.z(), -std::numbers::pi, 1e-12);
  EXPECT_DOUBLE_EQ(box.linear_damping, 0.25);
  EXPECT_DOUBLE_EQ(box.angular_damping, 0.5);
  EXPECT_TRUE(box.gravity.isApprox(sim::Vec3(0, 0, -5))) << "the scene's gravity";
  EXPECT_TRUE(box.path.empty());

  const sim::BodyDef ball = dynamic_body_def(s.colliders[2]);
  EXPECT_EQ(ball.shapes[0].type, sim::ShapeType::sphere);
  EXPECT_DOUBLE_EQ(ball.shapes[0].radius, 0.2);
  EXPECT_DOUBLE_EQ(ball.mass, 2.5);

  const sim::BodyDef drum = dynamic_body_def(s.colliders[3]);
  EXPECT_EQ(drum.shapes[0].type, sim::ShapeType::cylinder);
  EXPECT_DOUBLE_EQ(drum.shapes[0].radius, 0.1);
  EXPECT_DOUBLE_EQ(drum.shapes[0].half_height, 0.4);
}

TEST(SceneBodies, Defaults) {
  const Scene s = scene_from_json(json::parse(R"({"colliders": [{"type": "box", "motion": "dynamic"}]})"), "s.json");
  const sim::BodyDef b = dynamic_body_def(s.colliders[0]);
  EXPECT_DOUBLE_EQ(b.shapes[0].density, 1000.0) << "water";
  EXPECT_DOUBLE_EQ(b.mass, 0.0);
  EXPECT_EQ(b.linear_velocity, sim::Vec3::Zero());
  EXPECT_EQ(b.angular_velocity, sim::Vec3::Zero());
  EXPECT_DOUBLE_EQ(b.linear_damping, 0.0);
  EXPECT_DOUBLE_EQ(b.angular_damping, 0.0);
  EXPECT_TRUE(b.gravity.isApprox(sim::Vec3(0, 0, -9.81)));
  // Without "motion" a collider stays static (no path) and builds as before.
  const Scene st = scene_from_json(json::parse(R"({"colliders": [{"type": "box"}]})"), "s.json");
  EXPECT_FALSE(st.colliders[0].dynamic.enabled);
  // "motion": "static" / "kinematic" agree with the path.
  EXPECT_EQ(collider_errors(R"({"type": "box", "motion": "static"})"), "");
  EXPECT_EQ(collider_errors(
                R"({"type": "box", "motion": "kinematic", "path": {"keys": [{"time": 0, "position": [0, 0, 1]}]}})"),
            "");
}

TEST(SceneBodies, BadValuesAreReportedWithTheirPointer) {
  struct Case {
    const char* collider;
    const char* pointer_and_text;  ///< expected in the message
  };
  const Case cases[] = {
      {R"({"type": "box", "motion": "dynamic", "density": 0})", "s.json: /colliders/0/density: expected a number > 0"},
      {R"({"type": "box", "motion": "dynamic", "density": -5})", "/colliders/0/density: expected a number > 0"},
      {R"({"type": "box", "motion": "dynamic", "mass": 0})", "/colliders/0/mass: expected a number > 0"},
      {R"({"type": "box", "motion": "dynamic", "mass": "heavy"})", "/colliders/0/mass: expected a number"},
      {R"({"type": "box", "motion": "dynamic", "density": 500, "mass": 2})",
       "/colliders/0/mass: expected \"density\" or \"mass\", found both"},
      {R"({"type": "box", "motion": "dynamic", "linear_damping": -1})", "/colliders/0/linear_damping: expected a number >= 0"},
      {R"({"type": "box", "motion": "dynamic", "angular_damping": -0.1})", "/colliders/0/angular_damping: expected a number >= 0"},
      {R"({"type": "box", "motion": "dynamic", "velocity": [1, 2]})", "/colliders/0/velocity: expected"},
      {R"({"type": "box", "motion": "dynamic", "angular_velocity_deg": "fast"})", "/colliders/0/angular_velocity_deg: expected"},
      {R"({"type": "box", "motion": "wobbly"})", "/colliders/0/motion: expected one of \"static\", \"kinematic\", \"dynamic\""},
      {R"({"type": "plane", "motion": "dynamic"})", "/colliders/0/motion: expected \"dynamic\" only on a box, sphere, cylinder or capsule"},
      {R"({"type": "mesh", "file": "../../assets/models/rock.obj", "motion": "dynamic"})",
       "/colliders/0/motion: expected \"dynamic\" only on a box, sphere, cylinder or capsule collider, found a mesh"},
      {R"({"type": "box", "motion": "kinematic"})", "/colliders/0/motion: expected a \"path\""},
      {R"({"type": "box", "velocity": [1, 0, 0]})", "/colliders/0/velocity: expected \"motion\": \"dynamic\" for \"velocity\", found a static collider"},
      {R"({"type": "sphere", "density": 10})", "/colliders/0/density: expected \"motion\": \"dynamic\""},
  };
  for (const Case& c : cases) {
    const std::string e = collider_errors(c.collider);
    EXPECT_NE(e.find(c.pointer_and_text), std::string::npos) << c.collider << "\n  gave: " << e;
  }
}

TEST(SceneBodies, DynamicWithAPathIsRejected) {
  const std::string e = collider_errors(
      R"({"type": "box", "motion": "dynamic", "path": {"keys": [{"time": 0, "position": [0, 0, 1]}]}})");
  EXPECT_NE(e.find("s.json: /colliders/0/path: expected no \"path\" on a \"dynamic\" collider"), std::string::npos) << e;
  const std::string st = collider_errors(
      R"({"type": "box", "motion": "static", "path": {"keys": [{"time": 0, "position": [0, 0, 1]}]}})");
  EXPECT_NE(st.find("/colliders/0/motion: expected \"kinematic\""), std::string::npos) << st;
}

TEST(SceneBodies, BoxFallsOntoThePlaneAndRests) {
  const Scene scene = scene_from_json(json::parse(R"({
    "fps": 30,
    "colliders": [
      {"type": "plane", "friction": 0.6},
      {"type": "box", "motion": "dynamic", "position": [0, 0, 1], "rotation_deg": [0, 0, 20],
       "half_extents": [0.2, 0.15, 0.1], "friction": 0.6, "restitution": 0.1}
    ]})"),
                                      "s.json");
  SceneWorld sw = build_world(scene);
  const std::uint64_t key = sw.colliders[1].id.packed();
  bool moved_while_falling = false;
  for (int frame = 0; frame < 60; ++frame) {
    render::SceneList list;
    append_moved(sw.world.advance(1.0 / 30.0), list);
    if (frame < 10)  // still in the air (free fall from 0.9 m takes ~0.43 s)
      for (const auto& m : list.moved) moved_while_falling |= m.key == key;
  }
  EXPECT_TRUE(moved_while_falling);
  const sim::MovedObject p = sw.world.pose(sw.colliders[1]);
  EXPECT_NEAR(p.translation.z(), 0.1, 2e-3) << "resting on its face: z = half height";
  EXPECT_NEAR(p.translation.x(), 0.0, 1e-2);
  EXPECT_NEAR(p.translation.y(), 0.0, 1e-2);
  // Still upright: the body z axis stays along the world z axis.
  EXPECT_NEAR(p.rotation(2, 2), 1.0, 1e-3);
}

// The cloth_pile demo (a free sheet dropped over a pile of bodies; two-way coupling, §3.7) over
// its whole length: nothing diverges and no body is spun up wildly. Its capsule, squeezed between
// the sheet's edge and the ground, used to be spun from 22 to 205 rad/s in two frames (~frame 71)
// and on until the simulation stopped as diverged at frame 113: every round of the cloth's
// contact passes logged its push on the body again. Known and still open (issue 16): the first
// round's pushes, which undo position errors rather than stop an approach, still spin it to
// ~60 rad/s for a few frames; the bound here is the one the fixed build must keep.
TEST(SceneBodies, ClothPileDemoKeepsEveryBodyCalm) {
  const Scene scene = load_scene(fs::path(SIMREEL_SOURCE_DIR) / "demos" / "scenes" / "cloth_pile.json");
  SceneWorld sw = build_world(scene);
  double fastest_spin = 0.0, fastest = 0.0;
  int at = -1;
  for (int frame = 0; frame < scene.frames; ++frame) {
    ASSERT_NO_THROW(sw.world.advance(1.0 / scene.fps)) << "frame " << frame;
    for (const sim::BodyHandle h : sw.colliders) {
      const auto [v, w] = sw.world.velocity(h);
      if (w.norm() > fastest_spin) {
        fastest_spin = w.norm();
        at = frame;
      }
      fastest = std::max(fastest, v.norm());
    }
  }
  std::printf("cloth_pile: fastest spin %.1f rad/s (frame %d), fastest body %.2f m/s\n",
              fastest_spin, at, fastest);
  EXPECT_LT(fastest_spin, 100.0) << "frame " << at;
  EXPECT_LT(fastest, 6.0);  // the bodies fall from at most 1.6 m: sqrt(2 g 1.6) = 5.6 m/s
}

TEST(SceneBodies, CouplingKeysReachTheDefinitions) {
  // Air drag of bodies (drag_coefficient, drag_area_m2), a uniform field's wind, a blast field,
  // a field kept off bodies ("bodies": false) and a blast kept off particles ("particles": false).
  // README "Rigid bodies" and "force_fields[i]", body_coupling.cpp, stage_integrate.cpp.
  const Scene s = scene_from_json(json::parse(R"({
    "colliders": [
      {"type": "box", "motion": "dynamic", "half_extents": [0.1, 0.1, 0.1],
       "drag_coefficient": 1.05, "drag_area_m2": 0.02}
    ],
    "force_fields": [
      {"type": "uniform", "wind": [3, 0, 0], "drag": 0.002},
      {"type": "blast", "impulse": 50, "time": 0.4, "region": {"center": [1, 2, 0]}, "particles": false},
      {"type": "vortex", "bodies": false}
    ]})"),
                                  "s.json");
  const sim::BodyDef b = dynamic_body_def(s.colliders[0]);
  EXPECT_EQ(b.drag_coefficient, 1.05);
  EXPECT_EQ(b.drag_area, 0.02);
  ASSERT_EQ(s.force_fields.size(), 3u);
  EXPECT_EQ(s.force_fields[0].def.wind, sim::Vec3(3, 0, 0));
  EXPECT_EQ(s.force_fields[0].def.drag, 0.002);
  EXPECT_TRUE(s.force_fields[0].def.bodies);
  EXPECT_EQ(s.force_fields[1].def.kind, sim::FieldKind::blast);
  EXPECT_EQ(s.force_fields[1].def.impulse, 50.0);
  EXPECT_EQ(s.force_fields[1].def.time, 0.4);
  EXPECT_FALSE(s.force_fields[1].def.particles);
  EXPECT_TRUE(s.force_fields[1].def.bodies);
  EXPECT_FALSE(s.force_fields[2].def.bodies);
  EXPECT_TRUE(s.force_fields[2].def.particles);
  const std::string bad_flag = errors_of(R"({"force_fields": [{"type": "blast", "particles": 1}]})");
  EXPECT_NE(bad_flag.find("/force_fields/0/particles"), std::string::npos) << bad_flag;
  EXPECT_NE(collider_errors(R"({"type": "box", "motion": "dynamic", "drag_coefficient": -1})"), "");
  EXPECT_NE(collider_errors(R"({"type": "box", "drag_area_m2": 0.1})"), "");  // not dynamic
  EXPECT_NE(errors_of(R"({"force_fields": [{"type": "blast", "impulse": -1}]})"), "");
}
