// A cloth from a mesh file (README "cloths[i]", issue 16): "mesh" read relative to the scene,
// vertices welded across the file's seams, pins by vertex index or selection box, mass from the
// areal density and the mesh's area, and bad input named by file and pointer (exit 2).
#include <gtest/gtest.h>

#include <string>

#include "cli_util.hpp"
#include "json_reader.hpp"
#include "scene.hpp"

using simreel::app::load_scene;
using simreel::test::run_simreel;
using simreel::test::TempDir;
using simreel::test::write_file;
namespace sim = simreel::sim;

namespace {

/// A 2 m x 1 m flag as an OBJ: 3 x 2 vertices, 4 triangles, its left edge at x = 0, written
/// with a UV seam (the middle column twice with other UVs) that the loader must weld.
const char* kFlagObj =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 1 0 0\nv 2 0 0\nv 1 1 0\nv 2 1 0\n"
    "vt 0 0\nvt 0.5 0\nvt 0 1\nvt 0.5 1\nvt 0.6 0\nvt 1 0\nvt 0.6 1\nvt 1 1\n"
    "f 1/1 2/2 4/4\nf 1/1 4/4 3/3\nf 5/5 6/6 8/8\nf 5/5 8/8 7/7\n";

/// A 1 m x 1 m flag in two OBJ groups: "hoist", the 10 cm strip at x <= 0.1, and "fly", the rest.
const char* kGroupedFlagObj =
    "v 0 0 0\nv 0.1 0 0\nv 1 0 0\nv 0 1 0\nv 0.1 1 0\nv 1 1 0\n"
    "g hoist\nf 1 2 5\nf 1 5 4\ng fly\nf 2 3 6\nf 2 6 5\n";

}  // namespace

// Pins by group name (issue 16): every vertex of the named OBJ group's faces is pinned, once,
// and the others are free: the flag, lying level, keeps its hoist strip where it was and its fly
// end swings down about it. A name the file lacks is refused naming the groups it has.
TEST(SceneClothMesh, PinsByGroupNameHoldThatGroupsVertices) {
  TempDir d;
  write_file(d / "flag.obj", kGroupedFlagObj);
  write_file(d / "s.json", R"({"cloths":[{"mesh":"flag.obj","scale":2,"position":[0,0,2],
      "pins":[{"group":"hoist"}]}]})");
  const auto s = load_scene(d / "s.json");
  const sim::ClothDef& c = s.cloths.at(0).def;
  ASSERT_EQ(c.mesh.vertices.size(), 6u);
  ASSERT_EQ(c.pins.size(), 4u);  // x = 0 and x = 0.1 (m in the file), top and bottom
  for (const auto& p : c.pins) EXPECT_LE(c.mesh.vertices[p.column].x(), 0.2 + 1e-6);  // after scale 2
  auto sw = simreel::app::build_world(s);
  for (int f = 0; f < 30; ++f) sw.world.advance(1.0 / 30);
  const sim::ClothView v = sw.world.cloth(sw.cloths.at(0));
  for (const auto& p : c.pins) EXPECT_EQ(v.positions[3 * p.column + 2], 2.0f);  // where they were
  std::size_t corner = 0;  // the fly end's bottom corner, (2, 0) m in the cloth's frame
  for (std::size_t k = 0; k < 6; ++k)
    if (c.mesh.vertices[k].x() == 2.0 && c.mesh.vertices[k].y() == 0.0) corner = k;
  EXPECT_LT(v.positions[3 * corner + 2], 1.0f);  // it swung down (it started at z = 2)

  write_file(d / "bad.json", R"({"cloths":[{"mesh":"flag.obj","pins":[{"group":"top"}]}]})");
  const auto r = run_simreel("validate " + (d / "bad.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find((d / "bad.json").string() +
                       ": /cloths/0/pins/0/group: expected a group of flag.obj (it has \"hoist\", \"fly\"), found \"top\""),
            std::string::npos) << r.err;
}

TEST(SceneClothMesh, MeshFileWeldedPinnedByBoxAndWeighedByArea) {
  TempDir d;
  write_file(d / "flag.obj", kFlagObj);
  write_file(d / "s.json", R"({"cloths":[{"mesh":"flag.obj","scale":0.5,"areal_density":0.2,
      "pins":[{"box_min":[-0.01,-0.01,-0.01],"box_max":[0.01,0.51,0.01]},{"vertex":3}]}]})");
  const auto s = load_scene(d / "s.json");
  const sim::ClothDef& c = s.cloths.at(0).def;
  ASSERT_EQ(c.mesh.vertices.size(), 6u);  // the seam's two copies of x = 1 welded
  EXPECT_EQ(c.mesh.triangles.size(), 12u);
  EXPECT_EQ(c.rows, 1u);
  EXPECT_EQ(c.columns, 6u);
  EXPECT_NEAR(c.mass, 0.2 * 1.0 * 0.5, 1e-12);  // 1 m x 0.5 m after the scale
  ASSERT_EQ(c.pins.size(), 3u);                 // the two left-edge vertices, then vertex 3
  for (std::size_t k = 0; k < 2; ++k) EXPECT_EQ(c.mesh.vertices[c.pins[k].column].x(), 0.0);
  EXPECT_EQ(c.pins[2].column, 3u);
  auto sw = simreel::app::build_world(s);
  for (int f = 0; f < 30; ++f) sw.world.advance(1.0 / 30);
  const sim::ClothView v = sw.world.cloth(sw.cloths.at(0));
  EXPECT_EQ(v.vertex_count, 6u);
  EXPECT_LT(v.positions[3 * 5 + 2], 0.9f);  // the free tip fell (the cloth sits at z = 1)
}

TEST(SceneClothMesh, BadMeshInputNamesFileAndPointer) {
  TempDir d;
  write_file(d / "flag.obj", kFlagObj);
  struct Case {
    std::string json, expect;
  };
  const Case cases[] = {
      {R"({"cloths":[{"mesh":"missing.obj"}]})", "/cloths/0/mesh: "},
      {R"({"cloths":[{"mesh":"flag.obj","rows":4}]})", "/cloths/0/rows: expected either \"mesh\" or \"rows\""},
      {R"({"cloths":[{"mesh":"flag.obj","pins":[{"vertex":6}]}]})", "/cloths/0/pins/0/vertex: expected an integer in [0, 5], found 6"},
      {R"({"cloths":[{"mesh":"flag.obj","pins":[{"box_min":[5,5,5],"box_max":[6,6,6]}]}]})",
       "/cloths/0/pins/0: expected the box to hold some vertex of the mesh, found none"},
      {R"({"cloths":[{"mesh":"flag.obj","pins":"top_edge"}]})", "/cloths/0/pins: expected for a mesh cloth"},
  };
  for (const Case& c : cases) {
    write_file(d / "s.json", c.json);
    const auto r = run_simreel("validate " + (d / "s.json").string());
    EXPECT_EQ(r.code, 2) << c.json;
    EXPECT_NE(r.err.find((d / "s.json").string() + ": " + c.expect), std::string::npos) << c.json << "\n" << r.err;
  }
}
