#pragma once
// Narrow phase: a sphere of radius r moving a -> a + d against one triangle (Coutinho §3.4 swept
// spheres, §3.7 first contact with a face, edge or vertex and that feature's normal). Closed
// forms: the face is a plane offset by r, an edge a cylinder of radius r, a vertex a sphere of
// radius r; their union is the triangle grown by r, so the earliest of the three is the exact
// time of contact. Triangles are two-sided: the face normal is taken on the side of the start
// point. Private; header-only so the tests can check it against brute force.

#include <algorithm>
#include <cmath>

#include "collision/bvh.hpp"

namespace simreel::sim::detail {

/// First contact found so far: fraction s of the segment, unit normal at contact (pointing from
/// the surface to the particle) and the particle centre there, moved out to exactly r.
struct SweepHit {
  double s = std::numeric_limits<double>::infinity();
  Vec3 normal = Vec3::Zero();
  Vec3 point = Vec3::Zero();
};

namespace np {

/// (m) How deep a segment that starts on a surface must go into it to count as a contact: a
/// particle moving along a face, or off a round surface along its tangent, is not re-hit at s = 0
/// through the rounding of its start point (which would use up its contacts and stall it).
inline constexpr double kSkin = 1e-9;

/// First time s in [0, 1] at which a point m + s d enters the ball |x| <= rho, given
/// A = |d|², B = m·d, C = |m|² - rho² (the closed form of a swept sphere against a vertex,
/// an edge's axis or a sphere, Coutinho §3.5). A start inside (C <= 0) counts at s = 0 when it
/// moves further in, deeper than kSkin somewhere along the segment. Returns false when there is
/// no such entry.
inline bool first_entry(double A, double B, double C, double rho, double& s) {
  if (!(B < 0.0)) return false;
  if (C <= 0.0) {
    // |m + t d|² - rho² = C + 2 B t + A t², least at t* = -B / A (within [0, 1]); a depth delta
    // below the surface is about 2 rho delta there.
    const double t = A > 0.0 ? std::min(1.0, -B / A) : 1.0;
    if (!(C + t * (2.0 * B + A * t) < -2.0 * rho * kSkin)) return false;
    s = 0.0;
    return true;
  }
  if (A == 0.0) return false;
  const double disc = B * B - A * C;
  if (disc < 0.0) return false;
  s = (-B - std::sqrt(disc)) / A;
  return s <= 1.0;
}

/// A start point inside the grown feature counts as a contact at s = 0 when it moves further in
/// (the particle rests on, or was pushed a little into, the surface), and is put back on it.
inline void sweep_vertex(const Vec3& v, const Vec3& a, const Vec3& d, double r, SweepHit& best) {
  const Vec3 m = a - v;
  const double A = d.squaredNorm(), B = m.dot(d), C = m.squaredNorm() - r * r;
  double s;
  if (!first_entry(A, B, C, r, s)) return;
  if (!(s < best.s)) return;
  const Vec3 p = a + s * d;
  const Vec3 off = p - v;
  const double len = off.norm();
  if (!(len > 0.0)) return;
  best.s = s;
  best.normal = off / len;
  best.point = v + best.normal * r;
}

inline void sweep_edge(const Vec3& p0, const Vec3& p1, const Vec3& a, const Vec3& d, double r,
                       SweepHit& best) {
  const Vec3 e = p1 - p0;
  const double ee = e.squaredNorm();
  if (!(ee > 0.0)) return;
  const Vec3 m = a - p0;
  const Vec3 mp = m - (m.dot(e) / ee) * e;
  const Vec3 dp = d - (d.dot(e) / ee) * e;
  const double A = dp.squaredNorm(), B = mp.dot(dp), C = mp.squaredNorm() - r * r;
  double s;
  if (!first_entry(A, B, C, r, s)) return;
  if (!(s < best.s)) return;
  const Vec3 p = a + s * d;
  const double u = (p - p0).dot(e) / ee;
  if (u < 0.0 || u > 1.0) return;  // the end vertices cover the rest
  const Vec3 q = p0 + u * e;
  const Vec3 off = p - q;
  const double len = off.norm();
  if (!(len > 0.0)) return;
  best.s = s;
  best.normal = off / len;
  best.point = q + best.normal * r;
}

/// Is p (on the triangle's plane, or near it) inside the triangle's prism? Barycentric signs.
inline bool in_prism(const Triangle& t, const Vec3& p) {
  const Vec3& n = t.normal;
  return n.dot((t.b - t.a).cross(p - t.a)) >= 0.0 && n.dot((t.c - t.b).cross(p - t.b)) >= 0.0 &&
         n.dot((t.a - t.c).cross(p - t.c)) >= 0.0;
}

inline void sweep_face(const Triangle& t, const Vec3& a, const Vec3& d, double r, SweepHit& best) {
  double d0 = t.normal.dot(a - t.a);
  double dd = t.normal.dot(d);
  Vec3 n = t.normal;
  if (d0 < 0.0 || (d0 == 0.0 && dd > 0.0)) {  // the start point's side
    n = -n;
    d0 = -d0;
    dd = -dd;
  }
  if (!(dd < 0.0)) return;  // not approaching
  if (d0 <= r && !(r - (d0 + dd) > kSkin)) return;  // on the face, moving along it
  const double s = d0 > r ? (d0 - r) / -dd : 0.0;
  if (s > 1.0 || !(s < best.s)) return;
  Vec3 p = a + s * d;
  if (!in_prism(t, p)) return;
  p += (r - n.dot(p - t.a)) * n;
  best.s = s;
  best.normal = n;
  best.point = p;
}

}  // namespace np

/// Swept sphere against one triangle: updates `best` if this triangle is touched earlier.
/// Every feature tested in turn: the reference the culled version below must match bit for bit.
inline void sweep_triangle_all(const Triangle& t, const Vec3& a, const Vec3& d, double r,
                               SweepHit& best) {
  np::sweep_face(t, a, d, r, best);
  np::sweep_edge(t.a, t.b, a, d, r, best);
  np::sweep_edge(t.b, t.c, a, d, r, best);
  np::sweep_edge(t.c, t.a, a, d, r, best);
  np::sweep_vertex(t.a, a, d, r, best);
  np::sweep_vertex(t.b, a, d, r, best);
  np::sweep_vertex(t.c, a, d, r, best);
}

/// A triangle with what the culled sweep derives from it alone (MeshGrid keeps these, so that a
/// particle's sweep does not derive them again every step): the in-plane normals of its edges
/// and their lengths.
struct SweepTriangle {
  Triangle t;
  Vec3 w[3];          ///< normal x e_k, e_k = v_{k+1} - v_k (a -> b, b -> c, c -> a)
  double len[3];      ///< |e_k| (m)
  double amax = 0.0;  ///< max |t.a_i| (m), for the rounding margin
  SweepTriangle() = default;
  explicit SweepTriangle(const Triangle& x) : t(x) {
    const Vec3* v[3] = {&t.a, &t.b, &t.c};
    for (int k = 0; k < 3; ++k) {
      const Vec3 e = *v[(k + 1) % 3] - *v[k];
      w[k] = t.normal.cross(e);
      len[k] = e.norm();
    }
    amax = t.a.cwiseAbs().maxCoeff();
  }
};

/// A swept segment a -> b = a + d with max |a_i|, |b_i| (m), shared by the triangles it is tested
/// against.
struct SweepSegment {
  Vec3 a, d, b;
  double amax;
  SweepSegment(const Vec3& a_, const Vec3& d_)
      : a(a_), d(d_), b(a_ + d_), amax(std::max(a_.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff())) {}
};

/// The same hits as sweep_triangle_all(), with the features the segment cannot come within r of
/// left untested. In the triangle's plane, edge k's line splits space by the signed distance
/// (n x e_k)·(x - v_k) / |e_k| (positive inside, the convention of in_prism); it is linear along
/// the segment, so when both ends are beyond r on one side, no point of the segment comes within
/// r of the edge's line — nor of the edge or its end vertices — and when that side is the outside,
/// of the triangle at all. (A particle lying on a face far from its edges then costs one face
/// test; the triangle next to it none.) Likewise for the triangle's plane, tested first. The
/// margin covers rounding (1e-6 r plus 1e-12 per metre of the coordinates' size), far above the
/// features' own. Once a contact at s = 0 is known, none can come earlier.
inline void sweep_triangle(const SweepTriangle& st, const SweepSegment& sg, double r,
                           SweepHit& best) {
  if (best.s == 0.0) return;
  const Triangle& t = st.t;
  const Vec3 &a = sg.a, &d = sg.d, &b = sg.b;
  const double size = 1.0 + std::max(sg.amax, st.amax);
  const double reach = r * (1.0 + 1e-6) + 1e-12 * size;
  // Both ends beyond r on one side of the triangle's plane: the grown triangle lies within r of
  // the plane, so the segment meets none of it (a drop above a terrain's triangle: two dots).
  const double h0 = t.normal.dot(a - t.a), h1 = t.normal.dot(b - t.a);
  if ((h0 > reach && h1 > reach) || (h0 < -reach && h1 < -reach)) return;
  const Vec3* v[3] = {&t.a, &t.b, &t.c};
  bool far[3];
  for (int k = 0; k < 3; ++k) {
    const Vec3& p = *v[k];
    const double s0 = st.w[k].dot(a - p), s1 = st.w[k].dot(b - p);
    const double lim = reach * st.len[k];
    if (s0 < -lim && s1 < -lim) return;  // wholly outside this edge by more than r
    far[k] = s0 > lim && s1 > lim;
  }
  np::sweep_face(t, a, d, r, best);
  if (!far[0]) np::sweep_edge(t.a, t.b, a, d, r, best);
  if (!far[1]) np::sweep_edge(t.b, t.c, a, d, r, best);
  if (!far[2]) np::sweep_edge(t.c, t.a, a, d, r, best);
  if (!far[2] && !far[0]) np::sweep_vertex(t.a, a, d, r, best);
  if (!far[0] && !far[1]) np::sweep_vertex(t.b, a, d, r, best);
  if (!far[1] && !far[2]) np::sweep_vertex(t.c, a, d, r, best);
}

/// The same for a bare triangle and segment (its edge data derived here).
inline void sweep_triangle(const Triangle& t, const Vec3& a, const Vec3& d, double r,
                           SweepHit& best) {
  if (best.s == 0.0) return;
  sweep_triangle(SweepTriangle(t), SweepSegment(a, d), r, best);
}

/// Does the ray from p along dir (unit) cross the triangle at a positive distance < len?
/// (Möller–Trumbore; used by the parity test for points inside closed meshes.)
inline bool ray_crosses(const Triangle& t, const Vec3& p, const Vec3& dir, double len) {
  const Vec3 e1 = t.b - t.a, e2 = t.c - t.a;
  const Vec3 q = dir.cross(e2);
  const double det = e1.dot(q);
  if (std::abs(det) < 1e-300) return false;
  const double inv = 1.0 / det;
  const Vec3 s = p - t.a;
  const double u = s.dot(q) * inv;
  if (u < 0.0 || u > 1.0) return false;
  const Vec3 k = s.cross(e1);
  const double v = dir.dot(k) * inv;
  if (v < 0.0 || u + v > 1.0) return false;
  const double dist = e2.dot(k) * inv;
  return dist > 0.0 && dist < len;
}

}  // namespace simreel::sim::detail
