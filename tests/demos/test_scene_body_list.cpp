// bodies[i] (README "bodies[i]", Coutinho Ch. 4): keys reach the engine's BodyDef in engine units,
// compounds of shapes at offsets, convex hulls from points and from a mesh file, a dynamic mesh
// file as the compound of its closed parts' hulls, the same trajectory as a colliders[i]
// "motion": "dynamic" box, names for springs and joints, the drawable (no GL), and every bad value
// reported with the file and JSON pointer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <variant>

#include <unistd.h>

#include "json_reader.hpp"
#include "scene.hpp"
#include "simreel/assets/mesh.hpp"
#include "scene_list_builder.hpp"
#include "simreel/render/image.hpp"
#include "simreel/render/mesh.hpp"

namespace {

using simreel::app::build_world;
using simreel::app::ColliderScene;
using simreel::app::json;
using simreel::app::Scene;
using simreel::app::scene_from_json;
using simreel::app::SceneError;
using simreel::app::SceneWorld;
namespace render = simreel::render;
namespace sim = simreel::sim;

constexpr double kDeg = std::numbers::pi / 180.0;

std::string errors_of(const std::string& text, const std::string& file = "s.json") {
  try {
    (void)scene_from_json(json::parse(text), file);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

std::string body_errors(const std::string& body) { return errors_of("{\"bodies\": [" + body + "]}"); }

/// A folder with an OBJ of two unit cubes (closed, apart) and one of an open square.
std::filesystem::path mesh_folder() {
  const auto dir = std::filesystem::temp_directory_path() / ("simreel_body_list_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream two(dir / "two_cubes.obj");
  for (int c = 0; c < 2; ++c)
    for (int i = 0; i < 8; ++i)
      two << "v " << ((i & 1) ? 0.5 : -0.5) + 3.0 * c << ' ' << ((i & 2) ? 0.5 : -0.5) << ' '
          << ((i & 4) ? 0.5 : -0.5) << '\n';
  const int quads[6][4] = {{1, 3, 4, 2}, {5, 6, 8, 7}, {1, 2, 6, 5}, {3, 7, 8, 4}, {1, 5, 7, 3}, {2, 4, 8, 6}};
  for (int c = 0; c < 2; ++c)
    for (const auto& q : quads) two << "f " << q[0] + 8 * c << ' ' << q[1] + 8 * c << ' ' << q[2] + 8 * c << ' ' << q[3] + 8 * c << '\n';
  // An L-shaped prism (3 unit cells, 1 m tall): concave, one closed part.
  std::ofstream ell(dir / "ell.obj");
  const double xy[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  for (int z = 0; z < 2; ++z)
    for (const auto& p : xy) ell << "v " << p[0] << ' ' << p[1] << ' ' << z << '\n';
  ell << "f 7 8 9\nf 7 9 10\nf 7 10 11\nf 7 11 12\nf 1 3 2\nf 1 4 3\nf 1 5 4\nf 1 6 5\n";
  for (int i = 1; i <= 6; ++i) ell << "f " << i << ' ' << i % 6 + 1 << ' ' << i % 6 + 7 << ' ' << i + 6 << '\n';
  // A unit cube whose faces use two materials of an MTL file (three faces each).
  std::ofstream mtl(dir / "two.mtl");
  mtl << "newmtl red\nKd 0.9 0.1 0.1\nnewmtl blue\nKd 0.1 0.2 0.9\n";
  std::ofstream two_mats(dir / "two_mats.obj");
  two_mats << "mtllib two.mtl\n";
  for (int i = 0; i < 8; ++i)
    two_mats << "v " << ((i & 1) ? 0.5 : -0.5) << ' ' << ((i & 2) ? 0.5 : -0.5) << ' ' << ((i & 4) ? 0.5 : -0.5) << '\n';
  for (int q = 0; q < 6; ++q) {
    if (q == 0) two_mats << "usemtl red\n";
    if (q == 3) two_mats << "usemtl blue\n";
    two_mats << "f " << quads[q][0] << ' ' << quads[q][1] << ' ' << quads[q][2] << ' ' << quads[q][3] << '\n';
  }
  std::ofstream open(dir / "open.obj");
  open << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nf 1 2 3 4\nf 1 2 5\n";
  return dir;
}

}  // namespace

TEST(SceneBodyList, KeysReachTheBodyDefInEngineUnits) {
  const Scene s = scene_from_json(json::parse(R"({
    "simulation": {"gravity": [0, 0, -5]},
    "bodies": [
      {"name": "dumbbell", "position": [1, 2, 3], "rotation_deg": [0, 0, 90], "density": 500,
       "velocity": [1, 0, 0], "angular_velocity_deg": [0, 0, 180], "linear_damping": 0.1, "angular_damping": 0.2,
       "material": {"restitution": 0.3, "friction": 0.7, "color": [0.1, 0.2, 0.3]},
       "shapes": [{"type": "sphere", "radius": 0.2, "position": [-0.5, 0, 0]},
                  {"type": "sphere", "radius": 0.2, "position": [0.5, 0, 0], "density": 1000},
                  {"type": "capsule", "radius": 0.05, "half_height": 0.4, "rotation_deg": [0, 90, 0]}]},
      {"name": "wedge", "type": "static", "shape": "convex_hull",
       "points": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0.1, 0.1, 0.1]]},
      {"name": "door", "type": "kinematic", "shape": "box", "half_extents": [0.5, 0.05, 1],
       "path": {"keys": [{"time": 0, "position": [0, 0, 1]}, {"time": 1, "position": [1, 0, 1]}]}}
    ]})"),
                                  "s.json");
  ASSERT_EQ(s.colliders.size(), 3u);
  const sim::BodyDef& d = s.colliders[0].body;
  EXPECT_EQ(s.colliders[0].type, ColliderScene::Type::body);
  EXPECT_TRUE(s.colliders[0].dynamic.enabled);
  EXPECT_EQ(d.type, sim::BodyType::dynamic);
  EXPECT_EQ(d.name, "dumbbell");
  EXPECT_EQ(d.pose.translation, sim::Vec3(1, 2, 3));
  EXPECT_NEAR((d.pose.rotation * sim::Vec3::UnitX() - sim::Vec3::UnitY()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(d.angular_velocity.z(), 180 * kDeg, 1e-12);
  EXPECT_EQ(d.linear_velocity, sim::Vec3(1, 0, 0));
  EXPECT_EQ(d.linear_damping, 0.1);
  EXPECT_EQ(d.angular_damping, 0.2);
  EXPECT_EQ(d.gravity, sim::Vec3(0, 0, -5));
  ASSERT_EQ(d.shapes.size(), 3u);
  EXPECT_EQ(d.shapes[0].offset.translation, sim::Vec3(-0.5, 0, 0));
  EXPECT_EQ(d.shapes[0].density, 500.0);
  EXPECT_EQ(d.shapes[1].density, 1000.0);
  EXPECT_EQ(d.shapes[2].type, sim::ShapeType::capsule);
  EXPECT_EQ(d.shapes[1].material.restitution, 0.3);
  EXPECT_EQ(d.shapes[2].material.friction, 0.7);
  EXPECT_FLOAT_EQ(s.colliders[0].color.x(), 0.1f);
  EXPECT_EQ(s.colliders[1].body.type, sim::BodyType::static_body);
  EXPECT_EQ(s.colliders[1].body.shapes[0].type, sim::ShapeType::convex_hull);
  EXPECT_EQ(s.colliders[1].body.shapes[0].points.size(), 5u);
  EXPECT_EQ(s.colliders[2].body.type, sim::BodyType::kinematic);
  EXPECT_EQ(s.colliders[2].body.path.keys.size(), 2u);

  // The engine gets them: the dumbbell's mass is its spheres' (500 and 1000 kg/m³) + the bar.
  SceneWorld sw = build_world(s);
  const sim::BodyMotion m = sw.world.motion(sw.colliders[0]);
  const double v = 4.0 / 3.0 * std::numbers::pi * 0.008;
  const double bar = std::numbers::pi * 0.0025 * 0.8 + 4.0 / 3.0 * std::numbers::pi * 0.05 * 0.05 * 0.05;
  EXPECT_NEAR(m.mass, 500 * v + 1000 * v + 500 * bar, 1e-9);
  // Heavier sphere at body +x, turned 90° about z: the centre of mass moves to +y of (1, 2, 3).
  EXPECT_NEAR(m.center_of_mass.y(), 2.0 + 0.5 * (1000 * v - 500 * v) / m.mass, 1e-9);
}

TEST(SceneBodyList, BodyBoxFollowsTheSameTrajectoryAsADynamicCollider) {
  // One engine path: the same box from bodies[i] and from colliders[i] "motion": "dynamic".
  auto run2 = [](const std::string& text) {
    Scene s = scene_from_json(json::parse(text), "s.json");
    SceneWorld sw = build_world(s);
    for (int i = 0; i < 60; ++i) sw.world.advance(1.0 / 30.0);
    return sw.world.pose(sw.colliders[1]);
  };
  const sim::MovedObject c = run2(R"({"colliders": [{"type": "plane"}, {"type": "box", "motion": "dynamic",
      "half_extents": [0.2, 0.3, 0.1], "position": [0, 0, 1], "rotation_deg": [20, 10, 0], "restitution": 0.2,
      "friction": 0.6}]})");
  const sim::MovedObject b = run2(R"({"colliders": [{"type": "plane"}], "bodies": [{"shape": "box",
      "half_extents": [0.2, 0.3, 0.1], "position": [0, 0, 1], "rotation_deg": [20, 10, 0],
      "material": {"restitution": 0.2, "friction": 0.6}}]})");
  EXPECT_EQ(b.translation, c.translation);
  EXPECT_EQ(b.rotation, c.rotation);
  EXPECT_NEAR(c.translation.z(), 0.1, 2e-3);  // it fell and lies on its largest face
}

TEST(SceneBodyList, AShapeOfACompoundHasItsOwnContactMaterial) {
  // A box sliding on the ground (friction 1) under a sphere riding on it, not touching the
  // ground. The box's own friction 0.16 gives the pair mu = sqrt(0.16 * 1) = 0.4 and the
  // deceleration mu g; the body's (the sphere's) 0.5 would give 0.71 g.
  const Scene s = scene_from_json(json::parse(R"({"colliders": [{"type": "plane", "friction": 1.0}],
      "bodies": [{"position": [0, 0, 0.1], "velocity": [3, 0, 0], "material": {"friction": 0.5, "restitution": 0.3},
        "shapes": [{"type": "box", "half_extents": [0.2, 0.2, 0.1], "material": {"friction": 0.16}},
                   {"type": "sphere", "radius": 0.1, "position": [0, 0, 0.25]}]}]})"),
                                  "s.json");
  const sim::BodyDef& b = s.colliders[1].body;
  ASSERT_EQ(b.shapes.size(), 2u);
  EXPECT_EQ(b.shapes[0].material.friction, 0.16);
  EXPECT_EQ(b.shapes[0].material.restitution, 0.3) << "the keys it does not give are the body's";
  EXPECT_EQ(b.shapes[1].material.friction, 0.5);
  SceneWorld sw = build_world(s);
  const double h = 1.0 / 240.0, T = 0.5;
  for (int i = 0; i < 12; ++i) sw.world.advance(h);  // settle the contact
  const double v0 = sw.world.motion(sw.colliders[1]).linear_velocity.x();
  for (int i = 0; i < int(T / h + 0.5); ++i) sw.world.advance(h);
  const double v1 = sw.world.motion(sw.colliders[1]).linear_velocity.x();
  EXPECT_NEAR((v0 - v1) / T, 0.4 * 9.81, 0.03 * 0.4 * 9.81);
  EXPECT_NE(body_errors(R"({"shapes": [{"type": "box", "material": {"friction": -1}}]})"), "");
  const std::string colour = body_errors(R"({"shapes": [{"type": "box", "material": {"color": [1, 0]}}]})");
  EXPECT_NE(colour.find("/bodies/0/shapes/0/material/color"), std::string::npos) << colour;
  const std::string texture = body_errors(R"({"shapes": [{"type": "box", "material": {"texture": "nope.png"}}]})");
  EXPECT_NE(texture.find("/bodies/0/shapes/0/material/texture: expected an image file"), std::string::npos) << texture;
}

TEST(SceneBodyList, AShapeWithItsOwnColourIsDrawnInIt) {
  // A mallet: a wooden handle (the body's colour) and a red head. The drawable gets one part per
  // shape, each over exactly that shape's triangles (box 12, sphere 48 x 24 x 2 - 2 x 48).
  const Scene s = scene_from_json(json::parse(R"({"bodies": [{"material": {"color": [0.6, 0.4, 0.2]}, "shapes": [
      {"type": "box", "half_extents": [0.05, 0.05, 0.5]},
      {"type": "sphere", "radius": 0.2, "position": [0, 0, 0.6], "material": {"color": [0.9, 0.1, 0.1]}}]},
      {"shapes": [{"type": "box"}, {"type": "sphere", "position": [0, 0, 2]}]}]})"),
                                  "s.json");
  SceneWorld sw = build_world(s);
  const render::SceneList list = simreel::app::initial_scene_list(s, sw);
  const auto& d = std::get<render::MeshDesc>(list.added[0].desc);
  ASSERT_EQ(d.parts.size(), 2u);
  const render::MeshDesc sphere = render::make_sphere_mesh(0.2f, 48);
  EXPECT_EQ(d.parts[0].first_triangle, 0u);
  EXPECT_EQ(d.parts[0].triangle_count, 12u);
  EXPECT_EQ(d.parts[1].first_triangle, 12u);
  EXPECT_EQ(d.parts[1].triangle_count, sphere.indices.size() / 3);
  EXPECT_EQ(d.indices.size(), 3 * std::size_t(d.parts[1].first_triangle + d.parts[1].triangle_count));
  EXPECT_FLOAT_EQ(d.parts[0].material.base_color.x(), 0.6f);
  EXPECT_FLOAT_EQ(d.parts[0].material.base_color.y(), 0.4f);
  EXPECT_FLOAT_EQ(d.parts[1].material.base_color.x(), 0.9f);
  EXPECT_FLOAT_EQ(d.parts[1].material.base_color.y(), 0.1f);
  // Every triangle of the head part lies in the sphere around (0, 0, 0.6); the handle's not.
  for (std::uint32_t t = d.parts[1].first_triangle; t < d.parts[1].first_triangle + d.parts[1].triangle_count; ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = d.indices[3 * t + std::size_t(k)];
      const Eigen::Vector3f p(d.positions[3 * v], d.positions[3 * v + 1], d.positions[3 * v + 2]);
      ASSERT_NEAR((p - Eigen::Vector3f(0, 0, 0.6f)).norm(), 0.2f, 1e-5f);
    }
  // A body whose shapes keep the body's material stays one material, no parts.
  EXPECT_TRUE(std::get<render::MeshDesc>(list.added[1].desc).parts.empty());
}

TEST(SceneBodyList, MeshFilesGiveHullsAndDynamicCompoundsOfTheirClosedParts) {
  const auto dir = mesh_folder();
  const std::string file = (dir / "s.json").string();
  const Scene s = scene_from_json(json::parse(R"({"bodies": [
      {"name": "pair", "shape": "mesh", "mesh": "two_cubes.obj", "density": 100, "position": [0, 0, 5]},
      {"name": "hull", "shape": "convex_hull", "mesh": "two_cubes.obj", "scale": 0.5},
      {"name": "static", "type": "static", "shape": "mesh", "mesh": "open.obj"}]})"),
                                  file);
  ASSERT_EQ(s.colliders.size(), 3u);
  const sim::BodyDef& pair = s.colliders[0].body;
  ASSERT_EQ(pair.shapes.size(), 2u);  // two closed parts -> two hulls
  EXPECT_EQ(pair.shapes[0].type, sim::ShapeType::convex_hull);
  EXPECT_EQ(pair.shapes[1].points.size(), 8u);
  EXPECT_TRUE(s.colliders[0].body_draw[1].skip);
  EXPECT_EQ(s.colliders[1].body.shapes.size(), 1u);  // one hull around both cubes
  EXPECT_EQ(s.colliders[2].body.shapes[0].type, sim::ShapeType::mesh);
  SceneWorld sw = build_world(s);
  const sim::BodyMotion m = sw.world.motion(sw.colliders[0]);
  EXPECT_NEAR(m.mass, 200.0, 1e-9);                                       // two 1 m³ cubes at 100 kg/m³
  EXPECT_NEAR((m.center_of_mass - sim::Vec3(1.5, 0, 5)).norm(), 0.0, 1e-9);  // midway
  const sim::BodyMotion h = sw.world.motion(sw.colliders[1]);
  EXPECT_NEAR(h.mass, 1000.0 * 2.0 * 0.5 * 0.5, 1e-9);  // the hull (scaled 0.5): 2 x 0.5 x 0.5 m

  // Drawables: the compound draws its file once (two cubes, 12 triangles); the hull its 6 faces.
  const render::SceneList list = simreel::app::initial_scene_list(s, sw);
  const auto& pair_mesh = std::get<render::MeshDesc>(list.added[0].desc);
  EXPECT_EQ(pair_mesh.indices.size(), 3u * 24u);
  const auto& hull_mesh = std::get<render::MeshDesc>(list.added[1].desc);
  EXPECT_EQ(hull_mesh.indices.size(), 3u * 12u);
  EXPECT_EQ(hull_mesh.positions.size(), 3u * 24u);  // flat: 4 vertices per face

  const std::string bad = errors_of(R"({"bodies": [{"shape": "mesh", "mesh": "open.obj"}]})", file);
  EXPECT_NE(bad.find("/bodies/0/mesh: expected a file of closed parts for a dynamic mesh"), std::string::npos) << bad;
  std::filesystem::remove_all(dir);
}

TEST(SceneBodyList, ADynamicConcaveMeshIsTheCompoundOfItsConvexDecomposition) {
  const auto dir = mesh_folder();
  const std::string file = (dir / "s.json").string();
  const Scene s = scene_from_json(json::parse(R"({"bodies": [
      {"name": "ell", "shape": "mesh", "mesh": "ell.obj", "density": 100},
      {"name": "one", "shape": "mesh", "mesh": "ell.obj", "density": 100, "max_convex_hulls": 1}]})"),
                                  file);
  const sim::BodyDef& ell = s.colliders[0].body;
  ASSERT_EQ(ell.shapes.size(), 2u);  // an L: two boxes
  EXPECT_FALSE(s.colliders[0].body_draw[0].skip);
  EXPECT_TRUE(s.colliders[0].body_draw[1].skip);  // the file is drawn once
  EXPECT_EQ(s.colliders[1].body.shapes.size(), 1u);
  SceneWorld sw = build_world(s);
  const sim::BodyMotion m = sw.world.motion(sw.colliders[0]);
  EXPECT_NEAR(m.mass, 300.0, 1e-9);  // the L's 3 m³, not its hull's 3.5
  EXPECT_NEAR((m.center_of_mass - sim::Vec3(5.0 / 6.0, 5.0 / 6.0, 0.5)).norm(), 0.0, 1e-9);
  EXPECT_NEAR(sw.world.motion(sw.colliders[1]).mass, 350.0, 1e-9);  // one piece: the hull

  const std::string bad = errors_of(R"({"bodies": [{"shape": "mesh", "mesh": "ell.obj", "max_convex_hulls": 0}]})", file);
  EXPECT_NE(bad.find("/bodies/0/max_convex_hulls"), std::string::npos) << bad;
  std::filesystem::remove_all(dir);
}

TEST(SceneBodyList, CompoundDrawableHasEveryShapeAtItsOffset) {
  const Scene s = scene_from_json(json::parse(R"({"bodies": [{"shapes": [
      {"type": "box", "half_extents": [0.5, 0.5, 0.5]},
      {"type": "convex_hull", "position": [0, 0, 2], "points": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]}]}]})"),
                                  "s.json");
  SceneWorld sw = build_world(s);
  const render::SceneList list = simreel::app::initial_scene_list(s, sw);
  const auto& d = std::get<render::MeshDesc>(list.added[0].desc);
  EXPECT_EQ(d.indices.size(), 3u * (12u + 4u));
  float zmax = -1e9f;
  for (std::size_t i = 2; i < d.positions.size(); i += 3) zmax = std::max(zmax, d.positions[i]);
  EXPECT_FLOAT_EQ(zmax, 3.0f);  // the tetrahedron's apex at offset z 2 + 1
}

TEST(SceneBodyList, AMeshFileWithSeveralMaterialsIsDrawnInThemUnlessTheSceneGivesAColour) {
  const auto dir = mesh_folder();
  const std::string file = (dir / "s.json").string();
  const Scene s = scene_from_json(json::parse(R"({
      "colliders": [{"type": "mesh", "file": "two_mats.obj"}, {"type": "mesh", "file": "two_mats.obj", "color": [0, 1, 0]}],
      "bodies": [{"shape": "mesh", "mesh": "two_mats.obj", "position": [3, 0, 1]},
                 {"shape": "mesh", "mesh": "two_mats.obj", "position": [6, 0, 1], "material": {"color": [0, 1, 0]}},
                 {"shapes": [{"type": "sphere", "radius": 0.2, "position": [0, 0, 1]},
                             {"type": "convex_hull", "mesh": "two_mats.obj"}], "position": [9, 0, 1]}]})"),
                                  file);
  const simreel::assets::TriangleMesh asset = simreel::assets::load_mesh(dir / "two_mats.obj");
  // (assimp may add a default material of its own; the faces use the two named ones)
  const auto named = [&](const std::string& name) {
    for (const auto& m : asset.materials)
      if (m.name == name) return m.base_color;
    ADD_FAILURE() << "no material " << name;
    return std::array<float, 4>{};
  };
  SceneWorld sw = build_world(s);
  const render::SceneList list = simreel::app::initial_scene_list(s, sw);
  // The file's materials, each over its own six triangles, in its own colour.
  for (const std::size_t k : {std::size_t(0), std::size_t(2)}) {
    const auto& d = std::get<render::MeshDesc>(list.added[k].desc);
    ASSERT_EQ(d.parts.size(), 2u) << k;
    EXPECT_EQ(d.indices.size(), 3u * 12u);
    for (std::size_t p = 0; p < 2; ++p) {
      EXPECT_EQ(d.parts[p].first_triangle, 6u * p);
      EXPECT_EQ(d.parts[p].triangle_count, 6u);
      const auto want = named(p == 0 ? "red" : "blue");
      EXPECT_FLOAT_EQ(d.parts[p].material.base_color.x(), want[0]) << k << " part " << p;
      EXPECT_FLOAT_EQ(d.parts[p].material.base_color.z(), want[2]) << k << " part " << p;
    }
    EXPECT_GT(d.parts[0].material.base_color.x(), d.parts[0].material.base_color.z());  // red
    EXPECT_GT(d.parts[1].material.base_color.z(), d.parts[1].material.base_color.x());  // blue
  }
  // A colour in the scene paints the whole file, as before.
  EXPECT_TRUE(std::get<render::MeshDesc>(list.added[1].desc).parts.empty());
  EXPECT_TRUE(std::get<render::MeshDesc>(list.added[3].desc).parts.empty());
  // A hull built from the file is drawn flat in the body's colour: no file materials.
  EXPECT_TRUE(std::get<render::MeshDesc>(list.added[4].desc).parts.empty());
  std::filesystem::remove_all(dir);
}

TEST(SceneBodyList, SpringsAndJointsNameBodies) {
  const Scene s = scene_from_json(json::parse(R"({"bodies": [{"name": "bob", "shape": "sphere", "radius": 0.1}],
      "springs": [{"body_a": "world", "body_b": "bob", "anchor_a": [0, 0, 2], "anchor_b": [0, 0, 0], "stiffness": 10}]})"),
                                  "s.json");
  EXPECT_EQ(s.springs[0].index_b, 0u);
  const std::string e = errors_of(R"({"bodies": [{"name": "bob", "shape": "sphere"}],
      "springs": [{"body_a": "world", "body_b": "bbo", "stiffness": 10}]})");
  EXPECT_NE(e.find("/springs/0/body_b: expected \"world\" or the name of a collider"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean \"bob\"?"), std::string::npos) << e;
}

TEST(SceneBodyList, BadBodiesAreReportedWithTheirPointers) {
  auto has = [](const std::string& errors, const std::string& part) {
    EXPECT_NE(errors.find(part), std::string::npos) << "missing: " << part << "\nin: " << errors;
  };
  has(body_errors(R"({"type": "dynamc", "shape": "sphere"})"), "s.json: /bodies/0/type: expected one of \"dynamic\"");
  has(body_errors(R"({"shape": "sphere", "densty": 3})"), "/bodies/0/densty");
  has(body_errors(R"({"shape": "sphere", "densty": 3})"), "did you mean \"density\"");
  has(body_errors(R"({"shape": "spheer"})"), "/bodies/0/shape: expected one of \"sphere\"");
  has(body_errors(R"({"name": "x"})"), "/bodies/0: expected \"shapes\": [...] or an inline \"shape\"");
  has(body_errors(R"({"shape": "convex_hull", "points": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]})"),
      "/bodies/0/points: expected points bounding a volume for a convex hull (at least 4, not all in one plane), "
      "found: all points are coplanar");
  has(body_errors(R"({"shape": "convex_hull", "points": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, "a", 0]]})"),
      "/bodies/0/points/3: expected a point [x, y, z] (m)");
  has(body_errors(R"({"shape": "convex_hull"})"), "/bodies/0: expected \"points\"");
  has(body_errors(R"({"shapes": [{"type": "box", "half_extents": [1, -1, 1]}]})"), "/bodies/0/shapes/0/half_extents");
  has(body_errors(R"({"type": "static", "shape": "box", "velocity": [1, 0, 0]})"),
      "/bodies/0/velocity: expected \"type\": \"dynamic\" for \"velocity\", found a static body");
  has(body_errors(R"({"type": "kinematic", "shape": "box"})"), "expected a \"path\" to follow for a \"kinematic\" body");
  has(body_errors(R"({"shape": "box", "density": 5, "mass": 2})"), "/bodies/0/mass: expected \"density\" or \"mass\", found both");
  has(body_errors(R"({"shape": "box", "material": {"texture": "nope.png"}})"), "/bodies/0/material/texture: expected an image file");
  {
    // A file that is not a decodable image is refused at its pointer when the scene loads (it
    // was a runtime failure, exit 1, once the renderer read it).
    const auto dir = std::filesystem::temp_directory_path() / ("simreel_body_tex_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "cut.png", std::ios::binary) << "\x89PNG\r\n\x1a\n\0\0\0\rIHDR";
    std::string err;
    try {
      (void)scene_from_json(json::parse(R"({"bodies": [{"shape": "box", "material": {"texture": "cut.png"}}]})"),
                            (dir / "s.json").string());
    } catch (const SceneError& e) {
      err = e.what();
    }
    EXPECT_NE(err.find("/bodies/0/material/texture: expected an image file (PNG, JPEG, ...), found \"cut.png\" "
                       "(cannot read image " + (dir / "cut.png").string() + ": "),
              std::string::npos)
        << err;
    std::filesystem::remove_all(dir);
  }
  has(body_errors(R"({"shape": "mesh", "mesh": "missing.obj"})"), "/bodies/0/mesh");
  has(errors_of(R"({"colliders": [{"type": "box", "name": "a"}], "bodies": [{"name": "a", "shape": "box"}]})"),
      "/bodies/0): expected a name not used by another collider");
}

TEST(SceneBodyList, TextureAMeshFileNamesMustBeAnImageWhenTheSceneLoads) {
  // An OBJ whose MTL named a missing or malformed texture passed the loader; the renderer then
  // stopped on it after the outputs were opened (exit 1, naming neither the scene nor the mesh).
  const auto dir = std::filesystem::temp_directory_path() / ("simreel_mesh_tex_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "sq.obj") << "mtllib sq.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n"
                                   "vt 0 1\nusemtl red\nf 1/1 2/2 3/3\nusemtl blue\nf 1/1 3/3 4/4\n";
  std::ofstream(dir / "sq.mtl") << "newmtl red\nKd 1 0 0\nnewmtl blue\nKd 0 0 1\nmap_Kd tex.png\n";
  const std::string scene = (dir / "s.json").string();
  const std::string collider = R"({"colliders": [{"type": "mesh", "name": "m", "file": "sq.obj"}]})";
  const std::string body = R"({"bodies": [{"type": "static", "shape": "mesh", "mesh": "sq.obj"}]})";
  const auto has = [](const std::string& err, const std::string& part) {
    EXPECT_NE(err.find(part), std::string::npos) << "expected \"" << part << "\" in: " << err;
  };
  // Missing.
  has(errors_of(collider, scene), "/colliders/0/file: sq.obj's material \"blue\" names the texture tex.png: "
                                  "expected an image file (PNG, JPEG, ...) (" + (dir / "tex.png").string() + " is not a file)");
  has(errors_of(body, scene), "/bodies/0/mesh: sq.obj's material \"blue\" names the texture tex.png");
  // Cut in its header.
  std::ofstream(dir / "tex.png", std::ios::binary) << "\x89PNG\r\n\x1a\n\0\0\0\rIHDR";
  has(errors_of(collider, scene), "/colliders/0/file: sq.obj's material \"blue\" names the texture tex.png: "
                                  "expected an image file (PNG, JPEG, ...) (cannot read image " + (dir / "tex.png").string());
  has(errors_of(body, scene), "/bodies/0/mesh: sq.obj's material \"blue\" names the texture tex.png");
  // A folder under the name.
  std::filesystem::remove(dir / "tex.png");
  std::filesystem::create_directory(dir / "tex.png");
  has(errors_of(collider, scene), "tex.png is not a file");
  // A real image: the scene loads, and the mesh keeps the texture for the renderer.
  std::filesystem::remove(dir / "tex.png");
  render::Image img(2, 2);
  std::fill(img.rgba.begin(), img.rgba.end(), std::uint8_t(200));
  render::write_png(dir / "tex.png", img);
  EXPECT_EQ(errors_of(collider, scene), "");
  EXPECT_EQ(errors_of(body, scene), "");
  // A file whose faces all use one material is drawn with that material's texture (assimp puts
  // its own default material first, so "the first material" had none and the image was dropped).
  std::ofstream(dir / "one.obj") << "mtllib sq.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n"
                                    "usemtl blue\nf 1/1 2/2 3/3\n";
  const Scene one = scene_from_json(json::parse(R"({"colliders": [{"type": "mesh", "name": "m", "file": "one.obj"}]})"), scene);
  ASSERT_EQ(one.colliders.size(), 1u);
  const render::MeshDesc desc = mesh_desc(one.colliders[0]);
  EXPECT_TRUE(desc.parts.empty());
  EXPECT_EQ(desc.material.texture_path, (dir / "tex.png").string());
  std::filesystem::remove_all(dir);
}
