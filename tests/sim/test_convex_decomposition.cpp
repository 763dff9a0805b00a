// Convex decomposition of closed meshes (Coutinho App. F) and concave dynamic bodies built from it:
// the pieces fill the solid exactly for polyhedra (volume and inertia of the compound equal the
// mesh's, App. D), a torus keeps its hole, a convex mesh stays one piece, and a ring dropped over
// a peg threads onto it (which one convex hull of the ring cannot do).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <set>
#include <tuple>
#include <vector>

#include "rigid/convex_hull.hpp"
#include "rigid/mass_properties.hpp"
#include "rigid_test_meshes.hpp"
#include "simreel/sim/convex_decomposition.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

using test::Mesh;
constexpr double kPi = std::numbers::pi;

/// The closed surface of a union of unit voxels (edge `a` m) on a grid: every face between a
/// filled and an empty cell, two outward triangles each, corners shared by grid position.
Mesh voxel_mesh(const std::set<std::array<int, 3>>& cells, double a = 1.0) {
  Mesh m;
  std::map<std::array<int, 3>, std::uint32_t> corner;
  const auto id = [&](std::array<int, 3> c) {
    const auto [it, fresh] = corner.emplace(c, std::uint32_t(m.vertices.size()));
    if (fresh) m.vertices.emplace_back(a * c[0], a * c[1], a * c[2]);
    return it->second;
  };
  for (const auto& c : cells)
    for (int axis = 0; axis < 3; ++axis)
      for (int dir : {-1, 1}) {
        std::array<int, 3> nb = c;
        nb[std::size_t(axis)] += dir;
        if (cells.count(nb)) continue;
        // The face's corners, counter-clockwise seen along +axis·dir.
        const int u = (axis + 1) % 3, w = (axis + 2) % 3;
        std::array<int, 3> base = c;
        if (dir > 0) base[std::size_t(axis)] += 1;
        std::array<std::array<int, 3>, 4> q{base, base, base, base};
        q[1][std::size_t(u)] += 1;
        q[2][std::size_t(u)] += 1;
        q[2][std::size_t(w)] += 1;
        q[3][std::size_t(w)] += 1;
        std::array<std::uint32_t, 4> i{id(q[0]), id(q[1]), id(q[2]), id(q[3])};
        if (dir > 0) {
          m.triangles.push_back({i[0], i[1], i[2]});
          m.triangles.push_back({i[0], i[2], i[3]});
        } else {
          m.triangles.push_back({i[0], i[2], i[1]});
          m.triangles.push_back({i[0], i[3], i[2]});
        }
      }
  return m;
}

/// A torus about z: tube of radius r around a circle of radius R, n × k quads.
Mesh torus_mesh(double R, double r, int n, int k) {
  Mesh m;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < k; ++j) {
      const double u = 2 * kPi * i / n, v = 2 * kPi * j / k;
      m.vertices.emplace_back((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u),
                              r * std::sin(v));
    }
  const auto at = [&](int i, int j) { return std::uint32_t((i % n) * k + (j % k)); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < k; ++j) {
      m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return m;
}

/// Volume and inertia about the origin of the compound of the pieces' hulls (App. D on each).
detail::MassProperties compound(const std::vector<ConvexPiece>& pieces) {
  std::vector<detail::MassPart> parts;
  for (const ConvexPiece& p : pieces) {
    const detail::ConvexHull h = detail::convex_hull(p);
    detail::MassPart part;
    part.props = detail::mesh_mass(h.vertices, h.triangles, 1.0);
    parts.push_back(part);
  }
  return detail::combine(parts);
}

bool inside_hull(const ConvexPiece& piece, const Vec3& x) {
  const detail::ConvexHull h = detail::convex_hull(piece);
  for (const auto& t : h.triangles) {
    const Vec3 n = (h.vertices[t[1]] - h.vertices[t[0]]).cross(h.vertices[t[2]] - h.vertices[t[0]]);
    if (n.dot(x - h.vertices[t[0]]) > 0.0) return false;
  }
  return true;
}

TEST(ConvexDecomposition, ALShapedBlockSplitsIntoTwoBoxesWithTheMeshsMassProperties) {
  const Mesh m = voxel_mesh({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}, {0, 2, 0}});
  const std::vector<ConvexPiece> pieces = convex_decomposition(m.vertices, m.triangles);
  EXPECT_EQ(pieces.size(), 2u);
  const detail::MassProperties exact = detail::mesh_mass(m.vertices, m.triangles, 1.0);
  const detail::MassProperties got = compound(pieces);
  EXPECT_NEAR(got.volume, 5.0, 1e-9);
  EXPECT_NEAR(exact.volume, 5.0, 1e-9);
  EXPECT_LT((got.center_of_mass - exact.center_of_mass).norm(), 1e-9);
  EXPECT_LT((got.inertia - exact.inertia).norm(), 1e-9 * exact.inertia.norm());
}

TEST(ConvexDecomposition, ACupKeepsItsHollowAndItsVolume) {
  // A 3 × 3 × 2 block with the middle of its top layer taken out.
  std::set<std::array<int, 3>> cells;
  for (int x = 0; x < 3; ++x)
    for (int y = 0; y < 3; ++y)
      for (int z = 0; z < 2; ++z)
        if (!(z == 1 && x == 1 && y == 1)) cells.insert({x, y, z});
  const Mesh m = voxel_mesh(cells, 0.1);
  const std::vector<ConvexPiece> pieces = convex_decomposition(m.vertices, m.triangles);
  EXPECT_GE(pieces.size(), 3u);
  EXPECT_LE(pieces.size(), 8u);
  const detail::MassProperties exact = detail::mesh_mass(m.vertices, m.triangles, 1.0);
  const detail::MassProperties got = compound(pieces);
  EXPECT_NEAR(got.volume, 17e-3, 1e-12);
  EXPECT_LT((got.center_of_mass - exact.center_of_mass).norm(), 1e-9);
  EXPECT_LT((got.inertia - exact.inertia).norm(), 1e-9 * exact.inertia.norm());
  for (const ConvexPiece& p : pieces)  // the hollow stays empty
    EXPECT_FALSE(inside_hull(p, Vec3(0.15, 0.15, 0.17)));
}

TEST(ConvexDecomposition, AConvexMeshIsOnePieceWithItsOwnVertices) {
  const Mesh m = test::icosphere(3, 0.5);
  const std::vector<ConvexPiece> pieces = convex_decomposition(m.vertices, m.triangles);
  ASSERT_EQ(pieces.size(), 1u);
  EXPECT_EQ(pieces[0], m.vertices);
}

TEST(ConvexDecomposition, ATorusMeshHasItsClosedFormMassPropertiesAndItsPiecesKeepTheHole) {
  const double R = 1.0, r = 0.25;
  const Mesh m = torus_mesh(R, r, 128, 64);
  // Closed forms (a solid torus of density 1): V = 2π² R r², I_z = m (R² + 3/4 r²),
  // I_x = m (R²/2 + 5/8 r²). The test: within 0.5% for tessellated round shapes.
  const detail::MassProperties mp = detail::mesh_mass(m.vertices, m.triangles, 1.0);
  const double V = 2 * kPi * kPi * R * r * r;
  EXPECT_NEAR(mp.volume, V, 0.005 * V);
  EXPECT_NEAR(mp.inertia(2, 2), V * (R * R + 0.75 * r * r), 0.005 * V * (R * R + 0.75 * r * r));
  EXPECT_NEAR(mp.inertia(0, 0), V * (0.5 * R * R + 0.625 * r * r), 0.005 * V * (0.5 * R * R + 0.625 * r * r));
  EXPECT_LT(mp.center_of_mass.norm(), 1e-12);

  const Mesh coarse = torus_mesh(R, r, 24, 12);
  const std::vector<ConvexPiece> pieces = convex_decomposition(coarse.vertices, coarse.triangles);
  EXPECT_GE(pieces.size(), 4u);
  EXPECT_LE(pieces.size(), 32u);
  const double mesh_volume = detail::mesh_mass(coarse.vertices, coarse.triangles, 1.0).volume;
  // Each piece's hull over-fills at most its share of the allowed concavity (1% of 2.5 m).
  EXPECT_NEAR(compound(pieces).volume, mesh_volume, 0.05 * mesh_volume);
  for (const ConvexPiece& p : pieces) {
    EXPECT_FALSE(inside_hull(p, Vec3::Zero()));
    EXPECT_FALSE(inside_hull(p, Vec3(0.5, 0.0, 0.0)));
  }
}

TEST(ConvexDecomposition, RejectsAnOpenMesh) {
  Mesh m = test::icosphere(1, 0.5);
  m.triangles.pop_back();
  EXPECT_THROW(convex_decomposition(m.vertices, m.triangles), std::invalid_argument);
}

/// A ring (tube radius 6 cm around a 22 cm circle: a 16 cm hole) dropped over a 4 cm peg 0.5 m
/// tall, after 2 s: its centre (m).
Vec3 ring_after_drop(bool decomposed) {
  WorldDef d;
  d.max_step = 1.0 / 240.0;
  d.threads = 1;
  World w(d);
  BodyDef ground;
  ground.shapes.push_back(ShapeDef::plane());
  w.add_body(ground);
  BodyDef peg;
  peg.pose.translation = {0.0, 0.0, 0.25};
  peg.shapes.push_back(ShapeDef::cylinder(0.02, 0.25));
  w.add_body(peg);
  const Mesh ring = torus_mesh(0.22, 0.06, 24, 10);
  BodyDef b;
  b.type = BodyType::dynamic;
  b.pose.translation = {0.01, 0.0, 0.7};
  if (decomposed) {
    for (ConvexPiece& p : convex_decomposition(ring.vertices, ring.triangles))
      b.shapes.push_back(ShapeDef::convex_hull(std::move(p)));
  } else {
    b.shapes.push_back(ShapeDef::convex_hull(ring.vertices));
  }
  for (ShapeDef& s : b.shapes) s.density = 500.0;
  const BodyHandle h = w.add_body(b);
  for (int i = 0; i < 60; ++i) w.advance(1.0 / 30.0);
  return w.pose(h).translation;
}

TEST(ConvexDecomposition, ARingOfConvexPiecesThreadsOntoAPegWhereItsHullWouldNot) {
  // Threaded: down on the ground (tube radius 6 cm) with the peg through the hole.
  const auto threaded = [](const Vec3& c) { return c.z() < 0.1 && std::hypot(c.x(), c.y()) < 0.14; };
  const Vec3 ring = ring_after_drop(true), hull = ring_after_drop(false);
  EXPECT_TRUE(threaded(ring)) << ring.transpose();
  EXPECT_FALSE(threaded(hull)) << hull.transpose();  // the hull is a disc: the peg cannot enter
}

}  // namespace
}  // namespace simreel::sim
