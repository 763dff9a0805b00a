// Contact manifolds of any two convex shapes on top of collide() (see contact_manifold.hpp).
#include "collision/contact_manifold.hpp"

#include <algorithm>
#include <cmath>

#include "collision/box_box.hpp"
#include "collision/clip.hpp"

namespace simreel::sim::detail {

namespace {

double bias(const ManifoldOptions& o, double separation) {
  return o.bias_abs + o.bias_rel * std::abs(separation);
}

/// A candidate reference face: the face of `s` most aligned with `dir`, and how far `other`
/// lies beyond its plane (m; the separation along the face normal, <= the true separation).
struct FaceCandidate {
  bool valid = false;
  FacePolygon polygon;
  double separation = 0.0;
};

void face_candidate(const PosedShape& s, const HullFaces* faces, const PosedShape& other,
                    const Vec3& dir, FaceCandidate& out) {
  out.valid = false;
  if (!has_faces(s, faces)) return;
  if (!face_polygon(s, faces, most_aligned_face(s, faces, dir), out.polygon)) return;
  const Vec3& n = out.polygon.normal;
  out.separation = n.dot(other.support(-n, ShapePart::full).world - out.polygon.vertices[0]);
  out.valid = true;
}

/// Two capsules whose axes are parallel within parallel_sin: one point at each end of the part
/// of A's axis that B's axis overlaps (Box2D's b2CollideCapsules does the same in 2-D).
bool parallel_capsules(const PosedShape& A, const PosedShape& B, const ConvexContact& c,
                       const ManifoldOptions& o, Manifold& m) {
  const Vec3 a0 = A.to_world({0, 0, -A.shape.half_height}), a1 = A.to_world({0, 0, A.shape.half_height});
  const Vec3 b0 = B.to_world({0, 0, -B.shape.half_height}), b1 = B.to_world({0, 0, B.shape.half_height});
  const Vec3 da = a1 - a0, db = b1 - b0;
  const double la2 = da.squaredNorm(), lb2 = db.squaredNorm();
  if (!(la2 > 0.0) || !(lb2 > 0.0)) return false;
  if (da.cross(db).norm() > o.parallel_sin * std::sqrt(la2 * lb2)) return false;
  // B's ends projected on A's axis, as parameters s in [0, 1].
  double s0 = (b0 - a0).dot(da) / la2, s1 = (b1 - a0).dot(da) / la2;
  bool swap_ends = s0 > s1;
  if (swap_ends) std::swap(s0, s1);
  const double lo = std::max(0.0, s0), hi = std::min(1.0, s1);
  if (!(hi - lo > 1e-9)) return false;  // end to end: one point
  const double ra = A.shape.radius, rb = B.shape.radius;
  const Vec3& n = c.normal;
  int count = 0;
  for (const double s : {lo, hi}) {
    const Vec3 pa = a0 + s * da;
    const double t = std::clamp((pa - b0).dot(db) / lb2, 0.0, 1.0);
    const Vec3 pb = b0 + t * db;
    const double sep = (pb - pa).dot(n) - ra - rb;
    if (!(sep <= o.margin)) continue;
    ManifoldPoint& p = m.points[count++];
    p = ManifoldPoint{};
    p.point_a = pa + ra * n;
    p.point_b = pb - rb * n;
    p.separation = sep;
    // An end of the overlap is an end of A's axis (A vertex, B edge) or of B's (A edge, B vertex).
    const bool a_end = s == lo ? s0 <= 0.0 : s1 >= 1.0;
    const std::uint32_t b_end = std::uint32_t((s == lo) != swap_ends ? 0 : 1);
    p.id = a_end ? FeatureId{FeatureType::vertex, FeatureType::edge, s == lo ? 0u : 1u, 0}
                 : FeatureId{FeatureType::edge, FeatureType::vertex, 0, b_end};
  }
  if (count == 0) return false;
  m.count = count;
  m.normal = n;
  return true;
}

}  // namespace

Manifold manifold_from_contact(const ConvexContact& c) {
  Manifold m;
  if (!c.touching) return m;
  m.count = 1;
  m.normal = c.normal;
  m.points[0].point_a = c.point_a;
  m.points[0].point_b = c.point_b;
  m.points[0].separation = -c.depth;
  m.points[0].id = {FeatureType::shape, FeatureType::shape, 0, 0};
  return m;
}

Manifold collide_manifold(const PosedShape& A, const PosedShape& B, const ManifoldOptions& options,
                          const HullFaces* faces_a, const HullFaces* faces_b) {
  if (A.shape.kind == ConvexKind::box && B.shape.kind == ConvexKind::box)
    return collide_boxes(A, B, options);
  const ConvexContact c = collide(A, B, options.margin);
  if (!c.touching) return {};
  const Manifold single = manifold_from_contact(c);
  if (A.shape.kind == ConvexKind::sphere || B.shape.kind == ConvexKind::sphere) return single;

  Manifold m;
  if (A.shape.kind == ConvexKind::capsule && B.shape.kind == ConvexKind::capsule)
    return parallel_capsules(A, B, c, options, m) ? m : single;

  // The reference face: A's or B's face most aligned with the contact normal, if its separation
  // is (within the bias) the true one; A's preferred, as in collide_boxes.
  const double sep = -c.depth;
  FaceCandidate fa, fb;
  face_candidate(A, faces_a, B, c.normal, fa);
  face_candidate(B, faces_b, A, -c.normal, fb);
  const bool ok_a = fa.valid && fa.separation >= sep - bias(options, sep);
  const bool ok_b = fb.valid && fb.separation >= sep - bias(options, sep);
  if (!ok_a && !ok_b) return single;
  const bool ref_is_a = ok_a && (!ok_b || fb.separation <= fa.separation + bias(options, fa.separation));
  const FacePolygon& ref = ref_is_a ? fa.polygon : fb.polygon;
  const PosedShape& other = ref_is_a ? B : A;
  const HullFaces* other_faces = ref_is_a ? faces_b : faces_a;

  // The incident feature: the other polytope's face most anti-parallel to the reference normal,
  // or a capsule's segment / a cylinder's cap or side line.
  FacePolygon inc;
  if (has_faces(other, other_faces)) {
    if (!face_polygon(other, other_faces, most_aligned_face(other, other_faces, -ref.normal), inc))
      return single;
  } else if (!rounded_feature(other, ref.normal, options.parallel_sin, inc)) {
    return single;
  }
  if (!clip_faces(ref, inc, options.margin, ref_is_a, m) || m.count == 0) return single;
  return m;
}

}  // namespace simreel::sim::detail
