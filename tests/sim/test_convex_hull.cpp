// Convex hull by quickhull (Barber, Dobkin & Huhdanpaa 1996; Coutinho §2.2.4): cubes with interior,
// duplicate and coplanar points, points on a sphere, degenerate input, a large cloud, and the hull
// feeding mass_properties.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "rigid/convex_hull.hpp"
#include "rigid/mass_properties.hpp"
#include "simreel/sim/random.hpp"

namespace simreel::sim::detail {
namespace {

/// Every point behind (or within `slack` of) the plane of every triangle, the surface closed and
/// consistently oriented, the enclosed volume positive.
void expect_valid_hull(const ConvexHull& hull, const std::vector<Vec3>& points, double slack,
                       std::size_t point_stride = 1) {
  ASSERT_EQ(closed_oriented_error(hull.triangles), "");
  ASSERT_EQ(hull.vertices.size(), hull.input_index.size());
  for (std::size_t v = 0; v < hull.vertices.size(); ++v)
    ASSERT_EQ(hull.vertices[v], points[hull.input_index[v]]);
  double worst = -1.0;
  for (const auto& t : hull.triangles) {
    const Vec3& a = hull.vertices[t[0]];
    const Vec3 n = (hull.vertices[t[1]] - a).cross(hull.vertices[t[2]] - a).normalized();
    for (std::size_t i = 0; i < points.size(); i += point_stride)
      worst = std::max(worst, n.dot(points[i] - a));
  }
  EXPECT_LE(worst, slack) << "a point lies in front of a hull face";
  EXPECT_GT(mesh_mass(hull.vertices, hull.triangles, 1.0).volume, 0.0);
}

std::vector<Vec3> cube_corners(double h) {
  std::vector<Vec3> c;
  for (int i = 0; i < 8; ++i) c.emplace_back(i & 1 ? h : -h, i & 2 ? h : -h, i & 4 ? h : -h);
  return c;
}

/// Deterministic shuffle (Fisher–Yates with the project's generator).
void shuffle(std::vector<Vec3>& v, Rng& rng) {
  for (std::size_t i = v.size(); i > 1; --i)
    std::swap(v[i - 1], v[std::size_t(rng.uniform() * double(i)) % i]);
}

TEST(ConvexHull, CubeCornersPlusInteriorPointsIsTheCube) {
  Rng rng(7);
  std::vector<Vec3> points;
  for (int i = 0; i < 2000; ++i)
    points.emplace_back(rng.uniform(-0.999, 0.999), rng.uniform(-0.999, 0.999),
                        rng.uniform(-0.999, 0.999));
  for (const Vec3& c : cube_corners(1.0)) points.push_back(c);
  shuffle(points, rng);
  const ConvexHull hull = convex_hull(points);
  EXPECT_EQ(hull.vertices.size(), 8u);
  EXPECT_EQ(hull.triangles.size(), 12u);
  ASSERT_EQ(hull.faces.size(), 6u);
  for (const auto& f : hull.faces) EXPECT_EQ(f.size(), 4u);
  for (const Vec3& v : hull.vertices) EXPECT_EQ(v.cwiseAbs(), Vec3::Ones());
  expect_valid_hull(hull, points, 1e-12);
  EXPECT_NEAR(mesh_mass(hull.vertices, hull.triangles, 1.0).volume, 8.0, 8e-12);
}

TEST(ConvexHull, PointsOnASphereAreAllVertices) {
  Rng rng(11);
  std::vector<Vec3> points;
  for (int i = 0; i < 3000; ++i) {
    Vec3 g(rng.normal(), rng.normal(), rng.normal());
    points.push_back(g.normalized() * 2.0);
  }
  const ConvexHull hull = convex_hull(points);
  ASSERT_EQ(hull.vertices.size(), points.size());
  std::vector<std::uint32_t> all(points.size());
  std::iota(all.begin(), all.end(), 0u);
  EXPECT_EQ(hull.input_index, all);
  // Euler: V - E + F = 2 with E = 3F/2 for a closed triangle mesh.
  const auto v = std::int64_t(hull.vertices.size()), f = std::int64_t(hull.triangles.size());
  EXPECT_EQ(3 * f % 2, 0);
  EXPECT_EQ(v - 3 * f / 2 + f, 2);
  // No two triangles of a sphere are coplanar: every face is a triangle.
  EXPECT_EQ(hull.faces.size(), hull.triangles.size());
  expect_valid_hull(hull, points, hull.tolerance);
}

TEST(ConvexHull, DuplicatesAndCoplanarGridsOnEveryFace) {
  // A 7 x 7 grid on each face of the cube [-1, 1]³ (edges and corners shared, so repeated), every
  // point twice, plus interior points; offset far from the origin.
  const Vec3 offset(100.0, -50.0, 20.0);
  std::vector<Vec3> points;
  for (int axis = 0; axis < 3; ++axis)
    for (const double side : {-1.0, 1.0})
      for (int i = 0; i <= 6; ++i)
        for (int j = 0; j <= 6; ++j) {
          Vec3 q;
          q[axis] = side;
          q[(axis + 1) % 3] = -1.0 + i / 3.0;
          q[(axis + 2) % 3] = -1.0 + j / 3.0;
          points.push_back(q + offset);
          points.push_back(q + offset);
        }
  Rng rng(3);
  for (int i = 0; i < 200; ++i)
    points.push_back(offset + Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)));
  shuffle(points, rng);
  const ConvexHull hull = convex_hull(points);
  EXPECT_EQ(hull.vertices.size(), 8u);
  EXPECT_EQ(hull.triangles.size(), 12u);
  EXPECT_EQ(hull.faces.size(), 6u);
  expect_valid_hull(hull, points, 1e-9);
  EXPECT_NEAR(mesh_mass(hull.vertices, hull.triangles, 1.0).volume, 8.0, 1e-10);

  // Without merging: more vertices may remain (grid points the construction happened to pick),
  // but the surface is still closed, convex and of the same volume.
  const ConvexHull raw = convex_hull(points, {.merge_coplanar = false});
  EXPECT_TRUE(raw.faces.empty());
  EXPECT_GE(raw.vertices.size(), 8u);
  expect_valid_hull(raw, points, 1e-9);
  EXPECT_NEAR(mesh_mass(raw.vertices, raw.triangles, 1.0).volume, 8.0, 1e-10);
}

TEST(ConvexHull, LatticeAndCylinderMergeIntoTheirPlanarFaces) {
  // A full 11³ lattice: every point is on a face, an edge, or inside; only the corners remain.
  std::vector<Vec3> lattice;
  for (int i = 0; i <= 10; ++i)
    for (int j = 0; j <= 10; ++j)
      for (int k = 0; k <= 10; ++k) lattice.emplace_back(0.1 * i, 0.1 * j, 0.1 * k);
  const ConvexHull cube = convex_hull(lattice);
  EXPECT_EQ(cube.vertices.size(), 8u);
  EXPECT_EQ(cube.faces.size(), 6u);
  expect_valid_hull(cube, lattice, 1e-12);
  // A prism over a regular 64-gon with 5 rings (3 of them inside the side rectangles): 128
  // vertices; faces: 2 caps of 64 corners and 64 rectangles.
  std::vector<Vec3> prism;
  for (int i = 0; i < 64; ++i)
    for (int z = 0; z <= 4; ++z) {
      const double a = 2.0 * std::numbers::pi * i / 64.0;
      prism.emplace_back(std::cos(a), std::sin(a), -1.0 + 0.5 * z);
    }
  const ConvexHull hull = convex_hull(prism);
  EXPECT_EQ(hull.vertices.size(), 128u);
  ASSERT_EQ(hull.faces.size(), 66u);
  std::vector<std::size_t> sizes;
  for (const auto& f : hull.faces) sizes.push_back(f.size());
  EXPECT_EQ(std::count(sizes.begin(), sizes.end(), 64u), 2);
  EXPECT_EQ(std::count(sizes.begin(), sizes.end(), 4u), 64);
  expect_valid_hull(hull, prism, 1e-12);
  // Volume of the prism: area of the 64-gon (32 sin(2π/64)) times the height 2.
  EXPECT_NEAR(mesh_mass(hull.vertices, hull.triangles, 1.0).volume,
              2.0 * 32.0 * std::sin(2.0 * std::numbers::pi / 64.0), 1e-12);
}

TEST(ConvexHull, DegenerateInputIsRejected) {
  const auto message_of = [](const std::vector<Vec3>& p) {
    try {
      convex_hull(p);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_NE(message_of({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}).find("at least 4"),
            std::string::npos);
  EXPECT_NE(message_of(std::vector<Vec3>(10, Vec3(1, 2, 3))).find("coincide"), std::string::npos);
  std::vector<Vec3> line, plane;
  for (int i = 0; i < 20; ++i) line.push_back(Vec3(1, 2, 3) * (0.1 * i) + Vec3(5, 0, 0));
  EXPECT_NE(message_of(line).find("collinear"), std::string::npos) << message_of(line);
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) plane.emplace_back(i, j, 0.5 * i - 0.25 * j);
  EXPECT_NE(message_of(plane).find("coplanar"), std::string::npos) << message_of(plane);
  std::vector<Vec3> bad = cube_corners(1.0);
  bad[3].x() = NAN;
  EXPECT_NE(message_of(bad).find("not finite"), std::string::npos);
}

TEST(ConvexHull, HundredThousandRandomPoints) {
  Rng rng(2024);
  std::vector<Vec3> points;
  points.reserve(100000);
  for (int i = 0; i < 100000; ++i)
    points.emplace_back(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
  const auto start = std::chrono::steady_clock::now();
  const ConvexHull hull = convex_hull(points);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("convex hull of %zu random points: %zu vertices, %zu triangles in %.3f s\n",
              points.size(), hull.vertices.size(), hull.triangles.size(), seconds);
  expect_valid_hull(hull, points, 1e-9, 7);
  const double volume = mesh_mass(hull.vertices, hull.triangles, 1.0).volume;
  EXPECT_LT(volume, 8.0);
  EXPECT_GT(volume, 7.8);  // the hull of 1e5 uniform points fills nearly all of the cube
}

TEST(ConvexHull, HullOfACubeHasTheBoxMassProperties) {
  Rng rng(5);
  const Mat3 r = Eigen::AngleAxisd(0.6, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Vec3 h(0.5, 1.0, 0.25), t(2.0, 0.0, -1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 8; ++i)
    points.push_back(
        r * Vec3(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z()) + t);
  for (int i = 0; i < 500; ++i)
    points.push_back(r * Vec3(rng.uniform(-h.x(), h.x()), rng.uniform(-h.y(), h.y()),
                              rng.uniform(-h.z(), h.z())) +
                     t);
  const ConvexHull hull = convex_hull(points);
  EXPECT_EQ(hull.vertices.size(), 8u);
  const MassProperties got = mesh_mass(hull.vertices, hull.triangles, 400.0);
  const MassProperties want = transformed(box_mass(h, 400.0), r, t);
  EXPECT_NEAR(got.mass, want.mass, 1e-12 * want.mass);
  EXPECT_LE((got.center_of_mass - want.center_of_mass).norm(), 1e-12);
  EXPECT_LE((got.inertia - want.inertia).cwiseAbs().maxCoeff(),
            1e-12 * want.inertia.cwiseAbs().maxCoeff());
}

}  // namespace
}  // namespace simreel::sim::detail
