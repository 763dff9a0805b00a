// Box–box SAT over 15 axes with face clipping (see box_box.hpp).
#include "collision/box_box.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "collision/clip.hpp"
#include "collision/contact_manifold.hpp"
#include "collision/polytope_faces.hpp"

namespace simreel::sim::detail {

namespace {

enum class AxisKind : std::uint8_t { face_a, face_b, edge };

struct Axis {
  AxisKind kind = AxisKind::face_a;
  int i = 0, j = 0;           ///< A's axis (face_a, edge) and B's axis (face_b, edge)
  double separation = -std::numeric_limits<double>::infinity();
  Vec3 direction = Vec3::UnitZ();  ///< unit, A's frame, from A toward B
};

/// The tolerance by which an axis must beat the preferred one to replace it (m).
double bias(const ManifoldOptions& o, double separation) {
  return o.bias_abs + o.bias_rel * std::abs(separation);
}

}  // namespace

void closest_parameters_of_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0,
                                    const Vec3& q1, double& s_out, double& t_out) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  const double c = d1.dot(r), b = d1.dot(d2);
  const double denom = a * e - b * b;
  double s = 0.0, t = 0.0;
  if (!(a > 0.0) && !(e > 0.0)) {
    s = t = 0.0;
  } else if (!(a > 0.0)) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else if (!(e > 0.0)) {
    s = std::clamp(-c / a, 0.0, 1.0);
  } else if (denom <= 1e-12 * a * e) {
    // Parallel: the middle of the overlap of q's projection on p (or the nearer ends).
    const double u0 = std::clamp(-c / a, 0.0, 1.0);
    const double u1 = std::clamp((q1 - p0).dot(d1) / a, 0.0, 1.0);
    s = 0.5 * (u0 + u1);
    t = std::clamp((p0 + s * d1 - q0).dot(d2) / e, 0.0, 1.0);
    s = std::clamp((q0 + t * d2 - p0).dot(d1) / a, 0.0, 1.0);
  } else {
    s = std::clamp((b * f - c * e) / denom, 0.0, 1.0);
    t = (b * s + f) / e;
    if (t < 0.0) {
      t = 0.0;
      s = std::clamp(-c / a, 0.0, 1.0);
    } else if (t > 1.0) {
      t = 1.0;
      s = std::clamp((b - c) / a, 0.0, 1.0);
    }
  }
  s_out = s;
  t_out = t;
}

void closest_points_of_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1,
                                Vec3& on_p, Vec3& on_q) {
  double s, t;
  closest_parameters_of_segments(p0, p1, q0, q1, s, t);
  on_p = p0 + s * (p1 - p0);
  on_q = q0 + t * (q1 - q0);
}

Manifold collide_boxes(const PosedShape& A, const PosedShape& B, const ManifoldOptions& options) {
  assert(A.shape.kind == ConvexKind::box && B.shape.kind == ConvexKind::box);
  const Vec3& ha = A.shape.half_extents;
  const Vec3& hb = B.shape.half_extents;
  // Everything in A's frame: B's axes are the columns of R, B's centre is t.
  const Mat3 R = A.rotation.transpose() * B.rotation;
  const Vec3 t = A.to_local(B.translation);
  const double margin = options.margin;

  // Separation along the unit axis L (A's frame), L turned to point from A toward B.
  // Gottschalk's test: |t·L| - (A's projected radius + B's projected radius).
  auto separation_along = [&](Vec3 L, Axis& axis) {
    if (t.dot(L) < 0.0) L = -L;
    axis.direction = L;
    axis.separation = t.dot(L) - ha.dot(L.cwiseAbs()) - hb.dot((R.transpose() * L).cwiseAbs());
    return axis.separation;
  };

  Axis best_a, best_b, best_edge;
  for (int i = 0; i < 3; ++i) {
    Axis axis{AxisKind::face_a, i, 0};
    if (separation_along(Vec3::Unit(i), axis) > margin) return {};
    if (axis.separation > best_a.separation) best_a = axis;
  }
  for (int j = 0; j < 3; ++j) {
    Axis axis{AxisKind::face_b, 0, j};
    if (separation_along(R.col(j), axis) > margin) return {};
    if (axis.separation > best_b.separation) best_b = axis;
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const Vec3 L = Vec3::Unit(i).cross(R.col(j));
      const double len = L.norm();
      // Nearly parallel edges: the cross product is rounding noise, and the face axes already
      // bound the separation to within len times the boxes' size.
      if (!(len > 1e-6)) continue;
      Axis axis{AxisKind::edge, i, j};
      if (separation_along(L / len, axis) > margin) return {};
      if (axis.separation > best_edge.separation) best_edge = axis;
    }
  }

  Axis best = best_a;
  if (best_b.separation > best_a.separation + bias(options, best_a.separation)) best = best_b;
  if (best_edge.separation > best.separation + bias(options, best.separation)) best = best_edge;

  Manifold m;
  if (best.kind == AxisKind::edge) {
    // The edge of A along axis i that is extreme toward B, and B's edge along j extreme toward
    // A: their closest points are the contact (one point; Coutinho §4.4's edge–edge case).
    const Vec3& L = best.direction;
    const Vec3 Lb = R.transpose() * L;
    const int i = best.i, j = best.j;
    Vec3 a0, b0;
    for (int k = 0; k < 3; ++k) {
      a0[k] = L[k] >= 0.0 ? ha[k] : -ha[k];
      b0[k] = Lb[k] <= 0.0 ? hb[k] : -hb[k];
    }
    Vec3 a1 = a0, b1 = b0;
    a0[i] = -ha[i];
    a1[i] = ha[i];
    b0[j] = -hb[j];
    b1[j] = hb[j];
    Vec3 pa, pb;
    closest_points_of_segments(A.to_world(a0), A.to_world(a1), B.to_world(b0), B.to_world(b1),
                               pa, pb);
    m.count = 1;
    m.normal = A.rotation * L;
    m.points[0].point_a = pa;
    m.points[0].point_b = pb;
    m.points[0].separation = (pb - pa).dot(m.normal);
    const int ua = (i + 1) % 3, va = (i + 2) % 3, ub = (j + 1) % 3, vb = (j + 2) % 3;
    m.points[0].id = {FeatureType::edge, FeatureType::edge,
                      box_edge_id(i, a0[ua] > 0.0, a0[va] > 0.0),
                      box_edge_id(j, b0[ub] > 0.0, b0[vb] > 0.0)};
    return m;
  }

  // A face axis: the reference face faces the other box; the incident face is the other box's
  // face most anti-parallel to the reference normal.
  const bool ref_is_a = best.kind == AxisKind::face_a;
  const PosedShape& ref_shape = ref_is_a ? A : B;
  const PosedShape& inc_shape = ref_is_a ? B : A;
  const Vec3 n_ref = (ref_is_a ? 1.0 : -1.0) * (A.rotation * best.direction);  // ref -> inc
  FacePolygon ref, inc;
  face_polygon(ref_shape, nullptr, most_aligned_face(ref_shape, nullptr, n_ref), ref);
  face_polygon(inc_shape, nullptr, most_aligned_face(inc_shape, nullptr, -n_ref), inc);
  clip_faces(ref, inc, margin, ref_is_a, m);
  // Nothing within the margin after clipping: the chosen face axis's support points lie beyond
  // the reference face's edges (a face kept by the bias at a corner). GJK/EPA's one point then.
  if (m.count == 0) return manifold_from_contact(collide(A, B, margin));
  return m;
}

}  // namespace simreel::sim::detail
