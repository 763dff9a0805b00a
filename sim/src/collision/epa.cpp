// EPA over fixed-capacity buffers (see epa.hpp for the sources and conventions).
#include "collision/epa.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace simreel::sim::detail {

namespace {

// A point counts as off the affine hull of the vertices so far when it is farther than this
// fraction of D's size: below it, a tetrahedron would be too thin for its face normals to mean
// anything.
constexpr double kAffineTol = 1e-10;

struct Vertex {
  Vec3 w = Vec3::Zero();  // w = a - b, world
  Vec3 a = Vec3::Zero();
  Vec3 b = Vec3::Zero();
};

struct Face {
  std::array<int, 3> v{};  // counter-clockwise seen from outside
  Vec3 n = Vec3::Zero();   // unit outward normal
  double dist = 0.0;       // n · w[v0]: signed distance of the face's plane from the origin
};

struct Polytope {
  std::array<Vertex, kEpaMaxVertices> vert;
  std::array<Face, kEpaMaxFaces> face;
  int nv = 0;
  int nf = 0;
  double scale = 0.0;  // largest |w| of the start simplex (m): what tolerances are relative to

  /// The face holding the directed edge a -> b, or -1.
  [[nodiscard]] int twin(int a, int b) const {
    for (int f = 0; f < nf; ++f) {
      const auto& v = face[f].v;
      if ((v[0] == a && v[1] == b) || (v[1] == a && v[2] == b) || (v[2] == a && v[0] == b)) {
        return f;
      }
    }
    return -1;
  }

  /// The face through vertices i, j, k (outward when i, j, k is counter-clockwise from outside).
  /// False when its normal is undefined (a sliver).
  [[nodiscard]] bool make_face(int i, int j, int k, Face& f) const {
    const Vec3 n = (vert[j].w - vert[i].w).cross(vert[k].w - vert[i].w);
    const double len = n.norm();
    if (!(len > 1e-24 * scale * scale)) return false;
    f.v = {i, j, k};
    f.n = n / len;
    f.dist = f.n.dot(vert[i].w);
    return true;
  }
};

Vertex support_vertex(const PosedShape& A, const PosedShape& B, const Vec3& dir, ShapePart part) {
  const Vec3 a = A.support(dir, part).world;
  const Vec3 b = B.support(-dir, part).world;
  return {a - b, a, b};
}

/// Distance of p from the affine hull of the first `count` (affinely independent) points.
double off_hull(const std::array<Vertex, 4>& s, int count, const Vec3& p) {
  const Vec3 d = p - s[0].w;
  if (count == 1) return d.norm();
  const Vec3 e = s[1].w - s[0].w;
  if (count == 2) return d.cross(e).norm() / e.norm();
  const Vec3 n = e.cross(s[2].w - s[0].w);
  return std::abs(n.dot(d)) / n.norm();
}

/// Directions in which a support point is most likely to leave the current affine hull.
int growth_directions(const std::array<Vertex, 4>& s, int count, std::array<Vec3, 6>& dirs) {
  if (count == 1) {
    dirs = {Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitY(), Vec3::UnitZ(),
            -Vec3::UnitZ()};
    return 6;
  }
  if (count == 2) {
    const Vec3 e = (s[1].w - s[0].w).normalized();
    int k = 0;  // the axis least aligned with the segment gives a well-conditioned perpendicular
    e.cwiseAbs().minCoeff(&k);
    const Vec3 d1 = e.cross(Vec3::Unit(k)).normalized();
    const Vec3 d2 = e.cross(d1);
    dirs = {d1, -d1, d2, -d2, (d1 + d2).normalized(), -(d1 + d2).normalized()};
    return 6;
  }
  const Vec3 n = (s[1].w - s[0].w).cross(s[2].w - s[0].w).normalized();
  dirs[0] = n;
  dirs[1] = -n;
  return 2;
}

/// D has no volume (a point, segment or polygon through the origin; e.g. the cores of two
/// spheres, or two coplanar flat hulls): depth 0 in the flat's own dimensions. The normal is
/// the polygon's normal, or the direction perpendicular to the segment nearest the centre
/// difference, or the centre difference itself; its sign is chosen to point from A's origin
/// towards B's. The witness points are the simplex's point nearest the origin.
EpaResult flat_result(const PosedShape& A, const PosedShape& B, const std::array<Vertex, 4>& s,
                      int count, int iterations) {
  EpaResult r;
  r.status = EpaStatus::flat;
  r.iterations = iterations;
  const Vec3 hint = B.translation - A.translation;
  Vec3 n = hint;
  if (count == 3) {
    n = (s[1].w - s[0].w).cross(s[2].w - s[0].w);
  } else if (count == 2) {
    const Vec3 e = (s[1].w - s[0].w).normalized();
    n = hint - hint.dot(e) * e;
    if (!(n.squaredNorm() > 1e-24 * hint.squaredNorm()) || !(n.squaredNorm() > 0.0)) {
      std::array<Vec3, 6> dirs;
      growth_directions(s, count, dirs);
      n = dirs[0];
    }
  }
  r.normal = n.squaredNorm() > 0.0 ? Vec3(n.normalized()) : Vec3(Vec3::UnitZ());
  if (r.normal.dot(hint) < 0.0) r.normal = -r.normal;
  std::array<Vec3, 4> w;
  for (int m = 0; m < count; ++m) w[m] = s[m].w;
  const SimplexClosest c = closest_on_simplex(w, count);
  for (int m = 0; m < c.count; ++m) {
    r.point_a += c.lambda[m] * s[c.index[m]].a;
    r.point_b += c.lambda[m] * s[c.index[m]].b;
  }
  return r;
}

}  // namespace

EpaResult epa_penetration(const PosedShape& A, const PosedShape& B, const GjkSimplex& start,
                          ShapePart part, const EpaOptions& options) {
  EpaResult r;
  // 1. An affinely independent subset of the GJK simplex, then support points off its hull
  //    until it is a tetrahedron (a GJK that stopped on a point, segment or triangle through
  //    the origin leaves fewer than four).
  std::array<Vertex, 4> s;
  int count = 0;
  double scale = 0.0;
  for (int m = 0; m < start.count; ++m) scale = std::max(scale, start.v[m].w.norm());
  for (int m = 0; m < start.count; ++m) {
    const Vertex x{start.v[m].w, start.v[m].a, start.v[m].b};
    if (count == 0 || off_hull(s, count, x.w) > kAffineTol * scale) s[count++] = x;
  }
  int it = 0;
  while (count < 4) {
    if (count == 0) {  // no start (a caller's error): any point of D
      s[count++] = support_vertex(A, B, Vec3::UnitX(), part);
      ++it;
      scale = std::max(scale, s[0].w.norm());
      continue;
    }
    std::array<Vec3, 6> dirs;
    const int nd = growth_directions(s, count, dirs);
    Vertex best{};
    double best_off = -1.0;
    for (int m = 0; m < nd; ++m) {
      const Vertex x = support_vertex(A, B, dirs[m], part);
      ++it;
      scale = std::max(scale, x.w.norm());
      const double off = off_hull(s, count, x.w);
      if (off > best_off) {
        best_off = off;
        best = x;
      }
    }
    if (!(best_off > kAffineTol * scale)) return flat_result(A, B, s, count, it);
    s[count++] = best;
  }

  // 2. The tetrahedron as a polytope with outward faces.
  Polytope P;
  P.scale = std::max(scale, 1e-300);
  for (int m = 0; m < 4; ++m) P.vert[m] = s[m];
  P.nv = 4;
  static constexpr std::array<std::array<int, 4>, 4> kFaces{
      {{0, 1, 2, 3}, {0, 3, 1, 2}, {0, 2, 3, 1}, {1, 3, 2, 0}}};  // three corners + the opposite
  for (const auto& f : kFaces) {
    int i = f[0], j = f[1], k = f[2];
    const Vec3 n = (P.vert[j].w - P.vert[i].w).cross(P.vert[k].w - P.vert[i].w);
    if (n.dot(P.vert[f[3]].w - P.vert[i].w) > 0.0) std::swap(j, k);
    Face face;
    if (!P.make_face(i, j, k, face)) return flat_result(A, B, s, 3, it);  // unreachable

    P.face[P.nf++] = face;
  }

  // 3. Expand.
  const double tol = options.rel_tol * P.scale;
  const int max_it = std::min(options.max_iterations, kEpaMaxVertices - 4) + it;
  r.status = EpaStatus::limit;
  Face chosen;  // the answer: the closest face of the last sound polytope
  bool have_chosen = false;
  std::array<bool, kEpaMaxFaces> visible{};
  std::array<bool, kEpaMaxFaces> visited{};
  std::array<int, kEpaMaxFaces> stack{};
  std::array<std::array<int, 2>, kEpaMaxFaces> horizon{};
  std::array<Face, kEpaMaxFaces> fresh{};
  while (true) {
    int best = 0;
    for (int f = 1; f < P.nf; ++f) {
      if (P.face[f].dist < P.face[best].dist) best = f;
    }
    // Expanding a convex polytope that holds the origin never brings a face closer; if rounding
    // made it non-convex and one did, the previous closest face is the sound answer.
    if (have_chosen && P.face[best].dist < chosen.dist - tol) break;
    chosen = P.face[best];
    have_chosen = true;
    if (it >= max_it) break;
    const Face& closest = P.face[best];
    const Vertex x = support_vertex(A, B, closest.n, part);
    ++it;
    if (closest.n.dot(x.w) - closest.dist <= tol) {
      r.status = EpaStatus::converged;
      break;
    }
    if (P.nv >= kEpaMaxVertices) break;
    const int xi = P.nv;
    // The faces x sees, grown from the closest face across shared edges (van den Bergen's
    // silhouette walk): on a curved D, x is nearly coplanar with faces far away, and testing
    // every face alone can mark a scattered set whose "horizon" is not one loop, which breaks
    // the polytope. The edges where the walk stops are the horizon.
    std::fill_n(visible.begin(), P.nf, false);
    std::fill_n(visited.begin(), P.nf, false);
    int nvis = 1, nh = 0, top = 0;
    visible[best] = visited[best] = true;
    stack[top++] = best;
    bool overflow = false;
    while (top > 0 && !overflow) {
      const int f = stack[--top];
      for (int e = 0; e < 3; ++e) {
        const int a = P.face[f].v[e], b = P.face[f].v[(e + 1) % 3];
        const int g = P.twin(b, a);
        if (g >= 0 && visible[g]) continue;
        if (g >= 0 && !visited[g]) {
          visited[g] = true;
          if (P.face[g].n.dot(x.w - P.vert[P.face[g].v[0]].w) > 0.0) {
            visible[g] = true;
            ++nvis;
            stack[top++] = g;
            continue;
          }
        }
        if (nh >= kEpaMaxFaces) {
          overflow = true;
          break;
        }
        horizon[nh++] = {a, b};
      }
    }
    if (overflow) break;
    if (P.nf - nvis + nh > kEpaMaxFaces) break;
    P.vert[xi] = x;
    bool ok = true;
    for (int h = 0; h < nh && ok; ++h) ok = P.make_face(horizon[h][0], horizon[h][1], xi, fresh[h]);
    if (!ok) break;  // a sliver: keep the polytope as it was and report its best face
    ++P.nv;
    int nf = 0;
    for (int f = 0; f < P.nf; ++f) {
      if (!visible[f]) P.face[nf++] = P.face[f];
    }
    for (int h = 0; h < nh; ++h) P.face[nf++] = fresh[h];
    P.nf = nf;
  }

  // 4. Witness points: barycentric coordinates of the origin's projection on the closest face.
  const Face& f = chosen;
  const Vertex& v0 = P.vert[f.v[0]];
  const Vertex& v1 = P.vert[f.v[1]];
  const Vertex& v2 = P.vert[f.v[2]];
  const Vec3 p = f.dist * f.n;
  const double l0 = f.n.dot((v1.w - p).cross(v2.w - p));
  const double l1 = f.n.dot((v2.w - p).cross(v0.w - p));
  const double l2 = f.n.dot((v0.w - p).cross(v1.w - p));
  const double sum = l0 + l1 + l2;
  r.iterations = it;
  r.depth = std::max(0.0, f.dist);
  r.normal = f.n;
  if (sum > 0.0) {
    r.point_a = (l0 * v0.a + l1 * v1.a + l2 * v2.a) / sum;
    r.point_b = (l0 * v0.b + l1 * v1.b + l2 * v2.b) / sum;
  } else {
    r.point_a = v0.a;
    r.point_b = v0.b;
  }
  return r;
}

}  // namespace simreel::sim::detail
