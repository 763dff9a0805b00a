// GJK with the signed-volume sub-algorithm (see gjk.hpp for the sources and conventions).
#include "collision/gjk.hpp"

#include <algorithm>
#include <cmath>

namespace simreel::sim::detail {

namespace {

// A simplex whose squared measure (length², area², volume²) is below kDegenerate times the
// product of its squared edge lengths is treated as one dimension lower: its barycentric
// coordinates would be mostly rounding error (sin² of the angle between edges < 1e-24).
constexpr double kDegenerate = 1e-24;

SimplexClosest vertex_only(const std::array<Vec3, 4>& w, int i) {
  SimplexClosest c;
  c.count = 1;
  c.index[0] = i;
  c.lambda[0] = 1.0;
  c.v = w[i];
  return c;
}

/// Keeps the better (closer to the origin) of two candidates; the first on a tie.
void keep_closer(SimplexClosest& best, const SimplexClosest& c, bool& have) {
  if (!have || c.v.squaredNorm() < best.v.squaredNorm()) {
    best = c;
    have = true;
  }
}

/// Segment i-j: the origin's projection t on the line, clamped to the ends.
SimplexClosest closest_segment(const std::array<Vec3, 4>& w, int i, int j) {
  const Vec3 e = w[j] - w[i];
  const double ee = e.squaredNorm();
  if (!(ee > kDegenerate * std::max(w[i].squaredNorm(), w[j].squaredNorm()))) {
    return w[j].squaredNorm() < w[i].squaredNorm() ? vertex_only(w, j) : vertex_only(w, i);
  }
  const double t = -w[i].dot(e) / ee;
  if (t <= 0.0) return vertex_only(w, i);
  if (t >= 1.0) return vertex_only(w, j);
  SimplexClosest c;
  c.count = 2;
  c.index = {std::min(i, j), std::max(i, j), 0, 0};
  c.lambda[0] = i < j ? 1.0 - t : t;
  c.lambda[1] = i < j ? t : 1.0 - t;
  c.v = w[i] + t * e;
  return c;
}

/// Triangle i-j-k: barycentric coordinates of the origin's projection p from the signed areas
/// n·((w_j - p) x (w_k - p)); only the edges facing a non-positive coordinate can hold the
/// closest point (Montanari et al. 2017, S2D).
SimplexClosest closest_triangle(const std::array<Vec3, 4>& w, int i, int j, int k) {
  const Vec3 e1 = w[j] - w[i], e2 = w[k] - w[i];
  const Vec3 n = e1.cross(e2);
  const double nn = n.squaredNorm();
  const bool degenerate = !(nn > kDegenerate * e1.squaredNorm() * e2.squaredNorm());
  SimplexClosest best;
  bool have = false;
  if (!degenerate) {
    const Vec3 p = (w[i].dot(n) / nn) * n;
    const double ai = n.dot((w[j] - p).cross(w[k] - p));
    const double aj = n.dot((w[k] - p).cross(w[i] - p));
    const double ak = n.dot((w[i] - p).cross(w[j] - p));
    if (ai > 0.0 && aj > 0.0 && ak > 0.0) {
      const double sum = ai + aj + ak;
      // Sort the three (index, weight) pairs by index so the kept order is canonical.
      std::array<std::pair<int, double>, 3> iw{{{i, ai / sum}, {j, aj / sum}, {k, ak / sum}}};
      std::sort(iw.begin(), iw.end());
      best.count = 3;
      for (int m = 0; m < 3; ++m) {
        best.index[m] = iw[m].first;
        best.lambda[m] = iw[m].second;
      }
      best.v = p;
      return best;
    }
    if (ai <= 0.0) keep_closer(best, closest_segment(w, j, k), have);
    if (aj <= 0.0) keep_closer(best, closest_segment(w, k, i), have);
    if (ak <= 0.0) keep_closer(best, closest_segment(w, i, j), have);
    return best;
  }
  keep_closer(best, closest_segment(w, j, k), have);
  keep_closer(best, closest_segment(w, k, i), have);
  keep_closer(best, closest_segment(w, i, j), have);
  return best;
}

/// Signed volume of the tetrahedron (a, b, c, d): (b - a)·((c - a) x (d - a)).
double volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a));
}

/// Tetrahedron 0-1-2-3: the origin's barycentric coordinates are the signed volumes with the
/// vertex replaced by the origin over the total; all of the total's sign means inside (S3D).
SimplexClosest closest_tetrahedron(const std::array<Vec3, 4>& w) {
  const Vec3 o = Vec3::Zero();
  const double V = volume(w[0], w[1], w[2], w[3]);
  const double scale2 = (w[1] - w[0]).squaredNorm() * (w[2] - w[0]).squaredNorm() *
                        (w[3] - w[0]).squaredNorm();
  const bool degenerate = !(V * V > kDegenerate * scale2);
  static constexpr std::array<std::array<int, 3>, 4> kOpposite{
      {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}}};
  std::array<double, 4> b{};
  if (!degenerate) {
    b = {volume(o, w[1], w[2], w[3]), volume(w[0], o, w[2], w[3]), volume(w[0], w[1], o, w[3]),
         volume(w[0], w[1], w[2], o)};
    if (b[0] * V > 0.0 && b[1] * V > 0.0 && b[2] * V > 0.0 && b[3] * V > 0.0) {
      SimplexClosest c;
      c.count = 4;
      const double sum = b[0] + b[1] + b[2] + b[3];
      for (int m = 0; m < 4; ++m) {
        c.index[m] = m;
        c.lambda[m] = b[m] / sum;
      }
      c.v = Vec3::Zero();
      return c;
    }
  }
  SimplexClosest best;
  bool have = false;
  for (int m = 0; m < 4; ++m) {
    if (degenerate || !(b[m] * V > 0.0)) {
      const auto& f = kOpposite[m];
      keep_closer(best, closest_triangle(w, f[0], f[1], f[2]), have);
    }
  }
  return best;
}

SimplexVertex make_vertex(const PosedShape& A, const PosedShape& B, const Vec3& dir,
                          ShapePart part) {
  const SupportPoint sa = A.support(dir, part);
  const SupportPoint sb = B.support(-dir, part);
  return {sa.world - sb.world, sa.world, sb.world, sa.local, sb.local};
}

/// Reduces the simplex to the vertices the closest point keeps (in index order) and returns
/// that point; `lambda` receives their weights.
Vec3 reduce(GjkSimplex& s, std::array<double, 4>& lambda) {
  std::array<Vec3, 4> w;
  for (int m = 0; m < s.count; ++m) w[m] = s.v[m].w;
  const SimplexClosest c = closest_on_simplex(w, s.count);
  GjkSimplex kept;
  kept.count = c.count;
  for (int m = 0; m < c.count; ++m) {
    kept.v[m] = s.v[c.index[m]];
    lambda[m] = c.lambda[m];
  }
  s = kept;
  return c.v;
}

}  // namespace

SimplexClosest closest_on_simplex(const std::array<Vec3, 4>& w, int count) {
  switch (count) {
    case 1:
      return vertex_only(w, 0);
    case 2:
      return closest_segment(w, 0, 1);
    case 3:
      return closest_triangle(w, 0, 1, 2);
    case 4:
      return closest_tetrahedron(w);
    default:
      return {};
  }
}

GjkResult gjk_distance(const PosedShape& A, const PosedShape& B, ShapePart part,
                       const GjkSimplex* warm, const GjkOptions& options) {
  GjkResult r;
  GjkSimplex& s = r.simplex;
  std::array<double, 4> lambda{1.0, 0.0, 0.0, 0.0};
  Vec3 v;
  if (warm != nullptr && warm->count > 0) {
    // Re-pose the cached local points: they are still points of the shapes, so the simplex is
    // still inside D and GJK stays correct however far the bodies moved.
    s.count = warm->count;
    for (int m = 0; m < s.count; ++m) {
      SimplexVertex& x = s.v[m];
      x.a_local = warm->v[m].a_local;
      x.b_local = warm->v[m].b_local;
      x.a = A.to_world(x.a_local);
      x.b = B.to_world(x.b_local);
      x.w = x.a - x.b;
    }
    v = reduce(s, lambda);
  } else {
    Vec3 dir = B.translation - A.translation;
    if (!(dir.squaredNorm() > 0.0)) dir = Vec3::UnitX();
    s.count = 1;
    s.v[0] = make_vertex(A, B, dir, part);
    v = s.v[0].w;
  }
  double vv = v.squaredNorm();
  const double max2 = options.max_distance * options.max_distance;
  r.status = GjkStatus::separated;
  double lower_bound = 0.0;
  int it = 0;
  while (true) {
    double wmax = 0.0;
    for (int m = 0; m < s.count; ++m) wmax = std::max(wmax, s.v[m].w.squaredNorm());
    if (s.count == 4 || vv <= options.overlap_tol * options.overlap_tol * wmax) {
      r.status = GjkStatus::overlap;
      break;
    }
    if (it >= options.max_iterations) break;
    ++it;
    const SimplexVertex x = make_vertex(A, B, -v, part);
    const double vw = v.dot(x.w);
    if (vw > 0.0 && vw * vw > max2 * vv) {  // lower bound v·w/|v| beyond max_distance
      r.status = GjkStatus::beyond;
      lower_bound = vw / std::sqrt(vv);
      break;
    }
    if (vv - vw <= options.rel_tol * vv) break;  // w brings no closer point: converged
    bool repeated = false;
    for (int m = 0; m < s.count; ++m) repeated = repeated || s.v[m].w == x.w;
    if (repeated) break;  // cycling on a vertex already held (rounding): as close as it gets
    GjkSimplex next = s;
    next.v[next.count++] = x;
    std::array<double, 4> next_lambda{};
    const Vec3 next_v = reduce(next, next_lambda);
    const double next_vv = next_v.squaredNorm();
    // |v| must shrink strictly every iteration (GJK's convergence proof); if rounding stops it,
    // the previous simplex is the answer. A full tetrahedron means the origin is inside.
    if (next.count < 4 && !(next_vv < vv)) break;
    s = next;
    lambda = next_lambda;
    v = next_v;
    vv = next_vv;
  }
  r.iterations = it;
  r.point_a = Vec3::Zero();
  r.point_b = Vec3::Zero();
  for (int m = 0; m < s.count; ++m) {
    r.point_a += lambda[m] * s.v[m].a;
    r.point_b += lambda[m] * s.v[m].b;
  }
  if (r.status == GjkStatus::overlap) {
    r.distance = 0.0;
    r.normal = Vec3::UnitZ();
    return r;
  }
  const double dist = std::sqrt(vv);
  r.normal = -v / dist;
  r.distance = dist;
  if (r.status == GjkStatus::beyond) {
    r.distance = lower_bound;  // the certified lower bound, not the current (larger) |v|
  }
  return r;
}

}  // namespace simreel::sim::detail
