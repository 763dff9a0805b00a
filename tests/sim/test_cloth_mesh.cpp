// A cloth from any triangle mesh (issue 16; Coutinho §3.9.2 with the springs taken from the
// mesh's edges and its pairs of adjacent triangles): the topology's spring families, bad meshes
// refused with the triangle named, and a square sheet triangulated differently from the grid
// hanging and draping like the grid cloth of the same size.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "simreel/sim/cloth.hpp"
#include "simreel/sim/world.hpp"

namespace {

using namespace simreel::sim;

constexpr double kFrame = 1.0 / 60.0;

/// A square sheet of nodes x nodes vertices, `size` wide, in the local xy plane with the grid's
/// vertex order (row 0 at +y), each cell split along the diagonal that alternates from cell to
/// cell (a pattern the grid generator never makes); alternate = false: the grid's own split.
ClothMesh square_sheet(std::size_t nodes, double size, bool alternate = true) {
  ClothMesh m;
  const double d = size / double(nodes - 1);
  for (std::size_t r = 0; r < nodes; ++r)
    for (std::size_t c = 0; c < nodes; ++c)
      m.vertices.emplace_back(-0.5 * size + double(c) * d, 0.5 * size - double(r) * d, 0.0);
  auto id = [nodes](std::size_t r, std::size_t c) { return std::uint32_t(r * nodes + c); };
  for (std::size_t r = 0; r + 1 < nodes; ++r)
    for (std::size_t c = 0; c + 1 < nodes; ++c) {
      const std::uint32_t a = id(r, c), b = id(r, c + 1), cc = id(r + 1, c), dd = id(r + 1, c + 1);
      if (alternate && (r + c) % 2 == 1) {
        m.triangles.insert(m.triangles.end(), {a, cc, b, b, cc, dd});
      } else {
        m.triangles.insert(m.triangles.end(), {a, cc, dd, a, dd, b});
      }
    }
  return m;
}

TEST(ClothMesh, SpringFamiliesFromEdgesAndTrianglePairs) {
  const std::size_t k = 5;
  const ClothTopology t(square_sheet(k, 1.0, false));
  std::size_t stretch = 0, shear = 0, bend = 0;
  for (const SpringKind s : t.kind)
    (s == SpringKind::stretch ? stretch : s == SpringKind::shear ? shear : bend)++;
  // The grid's triangles as a mesh. Edges: 2 k (k - 1) axis-aligned + one diagonal per cell;
  // shear: the other diagonal of each cell (across the cell's diagonal edge); bend: one spring
  // across every interior axis-aligned edge (a knight's move, √5 spacings, none repeated).
  const std::size_t cells = (k - 1) * (k - 1);
  EXPECT_EQ(stretch, 2 * k * (k - 1) + cells);
  EXPECT_EQ(shear, cells);
  EXPECT_EQ(bend, 2 * (k - 1) * (k - 2));
  EXPECT_EQ(t.limited_count, stretch + shear);
  EXPECT_TRUE(t.from_mesh);
  EXPECT_EQ(t.vertex_count(), k * k);
  EXPECT_EQ(t.edges.size() / 2, stretch);  // every edge is a stretch spring and a contact edge
  for (std::size_t s = 0; s < t.spring_count(); ++s) {
    if (t.kind[s] == SpringKind::bend) {
      EXPECT_NEAR(t.rest_length[s], std::sqrt(5.0) * 0.25, 1e-12);
    }
  }
}

TEST(ClothMesh, BadMeshesAreRefusedNamingTheTriangle) {
  ClothMesh m = square_sheet(3, 1.0);
  m.triangles[4] = 99;
  try {
    (void)ClothTopology(m);
    FAIL() << "accepted a vertex index out of range";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("triangle 1"), std::string::npos) << e.what();
  }
  m = square_sheet(3, 1.0);
  m.triangles[5] = m.triangles[4];
  EXPECT_THROW((void)ClothTopology(m), std::invalid_argument);
  ClothDef d;
  d.mesh = square_sheet(3, 1.0);
  d.pins = {{0, 9, {}}};  // 9 vertices: 0..8
  try {
    Cloth c(d);
    FAIL() << "accepted a pin beyond the mesh";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 9"), std::string::npos) << e.what();
  }
}

struct Shape {
  double min_z = 0.0, mean_z = 0.0, max_strain = 0.0;
};

/// Runs a 1 m, 0.2 kg, 17 x 17 sheet (grid or mesh) from flat at z = 1: pinned at two adjacent
/// corners, or free over a sphere of radius 0.3 m on the ground. Returns its shape after 4 s and
/// the largest stretch/shear strain after any frame.
Shape run_sheet(bool mesh, bool draped) {
  constexpr std::size_t kNodes = 17;
  World w(WorldDef{kFrame, 1, 0.05});
  ClothDef d;
  if (mesh) {
    d.mesh = square_sheet(kNodes, 1.0);
  } else {
    d.rows = d.columns = kNodes;
    d.width = d.height = 1.0;
  }
  d.mass = 0.2;
  // The drape (free fall onto the sphere, sliding, settling) amplifies the solver's residual:
  // at the default 1e-2 the mean drop moved by up to 2 % with the choice of preconditioner
  // (grid 0.5896 / 0.5913 m, mesh 0.5936 / 0.6092 m, block Jacobi / two-level). This test
  // compares the two discretisations, so it solves them closely (converged at 1e-5: grid
  // 0.5847 m, mesh 0.5963 m).
  d.cg_tolerance = 1e-4;
  d.transform.translation = Vec3(0, 0, 1.0);
  if (draped) {
    w.add_plane(PlaneDef{});
    SphereDef ball;
    ball.radius = 0.3;
    ball.transform.translation = Vec3(0, 0, 0.3);
    w.add_sphere(ball);
  } else {  // vertices (0, 0) and (0, 16): the same indices in both
    d.pins = {{0, 0, {}}, {0, kNodes - 1, {}}};
  }
  const ClothHandle h = w.add_cloth(d);
  Shape s;
  for (int f = 0; f < 240; ++f) {
    w.advance(kFrame);
    s.max_strain = std::max(s.max_strain, w.cloth_stats(h).max_strain);
  }
  const ClothView v = w.cloth(h);
  s.min_z = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < v.vertex_count; ++i) {
    s.min_z = std::min(s.min_z, double(v.positions[3 * i + 2]));
    s.mean_z += double(v.positions[3 * i + 2]) / double(v.vertex_count);
  }
  return s;
}

// The mesh sheet's cells are split along alternating diagonals, the grid's all along one, and
// its bend springs reach across an edge (√5 spacings) where the grid's skip a vertex (2
// spacings): the shapes must still agree within a few percent, both within the strain limit.
TEST(ClothMesh, SquareMeshHangsAndDrapesLikeTheGridCloth) {
  for (const bool draped : {false, true}) {
    const Shape g = run_sheet(false, draped), m = run_sheet(true, draped);
    SCOPED_TRACE(draped ? "draped over a sphere" : "hanging from two corners");
    EXPECT_LE(g.max_strain, 0.10 + 1e-9);
    EXPECT_LE(m.max_strain, 0.10 + 1e-9);
    const double drop_g = 1.0 - g.mean_z, drop_m = 1.0 - m.mean_z;  // sag of the mean height
    EXPECT_NEAR(drop_m, drop_g, 0.03 * drop_g) << "grid " << drop_g << " m, mesh " << drop_m << " m";
    const double low_g = 1.0 - g.min_z, low_m = 1.0 - m.min_z;
    // Hanging, the lowest point is where the strain limit holds the far corners; draped, it is
    // a corner's droop, which is set by the bend springs that differ: not compared there
    // (measured 0.86 m grid, 0.97 m mesh, the mesh's one bend spring per edge being softer).
    if (!draped) {
      EXPECT_NEAR(low_m, low_g, 0.03 * low_g) << "grid " << low_g << " m, mesh " << low_m << " m";
    }
    std::printf("%s: mean drop grid %.4f mesh %.4f, lowest grid %.4f mesh %.4f, strain %.4f %.4f\n",
                draped ? "draped" : "hanging", drop_g, drop_m, low_g, low_m, g.max_strain, m.max_strain);
  }
}

}  // namespace
