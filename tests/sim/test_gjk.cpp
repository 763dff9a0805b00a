// Convex narrow phase (Coutinho §4.7 GJK; van den Bergen 2001 EPA) against closed forms at
// seeded random poses: sphere–sphere, sphere–box, box–box (axis gap, corner on face, deep
// penetration against a 15-axis SAT reference), capsule–capsule against an independent
// segment–segment routine, cylinder on a plane-like box, hull of a cube == box, symmetry,
// degenerate input, iteration counts and warm starting.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <random>
#include <vector>

#include "collision/convex_contact.hpp"
#include "collision/epa.hpp"
#include "collision/gjk.hpp"
#include "collision/support.hpp"

namespace simreel::sim::detail {
namespace {

/// Uniform doubles from a fixed-seed 64-bit Mersenne twister (bits -> [0, 1) by hand, so the
/// draws are the same with any standard library).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : g_(seed) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * double(g_() >> 11) * 0x1.0p-53; }
  Vec3 vec(double lo, double hi) { return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)}; }
  Mat3 rotation() {
    Eigen::Vector4d q;
    do {
      q = {uniform(-1, 1), uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)};
    } while (q.squaredNorm() > 1.0 || q.squaredNorm() < 1e-3);
    q.normalize();
    return Quat(q[0], q[1], q[2], q[3]).toRotationMatrix();
  }

 private:
  std::mt19937_64 g_;
};

constexpr double kInf = std::numeric_limits<double>::infinity();

/// Contact with an infinite margin: the exact gap of separated pairs, never the early out.
ConvexContact collide_exact(const PosedShape& A, const PosedShape& B) {
  return collide(A, B, kInf);
}

/// Sphere, box, capsule, cylinder and a tetrahedron hull, of comparable sizes (index = kind).
std::array<ConvexShape, 5> one_of_each_kind() {
  static const std::vector<Vec3> tetra{Vec3(0, 0, 0.5), Vec3(0.5, 0, -0.2), Vec3(-0.3, 0.4, -0.2),
                                       Vec3(-0.3, -0.4, -0.2)};
  return {ConvexShape::sphere(0.4), ConvexShape::box({0.3, 0.5, 0.2}), ConvexShape::capsule(0.3, 0.2),
          ConvexShape::cylinder(0.3, 0.4), ConvexShape::hull(tetra)};
}

bool finite(const ConvexContact& c) {
  return std::isfinite(c.depth) && c.normal.allFinite() && c.point_a.allFinite() &&
         c.point_b.allFinite() && std::abs(c.normal.norm() - 1.0) < 1e-9;
}

/// Closest points of segments p1q1 and p2q2 (Ericson, Real-Time Collision Detection §5.1.9,
/// clamped parameters), written apart from GJK as the reference.
double segment_segment_distance(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2) {
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.dot(d1), e = d2.dot(d2), f = d2.dot(r), c = d1.dot(r), b = d1.dot(d2);
  const double denom = a * e - b * b;
  double s = denom > 0.0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
  double t = (b * s + f) / e;
  if (t < 0.0) {
    t = 0.0;
    s = std::clamp(-c / a, 0.0, 1.0);
  } else if (t > 1.0) {
    t = 1.0;
    s = std::clamp((b - c) / a, 0.0, 1.0);
  }
  return ((p1 + s * d1) - (p2 + t * d2)).norm();
}

/// Minimum translation of two overlapping boxes: the smallest overlap over the 15 SAT axes
/// (Coutinho §2.4.1: three face normals of each box and the nine edge-edge cross products).
double box_box_sat_depth(const Mat3& Ra, const Vec3& ha, const Vec3& ta, const Mat3& Rb,
                         const Vec3& hb, const Vec3& tb) {
  std::vector<Vec3> axes;
  for (int i = 0; i < 3; ++i) {
    axes.push_back(Ra.col(i));
    axes.push_back(Rb.col(i));
    for (int j = 0; j < 3; ++j) {
      const Vec3 c = Ra.col(i).cross(Rb.col(j));
      if (c.norm() > 1e-6) axes.push_back(c.normalized());
    }
  }
  double best = std::numeric_limits<double>::infinity();
  for (const Vec3& u : axes) {
    const double ra = (Ra.transpose() * u).cwiseAbs().dot(ha);
    const double rb = (Rb.transpose() * u).cwiseAbs().dot(hb);
    best = std::min(best, ra + rb - std::abs(u.dot(tb - ta)));
  }
  return best;
}

// ---------------------------------------------------------------------------------------------
// Support mappings: h_S(d) = max_{x in S} d·x in closed form.

TEST(SupportMapping, SupportValuesMatchClosedForms) {
  Rng rng(11);
  const std::array<Vec3, 8> cube{Vec3(-1, -2, -3), Vec3(1, -2, -3), Vec3(-1, 2, -3), Vec3(1, 2, -3),
                                 Vec3(-1, -2, 3),  Vec3(1, -2, 3),  Vec3(-1, 2, 3),  Vec3(1, 2, 3)};
  const ConvexShape hull = ConvexShape::hull(cube);
  for (int n = 0; n < 200; ++n) {
    const Vec3 d = rng.vec(-1, 1);
    const double dxy = std::hypot(d.x(), d.y());
    EXPECT_NEAR(d.dot(ConvexShape::sphere(0.7).support(d)), 0.7 * d.norm(), 1e-12);
    EXPECT_NEAR(d.dot(ConvexShape::box({1, 2, 3}).support(d)), d.cwiseAbs().dot(Vec3(1, 2, 3)),
                1e-12);
    EXPECT_NEAR(d.dot(hull.support(d)), d.cwiseAbs().dot(Vec3(1, 2, 3)), 1e-12);
    EXPECT_NEAR(d.dot(ConvexShape::capsule(0.5, 0.2).support(d)),
                0.5 * std::abs(d.z()) + 0.2 * d.norm(), 1e-12);
    EXPECT_NEAR(d.dot(ConvexShape::cylinder(0.3, 0.8).support(d)),
                0.3 * dxy + 0.8 * std::abs(d.z()), 1e-12);
    // Cores: the sphere's is its centre, the capsule's its segment.
    EXPECT_EQ(ConvexShape::sphere(0.7).support(d, ShapePart::core), Vec3::Zero());
    EXPECT_NEAR(d.dot(ConvexShape::capsule(0.5, 0.2).support(d, ShapePart::core)),
                0.5 * std::abs(d.z()), 1e-12);
  }
  // Posed: the world support is the rotated local one, shifted.
  const Mat3 R = rng.rotation();
  const Vec3 t(1, -2, 0.5);
  const PosedShape p(ConvexShape::box({1, 2, 3}), R, t);
  const Vec3 d(0.3, -0.4, 0.8);
  EXPECT_NEAR(d.dot(p.support(d, ShapePart::full).world),
              d.dot(t) + (R.transpose() * d).cwiseAbs().dot(Vec3(1, 2, 3)), 1e-12);
  // Zero direction: a finite point of the shape.
  EXPECT_TRUE(ConvexShape::cylinder(0.3, 0.8).support(Vec3::Zero()).allFinite());
  EXPECT_TRUE(ConvexShape::sphere(0.3).support(Vec3::Zero()).allFinite());
}

// ---------------------------------------------------------------------------------------------
// The signed-volume sub-algorithm on simplices with known closest points.

TEST(GjkSimplex, ClosestPointsOfSimplices) {
  std::array<Vec3, 4> w{Vec3(1, -1, 2), Vec3(1, 1, 2), Vec3::Zero(), Vec3::Zero()};
  SimplexClosest c = closest_on_simplex(w, 2);
  EXPECT_EQ(c.count, 2);
  EXPECT_NEAR((c.v - Vec3(1, 0, 2)).norm(), 0.0, 1e-15);
  EXPECT_NEAR(c.lambda[0], 0.5, 1e-15);
  // Triangle over the origin at height 2: the projection is inside.
  w = {Vec3(-1, -1, 2), Vec3(2, -1, 2), Vec3(-1, 2, 2), Vec3::Zero()};
  c = closest_on_simplex(w, 3);
  EXPECT_EQ(c.count, 3);
  EXPECT_NEAR((c.v - Vec3(0, 0, 2)).norm(), 0.0, 1e-15);
  // Triangle whose closest point is a vertex.
  w = {Vec3(1, 1, 0), Vec3(2, 1, 0), Vec3(1, 2, 0), Vec3::Zero()};
  c = closest_on_simplex(w, 3);
  EXPECT_EQ(c.count, 1);
  EXPECT_EQ(c.index[0], 0);
  // Triangle whose closest point is on one edge (only the last coordinate is negative).
  w = {Vec3(-1, 1, 0), Vec3(1, 1, 0), Vec3(0, 3, 0), Vec3::Zero()};
  c = closest_on_simplex(w, 3);
  EXPECT_EQ(c.count, 2);
  EXPECT_NEAR((c.v - Vec3(0, 1, 0)).norm(), 0.0, 1e-15);
  // Tetrahedron around the origin; and one beside it (closest on the face x = 1).
  w = {Vec3(-1, -1, -1), Vec3(3, -1, -1), Vec3(-1, 3, -1), Vec3(-1, -1, 3)};
  EXPECT_EQ(closest_on_simplex(w, 4).count, 4);
  w = {Vec3(1, -1, -1), Vec3(1, 3, -1), Vec3(1, -1, 3), Vec3(4, 0, 0)};
  c = closest_on_simplex(w, 4);
  EXPECT_EQ(c.count, 3);
  EXPECT_NEAR((c.v - Vec3(1, 0, 0)).norm(), 0.0, 1e-15);
  // Collinear triangle and flat tetrahedron: a lower-dimensional answer, finite.
  w = {Vec3(1, -1, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(1, 2, 0)};
  c = closest_on_simplex(w, 3);
  EXPECT_NEAR((c.v - Vec3(1, 0, 0)).norm(), 0.0, 1e-15);
  c = closest_on_simplex(w, 4);
  EXPECT_NEAR((c.v - Vec3(1, 0, 0)).norm(), 0.0, 1e-15);
}

// ---------------------------------------------------------------------------------------------
// Closed forms at random poses.

TEST(GjkSphereSphere, DistanceAndDepthExact) {
  Rng rng(1);
  for (int n = 0; n < 1000; ++n) {
    const Vec3 c1 = rng.vec(-2, 2), c2 = rng.vec(-2, 2);
    const double r1 = rng.uniform(0.1, 1.0), r2 = rng.uniform(0.1, 1.0);
    const PosedShape a(ConvexShape::sphere(r1), rng.rotation(), c1);
    const PosedShape b(ConvexShape::sphere(r2), rng.rotation(), c2);
    const ConvexContact c = collide_exact(a, b);
    const double dist = (c2 - c1).norm() - r1 - r2;
    const Vec3 n12 = (c2 - c1).normalized();
    ASSERT_NEAR(c.depth, -dist, 1e-9) << n;
    EXPECT_NEAR((c.normal - n12).norm(), 0.0, 1e-9);
    EXPECT_NEAR((c.point_a - (c1 + r1 * n12)).norm(), 0.0, 1e-9);
    EXPECT_NEAR((c.point_b - (c2 - r2 * n12)).norm(), 0.0, 1e-9);
    EXPECT_EQ(collide(a, b, 0.0).touching, dist <= 0.0);  // margin 0: touching iff overlapping
  }
}

TEST(GjkSphereBox, DistanceToAnalyticClosestPoint) {
  Rng rng(2);
  for (int n = 0; n < 1000; ++n) {
    const Vec3 h = rng.vec(0.1, 1.0);
    const Mat3 R = rng.rotation();
    const Vec3 t = rng.vec(-1, 1);
    const double r = rng.uniform(0.05, 0.8);
    const Vec3 local = rng.vec(-2, 2);
    const PosedShape box(ConvexShape::box(h), R, t);
    const Vec3 c = R * local + t;
    const ConvexContact k = collide_exact(box, {ConvexShape::sphere(r), Mat3::Identity(), c});
    ASSERT_TRUE(finite(k));
    const Vec3 q = local.cwiseMax(-h).cwiseMin(h);  // closest point of the box, local frame
    if (q != local) {                               // centre outside the box: exact
      const double dist = (local - q).norm() - r;
      ASSERT_NEAR(k.depth, -dist, 1e-9) << n;
      EXPECT_NEAR((k.point_a - (R * q + t)).norm(), 0.0, 1e-9);
      EXPECT_NEAR((k.normal - R * (local - q).normalized()).norm(), 0.0, 1e-7);
    } else {  // centre inside: leave through the nearest face, depth r + distance to it
      const Vec3 gap = h - local.cwiseAbs();
      int k_axis = 0;
      const double face = gap.minCoeff(&k_axis);
      ASSERT_NEAR(k.depth, r + face, 1e-7) << n;
      const Vec3 axis = R.col(k_axis) * (local[k_axis] >= 0 ? 1.0 : -1.0);
      EXPECT_NEAR((k.normal - axis).norm(), 0.0, 1e-6);
    }
  }
}

TEST(GjkBoxBox, SeparatedAlongAnAxisAtAKnownGap) {
  Rng rng(3);
  for (int n = 0; n < 500; ++n) {
    const Vec3 ha = rng.vec(0.3, 1.0), hb = rng.vec(0.3, 1.0);
    const Mat3 R = rng.rotation();
    const int k = n % 3;
    const double gap = n % 2 == 0 ? rng.uniform(1e-3, 1.0) : -rng.uniform(1e-3, 0.05);
    Vec3 off = 0.3 * ha.cwiseMin(hb).cwiseProduct(rng.vec(-1, 1));  // faces overlap laterally
    off[k] = (n % 4 < 2 ? 1.0 : -1.0) * (ha[k] + hb[k] + gap);
    const Vec3 ta = rng.vec(-3, 3);
    const ConvexContact c = collide_exact({ConvexShape::box(ha), R, ta},
                                            {ConvexShape::box(hb), R, ta + R * off});
    ASSERT_NEAR(c.depth, -gap, 1e-9) << n;
    const Vec3 axis = R.col(k) * (off[k] > 0 ? 1.0 : -1.0);
    EXPECT_NEAR((c.normal - axis).norm(), 0.0, 1e-9);
    EXPECT_NEAR((c.point_a - c.point_b).dot(c.normal), c.depth, 1e-9);
  }
}

TEST(GjkBoxBox, RotatedCornerOnFace) {
  Rng rng(4);
  for (int n = 0; n < 500; ++n) {
    const Vec3 ha(5, 5, 1);
    const double yaw = rng.uniform(0, 6.3);
    const Mat3 Ra = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix();
    const Vec3 ta = rng.vec(-2, 2);
    const Vec3 hb = rng.vec(0.2, 0.6);
    const Mat3 Rb = rng.rotation();
    const double gap = n % 2 == 0 ? rng.uniform(1e-4, 1.0) : -rng.uniform(1e-4, 0.1);
    // B's lowest corner is sum_k h_k |R_zk| below its centre.
    const double drop = (Rb.row(2).transpose()).cwiseAbs().dot(hb);
    const Vec3 tb(ta.x() + rng.uniform(-1, 1), ta.y() + rng.uniform(-1, 1),
                  ta.z() + ha.z() + drop + gap);
    const ConvexContact c =
        collide_exact({ConvexShape::box(ha), Ra, ta}, {ConvexShape::box(hb), Rb, tb});
    ASSERT_NEAR(c.depth, -gap, 1e-9) << n;
    EXPECT_NEAR((c.normal - Vec3::UnitZ()).norm(), 0.0, 1e-9);
    EXPECT_NEAR(c.point_b.z(), tb.z() - drop, 1e-9);  // B's contact point is its lowest corner
  }
}

TEST(EpaBoxBox, DeepPenetrationMatchesSatMinimumTranslation) {
  Rng rng(5);
  for (int n = 0; n < 500; ++n) {
    const Vec3 ha = rng.vec(0.5, 2.0), hb = rng.vec(0.1, 1.0);
    const Mat3 Ra = rng.rotation();
    const Mat3 Rb = n % 2 == 0 ? Ra : rng.rotation();  // aligned, then arbitrary
    const Vec3 ta = rng.vec(-1, 1);
    const Vec3 tb = ta + Ra * ha.cwiseProduct(rng.vec(-0.9, 0.9));
    const ConvexContact c =
        collide_exact({ConvexShape::box(ha), Ra, ta}, {ConvexShape::box(hb), Rb, tb});
    const double sat = box_box_sat_depth(Ra, ha, ta, Rb, hb, tb);
    ASSERT_GT(sat, 0.0);
    ASSERT_NEAR(c.depth, sat, 1e-9) << n;
    // Moving B by depth along the normal leaves them touching: SAT depth there is ~0.
    EXPECT_NEAR(box_box_sat_depth(Ra, ha, ta, Rb, hb, tb + c.depth * c.normal), 0.0, 1e-9);
  }
}

TEST(GjkCapsuleCapsule, SegmentDistanceMinusRadii) {
  Rng rng(6);
  int checked = 0;
  for (int n = 0; n < 1000; ++n) {
    const double h1 = rng.uniform(0.1, 1.0), h2 = rng.uniform(0.1, 1.0);
    const double r1 = rng.uniform(0.05, 0.5), r2 = rng.uniform(0.05, 0.5);
    const Mat3 R1 = rng.rotation(), R2 = rng.rotation();
    const Vec3 t1 = rng.vec(-1, 1), t2 = rng.vec(-1, 1);
    const Vec3 a1 = R1.col(2), a2 = R2.col(2);
    const double seg = segment_segment_distance(t1 - h1 * a1, t1 + h1 * a1, t2 - h2 * a2,
                                                t2 + h2 * a2);
    const ConvexContact c = collide_exact({ConvexShape::capsule(h1, r1), R1, t1},
                                            {ConvexShape::capsule(h2, r2), R2, t2});
    ASSERT_TRUE(finite(c));
    if (seg < 1e-6) continue;  // axes crossing: approximate EPA on the rounded shapes
    ++checked;
    ASSERT_NEAR(c.depth, r1 + r2 - seg, 1e-9) << n;
    EXPECT_NEAR(((c.point_a - r1 * c.normal) - (c.point_b + r2 * c.normal)).norm(), seg, 1e-9);
  }
  EXPECT_GT(checked, 900);
}

TEST(GjkCylinderBox, CylinderOnPlaneLikeBox) {
  Rng rng(7);
  for (int n = 0; n < 500; ++n) {
    const Vec3 ha(10, 10, 1);
    const Vec3 ta = rng.vec(-1, 1);
    const double r = rng.uniform(0.1, 0.5), hh = rng.uniform(0.1, 1.0);
    const Mat3 R = rng.rotation();
    const double az = R(2, 2);  // the cylinder axis' z component
    const double drop = hh * std::abs(az) + r * std::sqrt(std::max(0.0, 1.0 - az * az));
    const double gap = n % 2 == 0 ? rng.uniform(1e-4, 1.0) : -rng.uniform(1e-4, 0.05);
    const Vec3 tb(ta.x() + rng.uniform(-2, 2), ta.y() + rng.uniform(-2, 2),
                  ta.z() + ha.z() + drop + gap);
    const ConvexContact c = collide_exact({ConvexShape::box(ha), Mat3::Identity(), ta},
                                            {ConvexShape::cylinder(r, hh), R, tb});
    ASSERT_NEAR(c.depth, -gap, 1e-9) << n;
    EXPECT_NEAR((c.normal - Vec3::UnitZ()).norm(), 0.0, 1e-7);
  }
}

TEST(GjkHull, CubeHullEqualsBox) {
  Rng rng(8);
  const Vec3 h(0.4, 0.7, 0.5);
  std::vector<Vec3> corners;
  for (int m = 0; m < 8; ++m) {
    corners.emplace_back(m & 1 ? h.x() : -h.x(), m & 2 ? h.y() : -h.y(), m & 4 ? h.z() : -h.z());
  }
  const ConvexShape hull = ConvexShape::hull(corners);
  const std::array<ConvexShape, 4> others{ConvexShape::sphere(0.3), ConvexShape::box({0.3, 0.6, 0.2}),
                                          ConvexShape::capsule(0.4, 0.2),
                                          ConvexShape::cylinder(0.3, 0.5)};
  for (int n = 0; n < 400; ++n) {
    const Mat3 Ra = rng.rotation(), Rb = rng.rotation();
    const Vec3 ta = rng.vec(-1, 1), tb = ta + rng.vec(-1.5, 1.5);
    const ConvexShape& o = others[n % 4];
    const ConvexContact cb = collide({ConvexShape::box(h), Ra, ta}, {o, Rb, tb}, kInf);
    const ConvexContact ch = collide_exact({hull, Ra, ta}, {o, Rb, tb});
    // Against the cylinder's curved rim GJK's normal converges as sqrt(rel_tol).
    const bool curved = n % 4 == 3;
    ASSERT_NEAR(ch.depth, cb.depth, curved ? 1e-8 : 1e-9) << n;
    EXPECT_NEAR((ch.normal - cb.normal).norm(), 0.0, curved ? 1e-4 : 1e-7) << n;
  }
}

TEST(GjkContact, TouchingGivesZeroDistance) {
  const PosedShape a(ConvexShape::box({1, 1, 1}), Mat3::Identity(), Vec3::Zero());
  const ConvexContact face = collide(a, {ConvexShape::box({1, 1, 1}), Mat3::Identity(), {0.3, 0.2, 2}}, 0.0);
  EXPECT_NEAR(face.depth, 0.0, 1e-12);
  EXPECT_TRUE(face.touching);
  EXPECT_NEAR((face.normal - Vec3::UnitZ()).norm(), 0.0, 1e-9);
  const ConvexContact ball = collide(a, {ConvexShape::sphere(0.5), Mat3::Identity(), {0.2, 1.5, 0.1}}, 0.0);
  EXPECT_NEAR(ball.depth, 0.0, 1e-12);
  EXPECT_TRUE(ball.touching);
  // A corner exactly on the face, rotated.
  Rng rng(9);
  for (int n = 0; n < 100; ++n) {
    const Mat3 Rb = rng.rotation();
    const Vec3 hb = rng.vec(0.2, 0.6);
    const double drop = (Rb.row(2).transpose()).cwiseAbs().dot(hb);
    const ConvexContact c =
        collide(a, {ConvexShape::box(hb), Rb, {rng.uniform(-0.5, 0.5), 0.1, 1.0 + drop}}, 1e-6);
    EXPECT_NEAR(c.depth, 0.0, 1e-9);
    EXPECT_TRUE(c.touching);
  }
  // Beyond the margin: not touching, and -depth is a lower bound of the true gap 0.5.
  const ConvexContact far = collide(a, {ConvexShape::sphere(0.5), Mat3::Identity(), {0, 0, 2}}, 0.1);
  EXPECT_FALSE(far.touching);
  EXPECT_LE(-far.depth, 0.5 + 1e-12);
  EXPECT_GT(-far.depth, 0.1);
}

TEST(GjkContact, SwappingShapesFlipsTheNormal) {
  Rng rng(10);
  const std::array<ConvexShape, 5> shapes = one_of_each_kind();
  for (int n = 0; n < 500; ++n) {
    const PosedShape a(shapes[n % 5], rng.rotation(), rng.vec(-1, 1));
    const PosedShape b(shapes[(n / 5) % 5], rng.rotation(), rng.vec(-1, 1));
    const ConvexContact ab = collide_exact(a, b), ba = collide_exact(b, a);
    ASSERT_TRUE(finite(ab) && finite(ba));
    // The cylinder's rim is curved: GJK and EPA converge to it only to their tolerance.
    const bool curved = n % 5 == 3 || (n / 5) % 5 == 3;
    ASSERT_NEAR(ab.depth, ba.depth, curved ? 1e-8 : 1e-9) << n;
    EXPECT_NEAR((ab.normal + ba.normal).norm(), 0.0, curved ? 1e-4 : 1e-7) << n;
  }
}

TEST(GjkDegenerate, FiniteResultsAndBoundedIterations) {
  const GjkOptions gjk_defaults;
  const EpaOptions epa_defaults;
  const int bound = 2 * gjk_defaults.max_iterations + epa_defaults.max_iterations + 8;
  // Two spheres at the same centre: depth r1 + r2 (the rounded EPA is approximate).
  const ConvexContact same = collide({ConvexShape::sphere(0.5), Mat3::Identity(), Vec3(1, 1, 1)},
                                     {ConvexShape::sphere(0.3), Mat3::Identity(), Vec3(1, 1, 1)}, 0);
  ASSERT_TRUE(finite(same));
  EXPECT_NEAR(same.depth, 0.8, 1e-2);
  EXPECT_LE(same.depth, 0.8 + 1e-9);
  // Capsules crossing at their centres, at right angles: pushed apart by r1 + r2 = 0.5.
  const ConvexContact cross = collide({ConvexShape::capsule(1, 0.2), Mat3::Identity(), Vec3::Zero()},
                                      {ConvexShape::capsule(1, 0.3),
                                       Eigen::AngleAxisd(1.5707963267948966, Vec3::UnitX()).toRotationMatrix(),
                                       Vec3::Zero()}, 0);
  ASSERT_TRUE(finite(cross));
  EXPECT_NEAR(cross.depth, 0.5, 1e-2);
  EXPECT_LE(cross.gjk_iterations + cross.epa_iterations, bound);
  // Coplanar hull points (a flat square with a repeated point and its centre) over a box.
  static const std::vector<Vec3> square{Vec3(-1, -1, 0), Vec3(1, -1, 0), Vec3(1, 1, 0),
                                        Vec3(-1, 1, 0), Vec3(1, 1, 0), Vec3(0, 0, 0)};
  const PosedShape floor(ConvexShape::box({2, 2, 0.5}), Mat3::Identity(), Vec3(0, 0, -0.5));
  const ConvexContact above = collide(floor, {ConvexShape::hull(square), Mat3::Identity(), {0.1, 0, 0.25}}, 0);
  EXPECT_NEAR(above.depth, -0.25, 1e-12);
  const ConvexContact sunk = collide(floor, {ConvexShape::hull(square), Mat3::Identity(), {0.1, 0, -0.1}}, 0);
  ASSERT_TRUE(finite(sunk));
  EXPECT_NEAR(sunk.depth, 0.1, 1e-9);
  // Two coplanar flat squares overlapping: D is flat; finite, depth 0.
  const ConvexContact flat = collide({ConvexShape::hull(square), Mat3::Identity(), Vec3::Zero()},
                                     {ConvexShape::hull(square), Mat3::Identity(), {0.5, 0.2, 0}}, 0);
  ASSERT_TRUE(finite(flat));
  EXPECT_NEAR(flat.depth, 0.0, 1e-12);
  // A very flat box (1 nm thick) just above, and just inside, a box.
  const ConvexShape sheet = ConvexShape::box({0.5, 0.5, 1e-9});
  EXPECT_NEAR(collide(floor, {sheet, Mat3::Identity(), {0, 0, 1e-3}}, 0).depth, -(1e-3 - 1e-9), 1e-12);
  const ConvexContact in = collide(floor, {sheet, Mat3::Identity(), {0, 0, -1e-3}}, 0);
  EXPECT_NEAR(in.depth, 1e-3 + 1e-9, 1e-12);
  EXPECT_NEAR((in.normal - Vec3::UnitZ()).norm(), 0.0, 1e-9);
  // Identical boxes at the same pose: leave through the thinnest pair of faces, 2 * 0.2.
  const PosedShape b(ConvexShape::box({0.5, 0.3, 0.2}), Mat3::Identity(), Vec3(1, 2, 3));
  const ConvexContact coincident = collide(b, b, 0);
  ASSERT_TRUE(finite(coincident));
  EXPECT_NEAR(coincident.depth, 0.4, 1e-9);
  EXPECT_NEAR(std::abs(coincident.normal.z()), 1.0, 1e-9);
  // Straight from GJK: zero-size shapes at one point, bounded iterations.
  const GjkResult point = gjk_distance({ConvexShape::sphere(0), Mat3::Identity(), Vec3::Zero()},
                                       {ConvexShape::sphere(0), Mat3::Identity(), Vec3::Zero()});
  EXPECT_EQ(point.status, GjkStatus::overlap);
  EXPECT_LE(point.iterations, gjk_defaults.max_iterations);
}

TEST(GjkWarmStart, CachedSimplexGivesTheSameAnswerInFewerIterations) {
  Rng rng(12);
  long cold = 0, warm = 0;
  for (int n = 0; n < 300; ++n) {
    const PosedShape a(ConvexShape::box(rng.vec(0.3, 1.0)), rng.rotation(), Vec3::Zero());
    PosedShape b(ConvexShape::box(rng.vec(0.3, 1.0)), rng.rotation(), rng.vec(2.5, 3.0));
    GjkSimplex cache;
    (void)collide(a, b, kInf, &cache);
    // A small motion, as between two steps.
    b.translation += rng.vec(-0.01, 0.01);
    b.rotation = Eigen::AngleAxisd(0.01, Vec3::UnitZ()).toRotationMatrix() * b.rotation;
    const ConvexContact c0 = collide(a, b, kInf);
    const ConvexContact c1 = collide(a, b, kInf, &cache);
    ASSERT_NEAR(c1.depth, c0.depth, 1e-9) << n;
    cold += c0.gjk_iterations;
    warm += c1.gjk_iterations;
  }
  std::cout << "[ gjk      ] warm start: mean GJK iterations cold " << double(cold) / 300
            << ", warm " << double(warm) / 300 << "\n";
  EXPECT_LT(warm, cold);
}

TEST(GjkIterations, MeanCountsStaySmall) {
  // Every pair of the five kinds at 400 random poses, about half of them overlapping.
  Rng rng(13);
  const std::array<ConvexShape, 5> shapes = one_of_each_kind();
  const std::array<const char*, 5> names{"sphere", "box", "capsule", "cylinder", "hull"};
  long gjk = 0, epa = 0, queries = 0, epa_queries = 0;
  int gjk_max = 0, epa_max = 0;
  for (int i = 0; i < 5; ++i) {
    for (int j = i; j < 5; ++j) {
      long pg = 0, pe = 0, pq = 0, peq = 0;
      for (int n = 0; n < 400; ++n) {
        const ConvexContact c = collide_exact({shapes[i], rng.rotation(), Vec3::Zero()},
                                              {shapes[j], rng.rotation(), rng.vec(-0.9, 0.9)});
        ASSERT_TRUE(finite(c));
        pg += c.gjk_iterations;
        ++pq;
        gjk_max = std::max(gjk_max, c.gjk_iterations);
        if (c.epa_iterations > 0) {
          pe += c.epa_iterations;
          ++peq;
          epa_max = std::max(epa_max, c.epa_iterations);
        }
      }
      std::cout << "[ gjk      ] " << names[i] << "-" << names[j] << ": mean GJK "
                << double(pg) / double(pq) << ", mean EPA "
                << (peq > 0 ? double(pe) / double(peq) : 0.0) << " over " << peq
                << " overlaps\n";
      gjk += pg;
      epa += pe;
      queries += pq;
      epa_queries += peq;
    }
  }
  const double gjk_mean = double(gjk) / double(queries);
  const double epa_mean = double(epa) / double(epa_queries);
  std::cout << "[ gjk      ] all: mean GJK " << gjk_mean << " (max " << gjk_max << "), mean EPA "
            << epa_mean << " (max " << epa_max << ") over " << queries << " queries\n";
  RecordProperty("mean_gjk_iterations", std::to_string(gjk_mean));
  RecordProperty("mean_epa_iterations", std::to_string(epa_mean));
  EXPECT_GT(epa_queries, queries / 8);
  EXPECT_LT(gjk_mean, 10.0);
  EXPECT_LT(epa_mean, 30.0);
  EXPECT_LE(gjk_max, GjkOptions{}.max_iterations);
}

}  // namespace
}  // namespace simreel::sim::detail
