// Contact manifolds of boxes (box–box SAT + face clipping) and the clipping pieces, against
// closed forms: a box resting flat (any yaw, any world orientation) gives its four bottom
// corners at the gap; an overhang gives the analytic clipped polygon; an edge gives two points,
// a corner one; crossing edges give the analytic closest points; swapping A and B flips the
// normal and keeps the points; the output is deterministic.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "collision/box_box.hpp"
#include "collision/clip.hpp"
#include "collision/manifold.hpp"
#include "collision/polytope_faces.hpp"

namespace simreel::sim::detail {
namespace {

Mat3 rot(const Vec3& axis, double angle) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

/// Some world orientations to pose whole scenes in (identity first).
std::vector<Mat3> scene_rotations() {
  return {Mat3::Identity(), rot({1, 2, 3}, 0.7), rot({-2, 1, 0.5}, 2.1)};
}

/// Whether every expected point is matched by exactly one manifold point (order-free), tol m.
bool same_point_set(const std::vector<Vec3>& expected, const Manifold& m, bool on_b, double tol) {
  if (int(expected.size()) != m.count) return false;
  std::vector<bool> used(expected.size(), false);
  for (int i = 0; i < m.count; ++i) {
    const Vec3& p = on_b ? m.points[i].point_b : m.points[i].point_a;
    bool found = false;
    for (std::size_t j = 0; j < expected.size() && !found; ++j) {
      if (!used[j] && (expected[j] - p).norm() <= tol) used[j] = found = true;
    }
    if (!found) return false;
  }
  return true;
}

std::vector<Vec3> posed(const std::vector<Vec3>& pts, const Mat3& Q) {
  std::vector<Vec3> out;
  for (const Vec3& p : pts) out.push_back(Q * p);
  return out;
}

constexpr double kTol = 1e-9;

TEST(BoxBox, RestingFlatAnyYawGivesFourBottomCornersAtTheGap) {
  const ConvexShape big = ConvexShape::box({2.0, 1.5, 0.5});
  const Vec3 h(0.5, 0.3, 0.25);
  const ConvexShape small = ConvexShape::box(h);
  for (const Mat3& Q : scene_rotations()) {
    for (const double yaw : {0.0, 0.3, 1.0, std::numbers::pi / 4, 2.5, -1.2}) {
      for (const double gap : {0.01, 0.0, -0.003}) {
        const Vec3 c(0.2, -0.1, 0.5 + h.z() + gap);
        const Mat3 Ry = rot(Vec3::UnitZ(), yaw);
        const PosedShape A(big, Q, Vec3::Zero());
        const PosedShape B(small, Q * Ry, Q * c);
        ManifoldOptions o;
        o.margin = 0.02;
        const Manifold m = collide_boxes(A, B, o);
        std::vector<Vec3> corners_b, corners_a;
        for (const double sx : {-1.0, 1.0})
          for (const double sy : {-1.0, 1.0}) {
            const Vec3 p = c + Ry * Vec3(sx * h.x(), sy * h.y(), -h.z());
            corners_b.push_back(p);
            corners_a.push_back({p.x(), p.y(), 0.5});
          }
        ASSERT_EQ(m.count, 4) << "yaw " << yaw << " gap " << gap;
        EXPECT_NEAR((m.normal - Q * Vec3::UnitZ()).norm(), 0.0, 1e-12);
        for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.points[i].separation, gap, kTol);
        EXPECT_TRUE(same_point_set(posed(corners_b, Q), m, true, kTol));
        EXPECT_TRUE(same_point_set(posed(corners_a, Q), m, false, kTol));

        // A and B exchanged: the normal flips, the points stay.
        const Manifold s = collide_boxes(B, A, o);
        ASSERT_EQ(s.count, 4);
        EXPECT_NEAR((s.normal + Q * Vec3::UnitZ()).norm(), 0.0, 1e-12);
        for (int i = 0; i < 4; ++i) EXPECT_NEAR(s.points[i].separation, gap, kTol);
        EXPECT_TRUE(same_point_set(posed(corners_b, Q), s, false, kTol));
        EXPECT_TRUE(same_point_set(posed(corners_a, Q), s, true, kTol));
      }
    }
  }
}

TEST(BoxBox, SmallBoxOnASideFaceOfARotatedBigBox) {
  // The small box rests on the big box's +x face; the whole scene is turned.
  const Vec3 H(1.0, 2.0, 3.0), h(0.2, 0.4, 0.3);
  const double gap = -0.002, roll = 0.4;
  for (const Mat3& Q : scene_rotations()) {
    const Mat3 Rs = rot(Vec3::UnitX(), roll);  // spun about the face normal
    const Vec3 c(H.x() + h.x() + gap, 0.5, -1.0);
    const PosedShape big(ConvexShape::box(H), Q, Vec3(1, 2, 3));
    const PosedShape small(ConvexShape::box(h), Q * Rs, Vec3(1, 2, 3) + Q * c);
    const Manifold m = collide_boxes(small, big);  // A = small: its face is the reference
    std::vector<Vec3> corners;
    for (const double sy : {-1.0, 1.0})
      for (const double sz : {-1.0, 1.0})
        corners.push_back(Vec3(1, 2, 3) + Q * (c + Rs * Vec3(-h.x(), sy * h.y(), sz * h.z())));
    ASSERT_EQ(m.count, 4);
    EXPECT_NEAR((m.normal + Q * Vec3::UnitX()).norm(), 0.0, 1e-12);
    EXPECT_TRUE(same_point_set(corners, m, false, kTol));  // on A, the reference face
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.points[i].separation, gap, kTol);
  }
}

TEST(BoxBox, OverhangGivesTheClippedRectangleCorners) {
  // Bottom [-1, 1]² x [-0.5, 0.5]; top half 0.5 centred at (0.8, 0.3): the overlap is
  // [0.3, 1] x [-0.2, 0.8].
  const double gap = -0.001;
  const PosedShape A(ConvexShape::box({1, 1, 0.5}), Mat3::Identity(), Vec3::Zero());
  const PosedShape B(ConvexShape::box({0.5, 0.5, 0.5}), Mat3::Identity(), {0.8, 0.3, 1.0 + gap});
  const Manifold m = collide_boxes(A, B);
  std::vector<Vec3> expected;
  for (const double x : {0.3, 1.0})
    for (const double y : {-0.2, 0.8}) expected.push_back({x, y, 0.5 + gap});
  EXPECT_TRUE(same_point_set(expected, m, true, kTol));
  for (int i = 0; i < m.count; ++i) EXPECT_NEAR(m.points[i].separation, gap, kTol);
}

TEST(BoxBox, YawedOverhangGivesTheClippedTriangle) {
  // A cube of half 0.5 turned 45° (a diamond of half-diagonal d) centred 0.3 beyond the bottom
  // box's y = 1 edge: what lies over the bottom box is the triangle with apex (0.5, 1.3 - d) and
  // base on y = 1 from x = 0.5 - (d - 0.3) to 0.5 + (d - 0.3).
  const double d = 0.5 * std::sqrt(2.0), gap = -0.004;
  const PosedShape A(ConvexShape::box({1, 1, 0.5}), Mat3::Identity(), Vec3::Zero());
  const PosedShape B(ConvexShape::box({0.5, 0.5, 0.5}), rot(Vec3::UnitZ(), std::numbers::pi / 4),
                     {0.5, 1.3, 1.0 + gap});
  const Manifold m = collide_boxes(A, B);
  const double z = 0.5 + gap;
  const std::vector<Vec3> expected{
      {0.5, 1.3 - d, z}, {0.5 - (d - 0.3), 1.0, z}, {0.5 + (d - 0.3), 1.0, z}};
  EXPECT_TRUE(same_point_set(expected, m, true, kTol));
  // The two base points are incident edges crossing the reference side plane y = 1.
  int crossings = 0;
  for (int i = 0; i < m.count; ++i)
    crossings += m.points[i].id.type_a == FeatureType::edge && m.points[i].id.type_b == FeatureType::edge;
  EXPECT_EQ(crossings, 2);
}

TEST(BoxBox, BigOverhangReducesToFourOfTheClippedPentagon) {
  // The diamond centred at (0.8, 0.9) over the corner (1, 1): the clipped polygon is the
  // pentagon below; four of its corners are kept.
  const double d = 0.5 * std::sqrt(2.0), gap = -0.004, z = 0.5 + gap;
  const PosedShape A(ConvexShape::box({1, 1, 0.5}), Mat3::Identity(), Vec3::Zero());
  const PosedShape B(ConvexShape::box({0.5, 0.5, 0.5}), rot(Vec3::UnitZ(), std::numbers::pi / 4),
                     {0.8, 0.9, 1.0 + gap});
  const Manifold m = collide_boxes(A, B);
  const std::vector<Vec3> pentagon{{0.8 - d, 0.9, z}, {0.8, 0.9 - d, z}, {1.0, 1.1 - d, z},
                                   {1.0, 1.0, z}, {0.9 - d, 1.0, z}};
  ASSERT_EQ(m.count, 4);
  for (int i = 0; i < m.count; ++i) {
    double nearest = 1e9;
    for (const Vec3& p : pentagon) nearest = std::min(nearest, (p - m.points[i].point_b).norm());
    EXPECT_LT(nearest, kTol);
    EXPECT_NEAR(m.points[i].separation, gap, kTol);
  }
}

TEST(BoxBox, TiltedOntoAnEdgeGivesTwoPointsAlongIt) {
  const double h = 0.5;
  for (const double tilt : {std::numbers::pi / 4, 0.5}) {
    for (const Mat3& Q : scene_rotations()) {
      const double gap = -0.001;
      // Turned about x: the lowest edge runs along x at depth h (cos t + sin t) below the centre.
      const double drop = h * (std::cos(tilt) + std::sin(tilt));
      const Vec3 c(0.1, 0.2, 0.5 + drop + gap);
      const PosedShape A(ConvexShape::box({2, 2, 0.5}), Q, Vec3::Zero());
      const PosedShape B(ConvexShape::box({h, h, h}), Q * rot(Vec3::UnitX(), tilt), Q * c);
      const Manifold m = collide_boxes(A, B);
      const double y = c.y() + h * (std::sin(tilt) - std::cos(tilt));  // the lowest edge's y
      const std::vector<Vec3> expected{Q * Vec3(c.x() - h, y, 0.5 + gap),
                                       Q * Vec3(c.x() + h, y, 0.5 + gap)};
      EXPECT_TRUE(same_point_set(expected, m, true, kTol)) << "tilt " << tilt;
      EXPECT_NEAR((m.normal - Q * Vec3::UnitZ()).norm(), 0.0, 1e-12);
    }
  }
}

TEST(BoxBox, CornerDownGivesOnePoint) {
  const double h = 0.5, gap = -0.002;
  // Turn the cube so its (-1, -1, -1) corner points straight down.
  const Mat3 R = Eigen::Quaterniond::FromTwoVectors(Vec3(-1, -1, -1), Vec3(0, 0, -1))
                     .toRotationMatrix();
  const Vec3 c(0.1, 0.2, 0.5 + h * std::sqrt(3.0) + gap);
  const PosedShape A(ConvexShape::box({2, 2, 0.5}), Mat3::Identity(), Vec3::Zero());
  const PosedShape B(ConvexShape::box({h, h, h}), R, c);
  const Manifold m = collide_boxes(A, B);
  ASSERT_EQ(m.count, 1);
  EXPECT_NEAR((m.points[0].point_b - Vec3(0.1, 0.2, 0.5 + gap)).norm(), 0.0, kTol);
  EXPECT_NEAR(m.points[0].separation, gap, kTol);
  EXPECT_EQ(m.points[0].id.type_b, FeatureType::vertex);
  EXPECT_EQ(m.points[0].id.index_b, box_vertex_id(false, false, false));
}

/// Two cubes of half h = 0.5 whose edges cross: A turned 45° about x (its top edge runs along x
/// at height h√2 above its centre), B turned 45° about y and yawed by phi (its bottom edge runs
/// along (-sin phi, cos phi, 0), h√2 below its centre, `gap` above A's edge); the whole scene
/// turned by Q. The closest points lie one above the other where the edges cross.
struct CrossingEdges {
  PosedShape A, B;
  Vec3 pa, pb;  // analytic closest points
};
CrossingEdges crossing_edges(const Mat3& Q, double gap) {
  const double h = 0.5, s2 = std::sqrt(2.0), phi = 0.6;
  const Vec3 ca(0.05, 0.1, 0.0), cb(0.15, -0.05, 2 * h * s2 + gap);
  CrossingEdges e;
  e.A = PosedShape(ConvexShape::box({h, h, h}), Q * rot(Vec3::UnitX(), std::numbers::pi / 4), Q * ca);
  e.B = PosedShape(ConvexShape::box({h, h, h}),
                   Q * rot(Vec3::UnitZ(), phi) * rot(Vec3::UnitY(), std::numbers::pi / 4), Q * cb);
  // A's top edge: y = ca.y, z = h√2. B's bottom edge: (cb.x, cb.y) + u (-sin phi, cos phi),
  // z = cb.z - h√2. They cross above/below the point with y = ca.y.
  const double u = (ca.y() - cb.y()) / std::cos(phi);
  const double x = cb.x() - u * std::sin(phi);
  e.pa = Q * Vec3(x, ca.y(), h * s2);
  e.pb = Q * Vec3(x, ca.y(), h * s2 + gap);
  return e;
}

TEST(BoxBox, CrossingEdgesGiveTheAnalyticClosestPoints) {
  for (const Mat3& Q : scene_rotations()) {
    for (const double gap : {-0.01, 0.005}) {
      const CrossingEdges e = crossing_edges(Q, gap);
      ManifoldOptions o;
      o.margin = 0.01;
      const Manifold m = collide_boxes(e.A, e.B, o);
      ASSERT_EQ(m.count, 1);
      EXPECT_NEAR((m.points[0].point_a - e.pa).norm(), 0.0, kTol);
      EXPECT_NEAR((m.points[0].point_b - e.pb).norm(), 0.0, kTol);
      EXPECT_NEAR(m.points[0].separation, gap, kTol);
      EXPECT_NEAR((m.normal - Q * Vec3::UnitZ()).norm(), 0.0, 1e-12);
      EXPECT_EQ(m.points[0].id.type_a, FeatureType::edge);
      EXPECT_EQ(m.points[0].id.type_b, FeatureType::edge);
      // Swapped: the same point pair, the normal flipped.
      const Manifold s = collide_boxes(e.B, e.A, o);
      ASSERT_EQ(s.count, 1);
      EXPECT_NEAR((s.points[0].point_a - e.pb).norm(), 0.0, kTol);
      EXPECT_NEAR((s.normal + Q * Vec3::UnitZ()).norm(), 0.0, 1e-12);
    }
  }
}

TEST(BoxBox, FaceAxisKeptUnlessAnEdgeAxisIsBetterByTheBias) {
  // The crossing edges separate 0.01 less along the edge axis than along any face axis; with a
  // bias larger than that difference the face axis wins and the points come from clipping.
  const CrossingEdges e = crossing_edges(Mat3::Identity(), -0.01);
  ManifoldOptions o;
  o.bias_abs = 10.0;
  o.margin = 1.0;  // the tilted face's clipped points lie up to ~0.7 m off it
  const Manifold m = collide_boxes(e.A, e.B, o);
  ASSERT_GE(m.count, 1);
  // The normal is then a face normal of one cube (at 45° to z), not the edge axis z.
  EXPECT_NEAR(std::abs(m.normal.z()), std::sqrt(0.5), 1e-12);
  EXPECT_FALSE(m.points[0].id.type_a == FeatureType::edge && m.count == 1);
}

TEST(BoxBox, NearTieBetweenFacesGoesToA) {
  // A small box tilted by 1e-4 rad on a big one: B's face separates slightly better (by
  // about 6e-5 m), within the default bias, so A's tilted face stays the reference and gives the
  // normal; with no bias B's face (normal exactly -z) takes over.
  const Mat3 tilt = rot(Vec3::UnitX(), 1e-4);
  const PosedShape A(ConvexShape::box({0.3, 0.3, 0.3}), tilt, {0, 0, 0.799});
  const PosedShape B(ConvexShape::box({2, 2, 0.5}), Mat3::Identity(), Vec3::Zero());
  const Manifold m = collide_boxes(A, B);
  ASSERT_EQ(m.count, 4);
  EXPECT_NEAR((m.normal + tilt.col(2)).norm(), 0.0, 1e-15);
  ManifoldOptions no_bias;
  no_bias.bias_abs = no_bias.bias_rel = 0.0;
  const Manifold n = collide_boxes(A, B, no_bias);
  ASSERT_EQ(n.count, 4);
  EXPECT_EQ(n.normal, Vec3(0, 0, -1));
}

TEST(BoxBox, SeparatedBeyondTheMarginGivesNothing) {
  const PosedShape A(ConvexShape::box({1, 1, 0.5}), Mat3::Identity(), Vec3::Zero());
  const PosedShape B(ConvexShape::box({0.5, 0.5, 0.5}), Mat3::Identity(), {0.2, 0.1, 1.03});
  ManifoldOptions o;
  o.margin = 0.02;
  EXPECT_EQ(collide_boxes(A, B, o).count, 0);
  o.margin = 0.04;
  EXPECT_EQ(collide_boxes(A, B, o).count, 4);
}

TEST(BoxBox, DeterministicOrderAndIds) {
  const PosedShape A(ConvexShape::box({1, 1, 0.5}), rot({1, 1, 0}, 0.01), Vec3::Zero());
  const PosedShape B(ConvexShape::box({0.5, 0.5, 0.5}), rot(Vec3::UnitZ(), 0.7), {0.6, 0.7, 0.999});
  const Manifold m1 = collide_boxes(A, B), m2 = collide_boxes(A, B);
  ASSERT_EQ(m1.count, m2.count);
  ASSERT_GT(m1.count, 0);
  for (int i = 0; i < m1.count; ++i) {
    EXPECT_EQ(m1.points[i].point_a, m2.points[i].point_a);  // bit-identical
    EXPECT_EQ(m1.points[i].id, m2.points[i].id);
  }
  // Ids are distinct within a manifold (what warm starting matches on).
  for (int i = 0; i < m1.count; ++i)
    for (int j = i + 1; j < m1.count; ++j) EXPECT_FALSE(m1.points[i].id == m1.points[j].id);
}

/// A unit-square reference face [-1, 1]² at z = 0 (normal +z, counter-clockwise, vertex ids
/// 10..13) and an incident square [0, 3]² at height z, facing down.
void squares(double z, FacePolygon& ref, FacePolygon& inc) {
  ref.count = 4;
  ref.vertices = {Vec3(-1, -1, 0), Vec3(1, -1, 0), Vec3(1, 1, 0), Vec3(-1, 1, 0)};
  ref.vertex_ids = {10, 11, 12, 13};
  ref.normal = Vec3::UnitZ();
  ref.index = 4;
  inc.count = 4;
  inc.vertices = {Vec3(0, 0, z), Vec3(0, 3, z), Vec3(3, 3, z), Vec3(3, 0, z)};
  inc.vertex_ids = {20, 21, 22, 23};
  inc.normal = -Vec3::UnitZ();
  inc.index = 7;
}

TEST(Clip, OverlapOfTwoSquaresWithItsFeatureIds) {
  FacePolygon ref, inc;
  squares(-0.01, ref, inc);
  Manifold m;
  ASSERT_TRUE(clip_faces(ref, inc, 0.0, true, m));
  // The overlap [0, 1]²: the incident vertex (0, 0), two incident edges crossing the reference
  // side planes x = 1 and y = 1, and the reference corner (1, 1) inside the incident face.
  ASSERT_EQ(m.count, 4);
  int vertex_in_face = 0, crossings = 0, corner_in_face = 0;
  for (int i = 0; i < m.count; ++i) {
    const ManifoldPoint& p = m.points[i];
    EXPECT_NEAR(p.separation, -0.01, 1e-15);
    const FeatureId& id = p.id;
    if (id.type_a == FeatureType::face && id.type_b == FeatureType::vertex) {
      ++vertex_in_face;
      EXPECT_EQ(id.index_a, 4u);
      EXPECT_EQ(id.index_b, 20u);
      EXPECT_NEAR((p.point_b - Vec3(0, 0, -0.01)).norm(), 0.0, 1e-15);
    } else if (id.type_a == FeatureType::edge && id.type_b == FeatureType::edge) {
      ++crossings;
    } else if (id.type_a == FeatureType::vertex && id.type_b == FeatureType::face) {
      ++corner_in_face;
      EXPECT_EQ(id.index_a, 12u);  // the reference corner (1, 1)
      EXPECT_EQ(id.index_b, 7u);
      EXPECT_NEAR((p.point_a - Vec3(1, 1, 0)).norm(), 0.0, 1e-15);
    }
  }
  EXPECT_EQ(vertex_in_face, 1);
  EXPECT_EQ(crossings, 2);
  EXPECT_EQ(corner_in_face, 1);
  // Reference on B: normal flipped, ids and points exchanged.
  Manifold s;
  ASSERT_TRUE(clip_faces(ref, inc, 0.0, false, s));
  ASSERT_EQ(s.count, m.count);
  EXPECT_EQ(s.normal, -m.normal);
  for (int i = 0; i < m.count; ++i) {
    EXPECT_EQ(s.points[i].id, m.points[i].id.swapped());
    EXPECT_EQ(s.points[i].point_a, m.points[i].point_b);
  }
}

TEST(Clip, IncidentFaceCoveringTheReferenceGivesItsCorners) {
  // A large incident square turned by 0.2 rad covers the whole reference square: every point is
  // a reference corner inside the incident face (the clipped polygon's edges run along the side
  // planes, so each corner is where two side planes meet).
  FacePolygon ref, inc;
  squares(-0.01, ref, inc);
  const Mat3 turn = rot(Vec3::UnitZ(), 0.2);
  inc.vertices = {turn * Vec3(-5, -5, 0), turn * Vec3(-5, 5, 0), turn * Vec3(5, 5, 0),
                  turn * Vec3(5, -5, 0)};
  for (int i = 0; i < 4; ++i) inc.vertices[i].z() = -0.01;
  Manifold m;
  ASSERT_TRUE(clip_faces(ref, inc, 0.0, true, m));
  ASSERT_EQ(m.count, 4);
  std::vector<std::uint32_t> corners;
  for (int i = 0; i < m.count; ++i) {
    EXPECT_EQ(m.points[i].id.type_a, FeatureType::vertex);
    EXPECT_EQ(m.points[i].id.type_b, FeatureType::face);
    const std::uint32_t c = m.points[i].id.index_a;
    corners.push_back(c);
    ASSERT_GE(c, 10u);
    ASSERT_LE(c, 13u);
    EXPECT_NEAR((m.points[i].point_a - ref.vertices[c - 10]).norm(), 0.0, 1e-15);
  }
  std::sort(corners.begin(), corners.end());
  EXPECT_EQ(corners, (std::vector<std::uint32_t>{10, 11, 12, 13}));
}

TEST(Clip, FlushEqualFacesKeepTheIncidentVertices) {
  // Incident vertices exactly on the side planes stay themselves (no crossing points).
  FacePolygon ref, inc;
  squares(-0.01, ref, inc);
  for (int i = 0; i < 4; ++i) inc.vertices[i] = ref.vertices[3 - i] + Vec3(0, 0, -0.01);
  Manifold m;
  ASSERT_TRUE(clip_faces(ref, inc, 0.0, true, m));
  ASSERT_EQ(m.count, 4);
  for (int i = 0; i < m.count; ++i) EXPECT_EQ(m.points[i].id.type_b, FeatureType::vertex);
}

TEST(Clip, PointsAboveTheMarginAreDropped) {
  FacePolygon ref, inc;
  squares(0.05, ref, inc);
  Manifold m;
  ASSERT_TRUE(clip_faces(ref, inc, 0.04, true, m));
  EXPECT_EQ(m.count, 0);
  ASSERT_TRUE(clip_faces(ref, inc, 0.06, true, m));
  EXPECT_EQ(m.count, 4);
}

TEST(Clip, SegmentIsClippedToTheFace) {
  FacePolygon ref, inc;
  squares(0.0, ref, inc);
  inc.count = 2;
  inc.type = FeatureType::edge;
  inc.index = 0;
  inc.radius = 0.1;
  inc.vertices[0] = Vec3(-3, 0.5, 0.08);
  inc.vertices[1] = Vec3(0.5, 0.5, 0.08);
  Manifold m;
  ASSERT_TRUE(clip_faces(ref, inc, 0.0, true, m));
  ASSERT_EQ(m.count, 2);
  EXPECT_NEAR((m.points[0].point_b - Vec3(-1, 0.5, -0.02)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((m.points[1].point_b - Vec3(0.5, 0.5, -0.02)).norm(), 0.0, 1e-15);
  EXPECT_NEAR(m.points[0].separation, -0.02, 1e-15);
  EXPECT_EQ(m.points[0].id.type_b, FeatureType::edge);    // clipped at x = -1
  EXPECT_EQ(m.points[1].id.type_b, FeatureType::vertex);  // the segment's own end
}

TEST(Clip, ReductionKeepsTheDeepestAndTheWidest) {
  // A regular octagon, vertex 5 deepest: kept are 5, the opposite vertex 1 (farthest from it),
  // and 3 and 7, the apexes of the largest triangles on either side of the line 5-1.
  std::array<Vec3, 8> p;
  std::array<double, 8> sep;
  for (int i = 0; i < 8; ++i) {
    const double a = i * std::numbers::pi / 4;
    p[i] = {std::cos(a), std::sin(a), 0.0};
    sep[i] = i == 5 ? -0.02 : -0.01;
  }
  std::array<int, kMaxManifoldPoints> chosen{};
  ASSERT_EQ(reduce_contact_points(p.data(), sep.data(), 8, Vec3::UnitZ(), chosen), 4);
  EXPECT_EQ(chosen, (std::array<int, 4>{1, 3, 5, 7}));
  ASSERT_EQ(reduce_contact_points(p.data(), sep.data(), 3, Vec3::UnitZ(), chosen), 3);
}

}  // namespace
}  // namespace simreel::sim::detail
