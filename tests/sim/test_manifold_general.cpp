// Contact manifolds of general convex pairs (collide_manifold) and warm starting (warm_start)
// against closed forms: a cube hull against a box gives the box–box manifold; a capsule lying on
// a box gives its two segment ends; side-by-side capsules the ends of their overlap; a sphere on
// a box one point; a cylinder standing on a box four rim points, lying on it two; a box sliding
// 1 mm keeps its feature ids and its impulses; vanished points drop theirs.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "collision/box_box.hpp"
#include "collision/bvh.hpp"
#include "collision/collider_impl.hpp"
#include "collision/contact_manifold.hpp"
#include "collision/convex_contact.hpp"
#include "collision/persistent_manifold.hpp"
#include "core/body_dynamics.hpp"
#include "rigid/convex_hull.hpp"
#include "simreel/sim/random.hpp"

namespace simreel::sim::detail {
namespace {

constexpr double kTol = 1e-9;

Mat3 rot(const Vec3& axis, double angle) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

/// Order-free comparison of two manifolds' point pairs, normals and separations (tol m).
bool same_manifold(const Manifold& a, const Manifold& b, double tol) {
  if (a.count != b.count || (a.normal - b.normal).norm() > tol) return false;
  for (int i = 0; i < a.count; ++i) {
    bool found = false;
    for (int j = 0; j < b.count && !found; ++j) {
      found = (a.points[i].point_a - b.points[j].point_a).norm() <= tol &&
              (a.points[i].point_b - b.points[j].point_b).norm() <= tol &&
              std::abs(a.points[i].separation - b.points[j].separation) <= tol;
    }
    if (!found) return false;
  }
  return true;
}

bool has_point(const Manifold& m, const Vec3& p, bool on_b, double tol) {
  for (int i = 0; i < m.count; ++i)
    if (((on_b ? m.points[i].point_b : m.points[i].point_a) - p).norm() <= tol) return true;
  return false;
}

/// The hull of a cube of half extents h, with its faces.
struct CubeHull {
  ConvexHull hull;
  HullFaces faces;
  explicit CubeHull(const Vec3& h) {
    std::vector<Vec3> corners;
    for (int i = 0; i < 8; ++i)
      corners.push_back({i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z()});
    hull = convex_hull(corners);
    faces = make_hull_faces(hull.vertices, hull.faces);
  }
  [[nodiscard]] ConvexShape shape() const { return ConvexShape::hull(hull.vertices); }
};

TEST(ManifoldHull, CubeHullGivesTheBoxBoxManifold) {
  const Vec3 h(0.5, 0.3, 0.25);
  const CubeHull cube(h);
  ASSERT_EQ(cube.faces.face_count(), 6);
  const ConvexShape big = ConvexShape::box({2.0, 1.5, 0.5});
  struct Pose {
    Mat3 R;
    Vec3 c;
  };
  const std::vector<Pose> poses{
      {rot(Vec3::UnitZ(), 0.4), {0.2, -0.1, 0.749}},                            // flat: 4 points
      {rot(Vec3::UnitZ(), 0.4), {1.9, 1.4, 0.745}},                             // overhanging a corner
      {rot(Vec3::UnitX(), 0.5), {0.1, 0.2, 0.5 + 0.3 * std::sin(0.5) + 0.25 * std::cos(0.5) - 1e-3}},
  };
  for (const Pose& p : poses) {
    const PosedShape base(big, Mat3::Identity(), Vec3::Zero());
    const PosedShape as_box(ConvexShape::box(h), p.R, p.c);
    const PosedShape as_hull(cube.shape(), p.R, p.c);
    const Manifold ref = collide_boxes(base, as_box);
    ASSERT_GE(ref.count, 1);
    EXPECT_TRUE(same_manifold(collide_manifold(base, as_hull, {}, nullptr, &cube.faces), ref, kTol));
    EXPECT_TRUE(same_manifold(collide_manifold(as_hull, base, {}, &cube.faces, nullptr),
                              collide_boxes(as_box, base), kTol));
  }
}

TEST(ManifoldHull, NearTieOfFacesGoesToAAsInBoxBox) {
  // A cube tilted by 1e-4 rad on a big box: B's face separates better by less than the bias,
  // so A's tilted face is the reference (normal = minus its z axis), as collide_boxes decides.
  const CubeHull cube({0.3, 0.3, 0.3});
  const Mat3 tilt = rot(Vec3::UnitX(), 1e-4);
  const PosedShape hull(cube.shape(), tilt, {0, 0, 0.799});
  const PosedShape box(ConvexShape::box({0.3, 0.3, 0.3}), tilt, {0, 0, 0.799});
  const PosedShape big(ConvexShape::box({2, 2, 0.5}), Mat3::Identity(), Vec3::Zero());
  const Manifold m = collide_manifold(hull, big, {}, &cube.faces, nullptr);
  ASSERT_EQ(m.count, 4);
  EXPECT_NEAR((m.normal + tilt.col(2)).norm(), 0.0, 1e-12);
  EXPECT_TRUE(same_manifold(m, collide_boxes(box, big), kTol));
}

TEST(ManifoldHull, CrossingEdgesGiveOnePoint) {
  // Cube hull A turned 45° about x (top edge along x), box B turned 45° about y and yawed: the
  // edges cross 1 cm deep. No face is the contact plane, so the one point of GJK/EPA, which is
  // the box–box edge–edge answer.
  const double h = 0.5, s2 = std::sqrt(2.0);
  const CubeHull cube({h, h, h});
  const Mat3 Ra = rot(Vec3::UnitX(), std::numbers::pi / 4);
  const Mat3 Rb = rot(Vec3::UnitZ(), 0.6) * rot(Vec3::UnitY(), std::numbers::pi / 4);
  const Vec3 ca(0.05, 0.1, 0.0), cb(0.15, -0.05, 2 * h * s2 - 0.01);
  const Manifold m = collide_manifold(PosedShape(cube.shape(), Ra, ca),
                                      PosedShape(ConvexShape::box({h, h, h}), Rb, cb), {},
                                      &cube.faces, nullptr);
  const Manifold e = collide_boxes(PosedShape(ConvexShape::box({h, h, h}), Ra, ca),
                                   PosedShape(ConvexShape::box({h, h, h}), Rb, cb));
  ASSERT_EQ(m.count, 1);
  ASSERT_EQ(e.count, 1);
  EXPECT_TRUE(same_manifold(m, e, 1e-8));
}

TEST(ManifoldCapsule, LyingOnABoxGivesTwoPointsAtTheSegmentEnds) {
  const double hh = 0.4, r = 0.1;
  for (const double yaw : {0.0, 0.7, 2.0}) {
    for (const double gap : {-0.002, 0.0}) {
      // Axis along x turned by yaw; its core sits r + gap above the box's top face z = 0.5.
      const Mat3 R = rot(Vec3::UnitZ(), yaw) * rot(Vec3::UnitY(), std::numbers::pi / 2);
      const Vec3 c(0.2, 0.1, 0.5 + r + gap);
      const PosedShape box(ConvexShape::box({1, 1, 0.5}), Mat3::Identity(), Vec3::Zero());
      const PosedShape cap(ConvexShape::capsule(hh, r), R, c);
      const Manifold m = collide_manifold(box, cap);
      ASSERT_EQ(m.count, 2) << "yaw " << yaw;
      EXPECT_NEAR((m.normal - Vec3::UnitZ()).norm(), 0.0, 1e-12);
      const Vec3 u = R.col(2);
      for (const double s : {-1.0, 1.0}) {
        const Vec3 end = c + s * hh * u;
        EXPECT_TRUE(has_point(m, end - Vec3(0, 0, r), true, kTol));
        EXPECT_TRUE(has_point(m, Vec3(end.x(), end.y(), 0.5), false, kTol));
      }
      for (int i = 0; i < 2; ++i) EXPECT_NEAR(m.points[i].separation, gap, kTol);
      // Swapped: same points, normal flipped.
      const Manifold s = collide_manifold(cap, box);
      ASSERT_EQ(s.count, 2);
      EXPECT_NEAR((s.normal + Vec3::UnitZ()).norm(), 0.0, 1e-12);
      for (int i = 0; i < 2; ++i) EXPECT_TRUE(has_point(s, m.points[i].point_b, false, kTol));
    }
  }
}

TEST(ManifoldCapsule, SideBySideCapsulesGiveTheEndsOfTheirOverlap) {
  // Both axes along x: A over [-0.5, 0.5] at y = 0, B over [-0.2, 0.8] at y = 0.25 (radii 0.1
  // and 0.15: penetration 0): points at x = -0.2 and x = 0.5.
  const Mat3 along_x = rot(Vec3::UnitY(), std::numbers::pi / 2);
  const double gap = -0.01;
  const PosedShape A(ConvexShape::capsule(0.5, 0.1), along_x, Vec3::Zero());
  const PosedShape B(ConvexShape::capsule(0.5, 0.15), along_x, {0.3, 0.25 + gap, 0.0});
  const Manifold m = collide_manifold(A, B);
  ASSERT_EQ(m.count, 2);
  EXPECT_NEAR((m.normal - Vec3::UnitY()).norm(), 0.0, 1e-9);
  EXPECT_TRUE(has_point(m, {-0.2, 0.1, 0.0}, false, kTol));
  EXPECT_TRUE(has_point(m, {0.5, 0.1, 0.0}, false, kTol));
  EXPECT_TRUE(has_point(m, {-0.2, 0.1 + gap, 0.0}, true, kTol));
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(m.points[i].separation, gap, kTol);
  EXPECT_FALSE(m.points[0].id == m.points[1].id);
  // Crossing capsules: one point.
  const PosedShape C(ConvexShape::capsule(0.5, 0.15), rot(Vec3::UnitX(), std::numbers::pi / 2),
                     {0.3, 0.0, 0.24});
  EXPECT_EQ(collide_manifold(A, C).count, 1);
}

TEST(ManifoldSphere, OnABoxGivesOnePoint) {
  const double r = 0.3, gap = -0.004;
  const PosedShape box(ConvexShape::box({1, 1, 0.5}), rot(Vec3::UnitZ(), 0.3), Vec3::Zero());
  const PosedShape ball(ConvexShape::sphere(r), Mat3::Identity(), {0.1, 0.2, 0.5 + r + gap});
  const Manifold m = collide_manifold(box, ball);
  ASSERT_EQ(m.count, 1);
  EXPECT_NEAR((m.points[0].point_a - Vec3(0.1, 0.2, 0.5)).norm(), 0.0, kTol);
  EXPECT_NEAR((m.points[0].point_b - Vec3(0.1, 0.2, 0.5 + gap)).norm(), 0.0, kTol);
  EXPECT_NEAR(m.points[0].separation, gap, kTol);
  EXPECT_NEAR((m.normal - Vec3::UnitZ()).norm(), 0.0, 1e-12);
}

TEST(ManifoldCylinder, StandingGivesFourRimPointsLyingGivesTwo) {
  const double r = 0.3, hh = 0.4, gap = -0.001, yaw = 0.5;
  const PosedShape box(ConvexShape::box({1, 1, 0.5}), Mat3::Identity(), Vec3::Zero());
  const Mat3 R = rot(Vec3::UnitZ(), yaw);
  const Vec3 c(0.1, 0.2, 0.5 + hh + gap);
  const Manifold m = collide_manifold(box, PosedShape(ConvexShape::cylinder(r, hh), R, c));
  ASSERT_EQ(m.count, 4);
  for (int k = 0; k < 4; ++k) {
    const double a = yaw + k * std::numbers::pi / 2;
    EXPECT_TRUE(has_point(m, c + Vec3(r * std::cos(a), r * std::sin(a), -hh), true, kTol));
    EXPECT_NEAR(m.points[k].separation, gap, kTol);
  }
  // On its side, axis along y: the lowest side line, from rim to rim.
  const Mat3 side = rot(Vec3::UnitX(), std::numbers::pi / 2);
  const Vec3 cs(0.1, 0.2, 0.5 + r + gap);
  const Manifold s = collide_manifold(box, PosedShape(ConvexShape::cylinder(r, hh), side, cs));
  ASSERT_EQ(s.count, 2);
  EXPECT_TRUE(has_point(s, cs + Vec3(0, hh, -r), true, 1e-6));
  EXPECT_TRUE(has_point(s, cs + Vec3(0, -hh, -r), true, 1e-6));
  // Tilted by 0.3 rad: the rim touches at one point.
  const Manifold t = collide_manifold(
      box, PosedShape(ConvexShape::cylinder(r, hh), rot(Vec3::UnitX(), 0.3),
                      {0.1, 0.2, 0.5 + hh * std::cos(0.3) + r * std::sin(0.3) + gap}));
  EXPECT_EQ(t.count, 1);
}

TEST(ManifoldDeterminism, SameInputSameOrder) {
  const CubeHull cube({0.5, 0.5, 0.5});
  const PosedShape base(ConvexShape::box({1, 1, 0.5}), Mat3::Identity(), Vec3::Zero());
  const PosedShape top(cube.shape(), rot(Vec3::UnitZ(), 0.6), {0.8, 0.7, 0.998});
  const Manifold a = collide_manifold(base, top, {}, nullptr, &cube.faces);
  const Manifold b = collide_manifold(base, top, {}, nullptr, &cube.faces);
  ASSERT_GT(a.count, 1);
  ASSERT_EQ(a.count, b.count);
  for (int i = 0; i < a.count; ++i) {
    EXPECT_EQ(a.points[i].point_b, b.points[i].point_b);
    EXPECT_EQ(a.points[i].id, b.points[i].id);
  }
}

/// A box resting flat (penetrating 1 mm) on a big box, slid by dx along x.
Manifold resting(double dx, double lift_one_side = 0.0) {
  const PosedShape base(ConvexShape::box({2, 2, 0.5}), Mat3::Identity(), Vec3::Zero());
  const PosedShape top(ConvexShape::box({0.5, 0.3, 0.25}), rot(Vec3::UnitY(), lift_one_side),
                       {0.1 + dx, 0.2, 0.749});
  return collide_manifold(base, top);
}

TEST(ManifoldWarmStart, SlidingOneMillimetreKeepsIdsAndImpulses) {
  Manifold before = resting(0.0);
  ASSERT_EQ(before.count, 4);
  for (int i = 0; i < 4; ++i) {
    before.points[i].normal_impulse = 1.0 + i;
    before.points[i].tangent_impulse = Vec3(0.1 * i, 0.2, 0.05);  // a normal part to drop
  }
  Manifold after = resting(1e-3);
  ASSERT_EQ(after.count, 4);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(after.points[i].id, before.points[i].id);
  EXPECT_EQ(warm_start(before, after), 4);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(after.points[i].normal_impulse, 1.0 + i);
    EXPECT_EQ(after.points[i].tangent_impulse, Vec3(0.1 * i, 0.2, 0.0));
  }
}

TEST(ManifoldWarmStart, MatchesByIdNotByOrder) {
  Manifold before = resting(0.0);
  for (int i = 0; i < before.count; ++i) before.points[i].normal_impulse = 1.0 + i;
  Manifold after = before;
  std::reverse(after.points.begin(), after.points.begin() + after.count);
  for (int i = 0; i < after.count; ++i) after.points[i].normal_impulse = 0.0;
  // Far apart ids would also match by distance; move the new points 5 cm so only ids can match.
  for (int i = 0; i < after.count; ++i) after.points[i].point_a.x() += 0.05;
  for (int i = 0; i < after.count; ++i) after.points[i].point_b.x() += 0.05;
  EXPECT_EQ(warm_start(before, after), 4);
  for (int i = 0; i < after.count; ++i) EXPECT_EQ(after.points[i].normal_impulse, 4.0 - i);
}

TEST(ManifoldWarmStart, NewIdsFallBackToTheNearestPointWithinTheDistance) {
  Manifold before = resting(0.0);
  for (int i = 0; i < before.count; ++i) before.points[i].normal_impulse = 1.0 + i;
  Manifold after = resting(0.004);
  for (int i = 0; i < after.count; ++i) after.points[i].id.index_b += 100;  // all new
  EXPECT_EQ(warm_start(before, after), 4);  // 4 mm < 1 cm
  for (int i = 0; i < after.count; ++i) EXPECT_EQ(after.points[i].normal_impulse, 1.0 + i);
  WarmStartOptions tight;
  tight.match_distance = 0.003;
  EXPECT_EQ(warm_start(before, after, tight), 0);
  for (int i = 0; i < after.count; ++i) EXPECT_EQ(after.points[i].normal_impulse, 0.0);
}

TEST(ManifoldWarmStart, VanishedPointsDropTheirImpulseAndATurnedNormalCarriesNothing) {
  Manifold before = resting(0.0);
  for (int i = 0; i < before.count; ++i) before.points[i].normal_impulse = 1.0 + i;
  // Tipped by 0.01 rad about y: only the two -x corners stay within the (zero) margin.
  Manifold after = resting(0.0, 0.01);
  ASSERT_EQ(after.count, 2);
  EXPECT_EQ(warm_start(before, after), 2);
  for (int i = 0; i < after.count; ++i) {
    bool was_there = false;
    for (int j = 0; j < before.count; ++j)
      if (before.points[j].id == after.points[i].id) {
        was_there = true;
        EXPECT_EQ(after.points[i].normal_impulse, before.points[j].normal_impulse);
      }
    EXPECT_TRUE(was_there);
  }
  Manifold turned = resting(0.0);
  turned.normal = rot(Vec3::UnitX(), 0.5) * turned.normal;
  EXPECT_EQ(warm_start(before, turned), 0);
}

}  // namespace
}  // namespace simreel::sim::detail

namespace simreel::sim::detail {
namespace {

// ---------------------------------------------------------------------------------------------
// The triangle-plane cull of the mesh–convex narrow phase (TrianglePlaneCull, body_contacts.cpp)

TEST(MeshNarrowPhase, TrianglePlaneCullSkipsOnlyTrianglesGjkFindsApart) {
  // One tilted triangle of a posed mesh, and each solid kind at random poses around it, some
  // placed so that their nearest point lies exactly at the gap (plus or minus a hair) from the
  // triangle's plane, others beside the triangle at that distance from an edge's line: whenever the cull says apart, GJK on the pair (the test
  // the narrow phase would otherwise run) must say not touching, so skipping changes nothing.
  ShapeDef md;
  md.type = ShapeType::mesh;
  md.vertices = {Vec3(-0.8, -0.6, 0.1), Vec3(0.9, -0.4, -0.2), Vec3(0.1, 0.8, 0.3)};
  md.triangles = {{0, 1, 2}};
  Collider mesh = make_collider(md, "mesh");
  mesh.follow(Transform{Vec3(0.3, -0.2, 0.1), Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 0.5).normalized()))},
              Vec3::Zero(), Vec3::Zero());
  const Triangle& tri = mesh.mesh->triangles[0];
  const std::array<Vec3, 3> corners{tri.a, tri.b, tri.c};
  const PosedShape T(ConvexShape::hull(corners), mesh.R, mesh.center);
  const Vec3 n = mesh.R * tri.normal;  // world
  const std::vector<ShapeDef> solids{
      ShapeDef::sphere(0.2), ShapeDef::box(Vec3(0.3, 0.1, 0.2)), ShapeDef::capsule(0.1, 0.25),
      ShapeDef::cylinder(0.15, 0.2),
      ShapeDef::convex_hull({Vec3(0.3, 0, 0), Vec3(-0.1, 0.25, 0.05), Vec3(-0.15, -0.2, 0.1),
                             Vec3(0.05, 0.02, 0.35), Vec3(0.0, -0.05, -0.2)})};
  Rng rng(11);
  for (const ShapeDef& def : solids) {
    Collider s = make_collider(def, "solid");
    int culled = 0, touching = 0, samples = 0;
    for (int k = 0; k < 3000; ++k) {
      const Vec3 axis(rng.normal(), rng.normal(), rng.normal());
      const Quat q(Eigen::AngleAxisd(rng.uniform(0.0, 2.0 * std::numbers::pi), axis.normalized()));
      // A point of the triangle's plane near the triangle (barycentric weights in [-0.3, 1.3]).
      const double u = rng.uniform(-0.3, 1.3), v = rng.uniform(-0.3, 1.3);
      const Vec3 on = T.to_world((1.0 - u - v) * tri.a + u * tri.b + v * tri.c);
      const double side = k % 2 == 0 ? 1.0 : -1.0;
      for (const double gap : {0.005, 0.05}) {
        // Pose the solid, then (every third sample) slide it along n until its lowest point
        // towards the plane sits at gap + delta from it.
        s.follow(Transform{on + side * rng.uniform(-0.6, 0.6) * n, q}, Vec3::Zero(), Vec3::Zero());
        // every other third sample, slide it perpendicular to one edge, in the triangle's plane,
        // until its nearest point to that edge's line sits at gap + delta beyond it.
        const double delta = std::array{-1e-7, -1e-12, 0.0, 1e-12, 1e-10, 1e-9, 3e-9}[k / 3 % 7];
        if (k % 3 == 0) {
          const PosedShape body(convex_of(s), s.R, s.center);
          const Vec3 low = body.support(-side * n, ShapePart::full).world;
          const double lift = gap + delta - side * n.dot(low - on);
          s.follow(Transform{s.center + side * lift * n, q}, Vec3::Zero(), Vec3::Zero());
        } else if (k % 3 == 1) {
          const std::array<Vec3, 3> w{T.to_world(tri.a), T.to_world(tri.b), T.to_world(tri.c)};
          const int e = k / 3 % 3;
          const Vec3 &p = w[std::size_t(e)], &r = w[std::size_t((e + 1) % 3)],
                     &o = w[std::size_t((e + 2) % 3)];
          Vec3 m = (r - p).cross(n).normalized();
          if (m.dot(o - p) > 0.0) m = -m;
          const PosedShape body(convex_of(s), s.R, s.center);
          const Vec3 low = body.support(-m, ShapePart::full).world;
          const double shift = gap + delta - m.dot(low - p);
          s.follow(Transform{s.center + shift * m, q}, Vec3::Zero(), Vec3::Zero());
        }
        const PosedShape body(convex_of(s), s.R, s.center);
        const ConvexContact cc = collide(T, body, gap);
        const bool apart = TrianglePlaneCull(mesh, s).apart(tri, gap);
        ++samples;
        culled += apart;
        touching += cc.touching;
        EXPECT_FALSE(apart && cc.touching)
            << "kind " << int(def.type) << " sample " << k << " gap " << gap << " depth " << cc.depth;
      }
    }
    // Both outcomes occur in numbers, so the property is tested where it matters.
    EXPECT_GT(culled, samples / 5) << int(def.type);
    EXPECT_GT(touching, samples / 20) << int(def.type);
  }
}

}  // namespace
}  // namespace simreel::sim::detail
