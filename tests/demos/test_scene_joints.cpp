// Scene keys of articulated bodies (README "joints[i]", "chains[i]", "ragdolls[i]"; Coutinho
// Ch. 5): joints parsed into sim::JointDef in engine units (degrees -> radians, rpm -> rad/s),
// bad input reported with file and JSON pointer (exit 2 from the CLI), chains expanded into n
// links whose joint anchors coincide (a hanging chain starts in its discrete catenary, at rest),
// a ragdoll's segments, total mass and height, capsules drawn, and the export CSVs' columns.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <cmath>
#include <numbers>
#include <string>

#include "cli_util.hpp"
#include "json_reader.hpp"
#include "scene.hpp"
#include "scene_list_builder.hpp"

namespace {

using simreel::app::build_world;
using simreel::app::json;
using simreel::app::JointScene;
using simreel::app::Scene;
using simreel::app::scene_from_json;
using simreel::app::SceneError;
namespace sim = simreel::sim;
namespace render = simreel::render;
using namespace simreel::test;

constexpr double kDeg = std::numbers::pi / 180.0;

std::string errors_of(const std::string& text) {
  try {
    (void)scene_from_json(json::parse(text), "s.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

const char* kTwoBodies = R"("colliders": [
    {"type": "sphere", "name": "a", "motion": "dynamic", "radius": 0.1, "position": [0, 0, 1]},
    {"type": "capsule", "name": "b", "motion": "dynamic", "radius": 0.05, "half_height": 0.2, "position": [0, 0, 0.5]},
    {"type": "box", "name": "post", "position": [3, 0, 0.5]}])";

}  // namespace

TEST(SceneJoints, KeysReachTheJointDefInEngineUnits) {
  const Scene s = scene_from_json(json::parse(std::string("{") + kTwoBodies + R"(,
    "joints": [
      {"type": "hinge", "name": "door", "body_a": "world", "body_b": "a", "anchor": [0, 0, 1.2], "axis": [0, 2, 0],
       "limits": {"lower_deg": -30, "upper_deg": 60}, "damping": 1.5, "motor": {"rpm": 30, "max_torque_n_m": 4},
       "break_force_n": 250, "collide_connected": true},
      {"type": "spherical", "body_a": "a", "body_b": "b", "anchor": [0, 0, 0.8],
       "limits": {"cone_deg": 45, "twist_lower_deg": -10, "twist_upper_deg": 20}},
      {"type": "fixed", "body_a": "post", "body_b": "b", "anchor": [0, 0, 0.3]},
      {"type": "hinge", "body_a": "a", "body_b": "world", "anchor": [0, 0, 1], "motor": {"speed_deg_s": 90, "max_torque_n_m": 1}}
    ]})"),
                                  "s.json");
  ASSERT_EQ(s.joints.size(), 4u);
  const JointScene& h = s.joints[0];
  EXPECT_EQ(h.def.type, sim::JointType::hinge);
  EXPECT_EQ(h.def.name, "door");
  EXPECT_EQ(h.index_a, JointScene::kWorld);
  EXPECT_EQ(h.index_b, 0u);
  EXPECT_EQ(h.def.anchor, sim::Vec3(0, 0, 1.2));
  EXPECT_TRUE(h.def.limit_enabled);
  EXPECT_DOUBLE_EQ(h.def.lower_angle, -30 * kDeg);
  EXPECT_DOUBLE_EQ(h.def.upper_angle, 60 * kDeg);
  EXPECT_DOUBLE_EQ(h.def.damping, 1.5);
  EXPECT_TRUE(h.def.motor_enabled);
  EXPECT_DOUBLE_EQ(h.def.motor_speed, 30 * 2 * std::numbers::pi / 60);  // 30 rpm = π rad/s
  EXPECT_DOUBLE_EQ(h.def.max_motor_torque, 4);
  EXPECT_DOUBLE_EQ(h.def.break_force, 250);
  EXPECT_TRUE(h.def.collide_connected);
  const JointScene& sp = s.joints[1];
  EXPECT_EQ(sp.def.type, sim::JointType::spherical);
  EXPECT_EQ(sp.def.name, "joint1");  // default name: "joint" + index
  EXPECT_EQ(sp.index_a, 0u);
  EXPECT_EQ(sp.index_b, 1u);
  EXPECT_DOUBLE_EQ(sp.def.cone_angle, 45 * kDeg);
  EXPECT_DOUBLE_EQ(sp.def.twist_lower, -10 * kDeg);
  EXPECT_DOUBLE_EQ(sp.def.twist_upper, 20 * kDeg);
  EXPECT_TRUE(std::isinf(sp.def.break_force)) << "no break_force_n: never breaks";
  EXPECT_FALSE(sp.def.motor_enabled);
  EXPECT_EQ(s.joints[2].def.type, sim::JointType::fixed);
  EXPECT_EQ(s.joints[2].index_a, 2u) << "a static collider on one side";
  EXPECT_DOUBLE_EQ(s.joints[3].def.motor_speed, std::numbers::pi / 2);
  // The engine accepts all of them.
  const auto sw = build_world(s);
  ASSERT_EQ(sw.joints.size(), 4u);
  EXPECT_EQ(sw.world.definition(sw.joints[0]).body_b, sw.colliders[0]);
  EXPECT_TRUE(sw.world.definition(sw.joints[0]).body_a.id.packed() == 0) << "world = null handle";
}

TEST(SceneJoints, BadInputIsReportedWithPointerFoundAndExpected) {
  const std::string e = errors_of(std::string("{") + kTwoBodies + R"(,
    "joints": [
      {"type": "ball", "body_a": "wrld", "body_b": "bb", "anchor": [0, 0, 1]},
      {"type": "hinge", "body_a": "a", "body_b": "a", "anchor": [0, 0, 1], "limits": {"lower_deg": 10}},
      {"type": "fixed", "body_a": "world", "body_b": "post", "anchor": [0, 0, 1], "limits": {}},
      {"type": "spherical", "body_a": "a", "body_b": "b", "limits": {"cone_deg": 0}, "motor": {"rpm": 1},
       "break_force_n": -5},
      {"body_b": "a", "anchor": [0, 0, 1], "axis": [0, 0, 0]}
    ]})");
  EXPECT_NE(e.find("s.json: /joints/0/type: expected one of \"spherical\", \"hinge\", \"fixed\", found \"ball\""),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("/joints/0/body_a: expected \"world\" or the name of a collider, chain link or ragdoll segment, "
                   "found \"wrld\"; did you mean \"world\"?"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("/joints/0/body_b:"), std::string::npos) << e;
  EXPECT_NE(e.find("/joints/1/body_b: expected a body other than body_a"), std::string::npos) << e;
  EXPECT_NE(e.find("/joints/1/limits/lower_deg: expected a number in [-360, 0], found 10"), std::string::npos) << e;
  EXPECT_NE(e.find("/joints/2/limits: expected no \"limits\" on a fixed joint"), std::string::npos) << e;
  EXPECT_NE(e.find("/joints/2/body_b: expected a \"motion\": \"dynamic\" body on at least one side"), std::string::npos)
      << e;
  EXPECT_NE(e.find("/joints/3: expected an \"anchor\""), std::string::npos) << e;
  EXPECT_NE(e.find("/joints/3/limits/cone_deg: expected a number in (0, 179]"), std::string::npos) << e;
  EXPECT_NE(e.find("/joints/3/motor: expected a motor only on a \"hinge\" joint"), std::string::npos) << e;
  EXPECT_NE(e.find("/joints/3/motor: expected a \"max_torque_n_m\""), std::string::npos) << e;
  EXPECT_NE(e.find("/joints/3/break_force_n: expected a number > 0, found -5"), std::string::npos) << e;
  EXPECT_NE(e.find("/joints/4: expected a \"body_a\""), std::string::npos) << e;
  EXPECT_NE(e.find("/joints/4/axis: expected a non-zero axis"), std::string::npos) << e;
  // Names must be unique (joints refer to them).
  const std::string dup = errors_of(R"({"colliders": [{"type": "box", "name": "x"}, {"type": "sphere", "name": "x"}],
                                       "chains": [{"name": "x", "from": [0, 0, 1], "to": [1, 0, 1], "links": 1}]})");
  EXPECT_NE(dup.find("body 1 (\"x\"): expected a name not used by another collider"), std::string::npos) << dup;
  EXPECT_NE(errors_of(R"({"chains": [{"name": "c", "from": [0, 0, 1], "to": [0, 0, 1]}]})")
                .find("/chains/0/to: expected a point other than \"from\""),
            std::string::npos);
}

TEST(SceneJoints, CliExitsTwoOnABadJoint) {
  TempDir d;
  write_file(d / "s.json", std::string("{\"frames\": 2, ") + kTwoBodies +
                               R"(, "joints": [{"body_a": "world", "body_b": "nobody", "anchor": [0, 0, 1]}]})");
  const auto r = run_simreel("validate " + (d / "s.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("/joints/0/body_b: expected \"world\" or the name of a collider"), std::string::npos) << r.err;
}

// A chain of n links: n bodies named name_0..name_{n-1}; joint k at point k joins link k-1 and
// link k, and in the world the anchor as carried by both links coincides (both links' ends).
TEST(SceneJoints, ChainExpandsIntoLinksWhoseJointAnchorsCoincide) {
  const Scene s = scene_from_json(json::parse(R"({
    "chains": [{"name": "c", "from": [-1, 0, 2], "to": [1, 0, 2], "links": 6, "pin_end": true, "slack": 0.2,
                "radius": 0.03, "mass": 3.0, "break_force_n": 900}]})"),
                                  "s.json");
  ASSERT_EQ(s.colliders.size(), 6u);
  ASSERT_EQ(s.joints.size(), 7u) << "5 between links + both pinned ends";
  ASSERT_EQ(s.generated.size(), 1u);
  EXPECT_EQ(s.generated[0].collider_count, 6u);
  const double l = 2.0 * 1.2 / 6;  // link length: the straight length with 20% slack, over 6
  double length = 0;
  for (std::size_t i = 0; i < 6; ++i) {
    const auto& c = s.colliders[i];
    EXPECT_EQ(c.name, "c_" + std::to_string(i));
    EXPECT_EQ(c.type, simreel::app::ColliderScene::Type::capsule);
    EXPECT_TRUE(c.dynamic.enabled);
    EXPECT_DOUBLE_EQ(c.dynamic.mass, 0.5);
    EXPECT_NEAR(2 * (c.capsule.half_height + c.capsule.radius), l, 1e-12);
    length += 2 * (c.capsule.half_height + c.capsule.radius);
  }
  EXPECT_NEAR(length, 2.4, 1e-12);
  // The ends of link i (centre ± half length along its axis) are joints i and i+1.
  for (std::size_t k = 0; k <= 6; ++k) {
    const JointScene& j = s.joints[k];
    EXPECT_EQ(j.def.name, "c_j" + std::to_string(k));
    EXPECT_DOUBLE_EQ(j.def.break_force, 900);
    if (k > 0) {
      const auto& t = s.colliders[k - 1].capsule.transform;
      EXPECT_LT((t.translation + t.rotation * sim::Vec3(0, 0, 0.5 * l) - j.def.anchor).norm(), 1e-9) << k;
      EXPECT_EQ(j.index_a, k - 1);
    } else {
      EXPECT_EQ(j.index_a, JointScene::kWorld);
    }
    if (k < 6) {
      const auto& t = s.colliders[k].capsule.transform;
      EXPECT_LT((t.translation - t.rotation * sim::Vec3(0, 0, 0.5 * l) - j.def.anchor).norm(), 1e-9) << k;
      EXPECT_EQ(j.index_b, k);
    } else {
      EXPECT_EQ(j.index_b, JointScene::kWorld);
    }
  }
  EXPECT_LT((s.joints[0].def.anchor - sim::Vec3(-1, 0, 2)).norm(), 1e-12);
  EXPECT_LT((s.joints[6].def.anchor - sim::Vec3(1, 0, 2)).norm(), 1e-9);
  // Symmetric catenary: sagging below the ends, lowest in the middle.
  EXPECT_NEAR(s.joints[3].def.anchor.x(), 0.0, 1e-9);
  EXPECT_LT(s.joints[3].def.anchor.z(), s.joints[2].def.anchor.z());
  EXPECT_LT(s.joints[2].def.anchor.z(), s.joints[1].def.anchor.z());

  // Started in its discrete catenary (equal link weights), the chain is in equilibrium: after
  // 0.5 s no link has moved more than 2 mm (a straight start would swing down by ~0.5 m).
  auto sw = build_world(s);
  std::vector<sim::Vec3> start;
  for (const auto h : sw.colliders) start.push_back(sw.world.pose(h).translation);
  for (int f = 0; f < 15; ++f) sw.world.advance(1.0 / 30);
  double moved = 0;
  for (std::size_t i = 0; i < 6; ++i) moved = std::max(moved, (sw.world.pose(sw.colliders[i]).translation - start[i]).norm());
  EXPECT_LT(moved, 2e-3);
  for (const auto h : sw.joints) EXPECT_LT(sw.world.joint_state(h).anchor_error, 1e-4);
}

// Winter's proportions: the ragdoll is mass_kg in all, stands height_m tall (feet on the ground,
// the head's top at the height), and has the standard segments and joints.
TEST(SceneJoints, RagdollHasTheSegmentsMassAndHeight) {
  const Scene s = scene_from_json(json::parse(R"({
    "ragdolls": [{"name": "r", "position": [1, 2, 0.5], "height_m": 1.6, "mass_kg": 60, "yaw_deg": 90},
                 {"name": "q", "position": [5, 0, 0], "hands": false, "feet": false, "pose": "sitting"}]})"),
                                  "s.json");
  ASSERT_EQ(s.generated.size(), 2u);
  const auto& g = s.generated[0];
  EXPECT_EQ(g.collider_count, 15u);
  EXPECT_EQ(g.joint_count, 14u);
  EXPECT_EQ(s.generated[1].collider_count, 11u);
  double mass = 0, zmin = 1e9, zmax = -1e9;
  std::vector<std::string> names;
  for (std::size_t i = g.first_collider; i < g.first_collider + g.collider_count; ++i) {
    const auto& c = s.colliders[i];
    names.push_back(c.name);
    mass += c.dynamic.mass;
    using T = simreel::app::ColliderScene::Type;
    if (c.type == T::capsule) {
      const sim::Vec3 axis = c.capsule.transform.rotation * sim::Vec3::UnitZ();
      for (double sgn : {-1.0, 1.0}) {
        const double z = (c.capsule.transform.translation + sgn * c.capsule.half_height * axis).z();
        zmin = std::min(zmin, z - c.capsule.radius);
        zmax = std::max(zmax, z + c.capsule.radius);
      }
    } else {
      ASSERT_EQ(c.type, T::box);
      zmin = std::min(zmin, c.box.transform.translation.z() - c.box.half_extents.z());
      zmax = std::max(zmax, c.box.transform.translation.z() + c.box.half_extents.z());
    }
  }
  EXPECT_NEAR(mass, 60.0, 1e-9);
  EXPECT_NEAR(zmin, 0.5 + 0.002, 1e-9) << "feet on position.z (+2 mm)";
  EXPECT_NEAR(zmax - zmin, 1.6, 1e-9);
  for (const char* n : {"r_head", "r_chest", "r_pelvis", "r_upper_arm_l", "r_forearm_r", "r_hand_l", "r_thigh_r",
                        "r_shin_l", "r_foot_r"})
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
  // Hinges at elbows and knees with limits (bend one way); cone-twist at neck, shoulders, hips.
  int hinges = 0, spherical = 0;
  for (std::size_t k = g.first_joint; k < g.first_joint + g.joint_count; ++k) {
    const auto& d = s.joints[k].def;
    EXPECT_TRUE(d.limit_enabled) << d.name;
    if (d.type == sim::JointType::hinge) {
      ++hinges;
      EXPECT_LE(d.lower_angle, 0.0);
      EXPECT_GE(d.upper_angle, 0.0);
    } else {
      ++spherical;
      EXPECT_GT(d.cone_angle, 0.0);
    }
    if (d.name == "r_knee_l") {
      EXPECT_DOUBLE_EQ(d.lower_angle, 0.0) << "a standing knee is straight: no hyperextension";
      EXPECT_NEAR(d.upper_angle, 140 * kDeg, 1e-12);
    }
  }
  EXPECT_EQ(hinges, 6);     // elbows, knees, ankles
  EXPECT_EQ(spherical, 8);  // waist, neck, shoulders, wrists, hips
  // The second ragdoll keeps 75 kg without hands and feet; sitting, its knees start bent 90°.
  double mass_q = 0;
  for (std::size_t i = s.generated[1].first_collider; i < s.colliders.size(); ++i) mass_q += s.colliders[i].dynamic.mass;
  EXPECT_NEAR(mass_q, 75.0, 1e-9);
  for (const auto& j : s.joints)
    if (j.def.name == "q_knee_l") {
      EXPECT_NEAR(j.def.lower_angle, -90 * kDeg, 1e-12);
      EXPECT_NEAR(j.def.upper_angle, 50 * kDeg, 1e-12);
    }
  // The engine takes it, and every joint's anchors coincide at registration.
  auto sw = build_world(s);
  for (const auto h : sw.joints) EXPECT_LT(sw.world.joint_state(h).anchor_error, 1e-12);
}

TEST(SceneJoints, CapsulesAreDrawnAsCapsuleMeshes) {
  const Scene s = scene_from_json(json::parse(R"({"colliders": [
      {"type": "capsule", "radius": 0.1, "half_height": 0.3, "rotation_deg": [90, 0, 0]},
      {"type": "capsule", "motion": "dynamic", "radius": 0.2, "half_height": 0.1}]})"),
                                  "s.json");
  const auto sw = build_world(s);
  const render::SceneList list = simreel::app::initial_scene_list(s, sw);
  ASSERT_EQ(list.added.size(), 2u);
  const auto* mesh = std::get_if<render::MeshDesc>(&list.added[0].desc);
  ASSERT_NE(mesh, nullptr);
  float zmin = 1e9f, zmax = -1e9f, rmax = 0;
  for (std::size_t v = 0; v < mesh->positions.size() / 3; ++v) {
    const float x = mesh->positions[3 * v], y = mesh->positions[3 * v + 1], z = mesh->positions[3 * v + 2];
    zmin = std::min(zmin, z);
    zmax = std::max(zmax, z);
    rmax = std::max(rmax, std::hypot(x, y));
  }
  EXPECT_NEAR(zmin, -0.4f, 1e-6f);  // -(half_height + radius)
  EXPECT_NEAR(zmax, 0.4f, 1e-6f);
  EXPECT_NEAR(rmax, 0.1f, 1e-6f);
  // The static capsule is a static body turned about x: its axis along -y.
  const sim::MovedObject p = sw.world.pose(sw.colliders[0]);
  EXPECT_NEAR((p.rotation * sim::Vec3::UnitZ() - sim::Vec3(0, -1, 0)).norm(), 0.0, 1e-12);
}

TEST(SceneJoints, ExportBodiesAndJointsCsvColumns) {
  TempDir d;
  write_file(d / "s.json", R"({"frames": 4, "colliders": [
      {"type": "sphere", "name": "bob", "motion": "dynamic", "mass": 1, "radius": 0.05, "position": [0.3, 0, 1]}],
    "joints": [{"name": "pivot", "body_a": "world", "body_b": "bob", "anchor": [0, 0, 1]}]})");
  const auto r = run_simreel("simulate " + (d / "s.json").string() + " --export-bodies " + (d / "b.csv").string() +
                             " --export-joints " + (d / "j.csv").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string b = slurp(d / "b.csv"), j = slurp(d / "j.csv");
  EXPECT_EQ(b.substr(0, b.find('\n')), "frame,time,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz");
  EXPECT_EQ(j.substr(0, j.find('\n')), "frame,time,joint,anchor_error,fx,fy,fz,force,angle,twist,broken");
  EXPECT_EQ(count_lines(b), 1 + 4);
  EXPECT_EQ(count_lines(j), 1 + 4);
  EXPECT_NE(b.find("\n0,0,bob,0.3,0,1,1,0,0,0,0,0,0,0,0,0\n"), std::string::npos) << b;
  // Frame 3 (0.1 s): the pendulum released from the horizontal (L = 0.3 m, 1 kg) pulls on its
  // pivot (a rod tension of several newtons); the drift stays below 0.1 mm.
  const std::size_t row = j.find("\n3,");
  ASSERT_NE(row, std::string::npos) << j;
  std::vector<std::string> cells;
  std::string line = j.substr(row + 1, j.find('\n', row + 1) - row - 1);
  for (std::size_t p = 0, q; p <= line.size(); p = q + 1) {
    q = line.find(',', p);
    if (q == std::string::npos) q = line.size();
    cells.push_back(line.substr(p, q - p));
  }
  ASSERT_EQ(cells.size(), 11u) << line;
  EXPECT_EQ(cells[2], "pivot");
  EXPECT_LT(std::stod(cells[3]), 1e-4) << "anchor error (m)";
  EXPECT_GT(std::stod(cells[7]), 1.0) << "force (N)";
  EXPECT_NEAR(std::hypot(std::stod(cells[4]), std::stod(cells[5]), std::stod(cells[6])), std::stod(cells[7]), 1e-9);
  EXPECT_EQ(cells[10], "0");
  // No export asked for: a usage error.
  EXPECT_EQ(run_simreel("simulate " + (d / "s.json").string()).code, 2);
}

// The ragdoll's hinge axes point the anatomical way: a standing ragdoll that collapses bends its
// knees backward and its elbows forward, never the other way. Measured on the bodies, not on the
// joints' own angle: the shin's long axis in the thigh's frame (x = forward in the template)
// swings to -x (the heel towards the buttock), the forearm's in the upper arm's frame to +x; a
// reversed hinge axis would let them bend the other way and lock the anatomical direction.
TEST(SceneJoints, RagdollKneesAndElbowsBendOneWay) {
  const Scene s = scene_from_json(json::parse(R"({"colliders": [{"type": "plane", "name": "ground"}],
    "ragdolls": [{"name": "r", "position": [0, 0, 0], "velocity": [0.3, 0, 0]}]})"),
                                  "s.json");
  auto sw = build_world(s);
  auto index = [&](const std::string& name) {
    for (std::size_t i = 0; i < s.colliders.size(); ++i)
      if (s.colliders[i].name == name) return i;
    return s.colliders.size();
  };
  // Forward component of the child's long axis (pointing away from the joint) in the parent's frame.
  auto forward = [&](const char* parent, const char* child) {
    const auto rp = sw.world.pose(sw.colliders[index(parent)]).rotation;
    const auto rc = sw.world.pose(sw.colliders[index(child)]).rotation;
    return (rp.transpose() * rc * sim::Vec3(0, 0, -1)).x();
  };
  const std::pair<const char*, const char*> knees[] = {{"r_thigh_l", "r_shin_l"}, {"r_thigh_r", "r_shin_r"}};
  const std::pair<const char*, const char*> elbows[] = {{"r_upper_arm_l", "r_forearm_l"},
                                                        {"r_upper_arm_r", "r_forearm_r"}};
  double knee_min = 0, knee_max = -1, elbow_min = 1, elbow_max = 0, drift = 0;
  for (int f = 0; f < 45; ++f) {
    sw.world.advance(1.0 / 30);
    for (const auto& [a, b] : knees) {
      knee_min = std::min(knee_min, forward(a, b));
      knee_max = std::max(knee_max, forward(a, b));
    }
    for (const auto& [a, b] : elbows) {
      elbow_min = std::min(elbow_min, forward(a, b));
      elbow_max = std::max(elbow_max, forward(a, b));
    }
    for (const auto h : sw.joints) drift = std::max(drift, sw.world.joint_state(h).anchor_error);
  }
  EXPECT_LT(knee_min, -0.5) << "a knee flexes by more than 30 degrees, heel backward";
  EXPECT_LT(knee_max, 0.03) << "no knee bends forward (within 2 degrees)";
  EXPECT_GT(elbow_max, 0.17) << "an elbow flexes by more than 10 degrees, hand forward";
  EXPECT_GT(elbow_min, -0.03) << "no elbow bends backward (within 2 degrees)";
  EXPECT_LT(drift, 1e-4);
}

TEST(SceneSprings, KeysReachTheEngineAndABodyHangsAtTheStaticExtension) {
  // springs[i] (§4.3.3): a 2 kg box on a 200 N/m spring from a world point, released at the
  // spring's rest length, oscillates down to 2 m g / k below its start (the static extension is
  // m g / k); the scene reaches the engine in SI units with the rest length defaulting to the
  // anchors' distance.
  const Scene s = scene_from_json(json::parse(R"({
    "colliders": [{"type": "box", "name": "w", "motion": "dynamic", "mass": 2, "position": [0, 0, 1],
                   "half_extents": [0.1, 0.1, 0.1]}],
    "springs": [{"name": "coil", "body_a": "world", "body_b": "w", "anchor_a": [0, 0, 2], "anchor_b": [0, 0, 1.1],
                 "stiffness": 200, "damping": 0}]})"),
                                  "s.json");
  ASSERT_EQ(s.springs.size(), 1u);
  EXPECT_EQ(s.springs[0].def.name, "coil");
  EXPECT_EQ(s.springs[0].index_a, JointScene::kWorld);
  EXPECT_EQ(s.springs[0].index_b, 0u);
  EXPECT_DOUBLE_EQ(s.springs[0].def.stiffness, 200.0);
  EXPECT_LT(s.springs[0].def.rest_length, 0.0) << "default: the distance at t = 0";
  simreel::app::SceneWorld sw = simreel::app::build_world(s);
  ASSERT_EQ(sw.springs.size(), 1u);
  double lowest = 1.0;
  for (int f = 0; f < 60; ++f) {
    sw.world.advance(1.0 / 60.0);
    lowest = std::min(lowest, sw.world.pose(sw.colliders[0]).translation.z());
  }
  EXPECT_NEAR(lowest, 1.0 - 2.0 * 2.0 * 9.81 / 200.0, 0.004);
}

TEST(SceneSprings, BadSpringsAreRefusedWithTheirPointer) {
  const std::string base = std::string("{") + kTwoBodies + R"(, "springs": [)";
  EXPECT_NE(errors_of(base + R"({"body_a": "world", "body_b": "aa", "anchor_a": [0,0,2], "anchor_b": [0,0,1], "stiffness": 1}]})")
                .find("/springs/0/body_b: expected \"world\" or the name of a collider"),
            std::string::npos);
  EXPECT_NE(errors_of(base + R"({"body_b": "a", "anchor_a": [0,0,2], "anchor_b": [0,0,1], "stiffness": -1}]})")
                .find("/springs/0/stiffness: expected a number > 0"),
            std::string::npos);
  EXPECT_NE(errors_of(base + R"({"body_b": "a", "anchor_b": [0,0,1], "stiffness": 1}]})").find("\"anchor_a\""),
            std::string::npos);
  EXPECT_NE(errors_of(base + R"({"body_a": "world", "body_b": "post", "anchor_a": [0,0,2], "anchor_b": [0,0,1], "stiffness": 1}]})")
                .find("\"dynamic\" body on at least one side"),
            std::string::npos);
}
