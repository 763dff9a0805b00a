#pragma once
// Closest points and continuous coplanarity times for the cloth contact pass (private): the
// vertex–triangle and edge–edge primitives of Bridson, Fedkiw & Anderson 2002 ("Robust treatment
// of collisions, contact and friction for cloth animation", §4–5), closest points after Ericson
// ("Real-Time Collision Detection" §5.1.5, §5.1.9). Coutinho §2.2 names the same closest-feature
// queries for rigid bodies.

#include <algorithm>
#include <cmath>

#include "collision/box_box.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim::detail::cg {

/// Barycentric weights (wa, wb, wc), each >= 0, summing to 1, of the point of triangle abc
/// closest to p (Ericson §5.1.5, region by region).
inline Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {1, 0, 0};
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double den = va + vb + vc;
  if (!(den > 0.0)) return {1.0 / 3, 1.0 / 3, 1.0 / 3};  // degenerate triangle
  const double v = vb / den, w = vc / den;
  return {1 - v - w, v, w};
}

/// Parameters s, t in [0, 1] of the closest points p1 + s (q1 - p1), p2 + t (q2 - p2) of two
/// segments: the narrow phase's (collision/box_box.hpp; Ericson §5.1.9, parallel segments at
/// the middle of their overlap).
inline void closest_segments(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2,
                             double& s, double& t) {
  closest_parameters_of_segments(p1, q1, p2, q2, s, t);
}

/// Times in [0, 1] (ascending, at most 3, written to `roots`, count returned) at which the four
/// linearly moving points x_k(t) = x0_k + t (x1_k - x0_k) are coplanar: the roots of the cubic
/// (x_1 - x_0) × (x_2 - x_0) · (x_3 - x_0) = 0 (Bridson et al. 2002 §4, after Provot 1997).
/// Each monotone piece of the cubic between its turning points is bisected where its sign
/// changes; a turning point where the cubic touches zero (|f| below a relative tolerance) counts
/// as a root too.
inline int coplanar_times(const Vec3 x0[4], const Vec3 x1[4], double roots[3]) {
  const Vec3 e0 = x0[1] - x0[0], f0 = x0[2] - x0[0], g0 = x0[3] - x0[0];
  const Vec3 de = (x1[1] - x1[0]) - e0, df = (x1[2] - x1[0]) - f0, dg = (x1[3] - x1[0]) - g0;
  const Vec3 C0 = e0.cross(f0), C1 = e0.cross(df) + de.cross(f0), C2 = de.cross(df);
  const double k0 = C0.dot(g0), k1 = C0.dot(dg) + C1.dot(g0), k2 = C1.dot(dg) + C2.dot(g0),
               k3 = C2.dot(dg);
  auto f = [&](double t) { return ((k3 * t + k2) * t + k1) * t + k0; };
  // Scale of the terms, for the "touches zero" tolerance.
  const double scale = std::abs(k0) + std::abs(k1) + std::abs(k2) + std::abs(k3);
  if (!(scale > 0.0)) {  // coplanar throughout (flat motion): the start is a coplanar time
    roots[0] = 0.0;
    return 1;
  }
  const double tol = 1e-12 * scale;
  // Turning points: 3 k3 t² + 2 k2 t + k1 = 0.
  double cut[4] = {0.0, 0.0, 0.0, 1.0};
  int nc = 1;
  const double A = 3 * k3, B = 2 * k2, C = k1;
  if (std::abs(A) > 1e-300) {
    const double disc = B * B - 4 * A * C;
    if (disc >= 0.0) {
      const double sq = std::sqrt(disc);
      const double q = -0.5 * (B + std::copysign(sq, B));
      double r1 = q / A, r2 = q != 0.0 ? C / q : r1;
      if (r1 > r2) std::swap(r1, r2);
      if (r1 > 0.0 && r1 < 1.0) cut[nc++] = r1;
      if (r2 > 0.0 && r2 < 1.0 && r2 != r1) cut[nc++] = r2;
    }
  } else if (std::abs(B) > 1e-300) {
    const double r = -C / B;
    if (r > 0.0 && r < 1.0) cut[nc++] = r;
  }
  cut[nc++] = 1.0;
  int n = 0;
  auto push = [&](double t) {
    if (n > 0 && std::abs(roots[n - 1] - t) < 1e-12) return;
    if (n < 3) roots[n++] = t;
  };
  for (int k = 0; k + 1 < nc; ++k) {
    double lo = cut[k], hi = cut[k + 1];
    double flo = f(lo), fhi = f(hi);
    if (std::abs(flo) <= tol) {
      push(lo);
      continue;
    }
    if (std::abs(fhi) <= tol) {
      if (k + 2 == nc) push(hi);  // the next piece starts there and takes it otherwise
      continue;
    }
    if ((flo < 0.0) == (fhi < 0.0)) continue;
    for (int it = 0; it < 60 && hi - lo > 1e-13; ++it) {
      const double mid = 0.5 * (lo + hi), fm = f(mid);
      if ((fm < 0.0) == (flo < 0.0)) {
        lo = mid;
        flo = fm;
      } else {
        hi = mid;
      }
    }
    push(0.5 * (lo + hi));
  }
  return n;
}

inline Vec3 lerp(const Vec3& a, const Vec3& b, double t) { return a + t * (b - a); }

}  // namespace simreel::sim::detail::cg
