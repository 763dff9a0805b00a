// Convex against a plane: candidate features below the plane, reduced to 4 (plane_manifold.hpp).
#include "collision/plane_manifold.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace simreel::sim::detail {
namespace {

constexpr int kMaxCandidates = 64;  // hulls with more vertices give their 64 first (documented)

struct Candidate {
  Vec3 point;  ///< world, on B's surface
  double separation;
  std::uint32_t id;
};

/// Is p (on the triangle's plane, world) inside triangle t grown by `grow` (m)?
bool inside_triangle(const Vec3* t, const Vec3& n, const Vec3& p, double grow) {
  for (int k = 0; k < 3; ++k) {
    const Vec3 e = t[(k + 1) % 3] - t[k];
    const Vec3 out = e.cross(n);  // outward edge normal for a counter-clockwise triangle about n
    const double len = out.norm();
    if (!(len > 0.0)) return false;
    if ((p - t[k]).dot(out) / len > grow) return false;
  }
  return true;
}

/// Signed area of (a, b, c) about n (twice the area).
double area(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n) {
  return (b - a).cross(c - a).dot(n);
}

}  // namespace

Manifold collide_plane(const Vec3& point, const Vec3& normal, const PosedShape& B, double margin,
                       const Vec3* triangle) {
  std::array<Candidate, kMaxCandidates> cand;
  int n = 0;
  const double r = B.core_radius();
  auto add = [&](const Vec3& core_world, std::uint32_t id) {
    if (n == kMaxCandidates) return;
    const Vec3 p = core_world - r * normal;  // the rounded shapes' lowest point
    const double s = (p - point).dot(normal);
    if (s > margin) return;
    cand[n++] = {p, s, id};
  };
  const ConvexShape& s = B.shape;
  switch (s.kind) {
    case ConvexKind::sphere:
      add(B.translation, 0);
      break;
    case ConvexKind::capsule:
      add(B.to_world(Vec3(0.0, 0.0, -s.half_height)), 0);
      add(B.to_world(Vec3(0.0, 0.0, s.half_height)), 1);
      break;
    case ConvexKind::box:
      for (std::uint32_t k = 0; k < 8; ++k)
        add(B.to_world(Vec3((k & 1) ? s.half_extents.x() : -s.half_extents.x(),
                            (k & 2) ? s.half_extents.y() : -s.half_extents.y(),
                            (k & 4) ? s.half_extents.z() : -s.half_extents.z())),
            k);
      break;
    case ConvexKind::cylinder: {
      // Rim points in the direction of steepest descent across each cap and at 90° steps from it,
      // so a tilted cylinder's lowest rim point is always a candidate.
      const Vec3 down = B.rotation.transpose() * -normal;
      Vec3 d(down.x(), down.y(), 0.0);
      d = d.norm() > 1e-9 ? Vec3(d.normalized()) : Vec3(Vec3::UnitX());
      const Vec3 e = Vec3::UnitZ().cross(d);
      for (std::uint32_t cap = 0; cap < 2; ++cap) {
        const double z = cap == 0 ? -s.half_height : s.half_height;
        const Vec3 dirs[4] = {d, e, -d, -e};
        for (std::uint32_t k = 0; k < 4; ++k)
          add(B.to_world(Vec3(0.0, 0.0, z) + s.radius * dirs[k]), cap * 4 + k);
      }
      break;
    }
    case ConvexKind::hull:
      for (std::size_t k = 0; k < s.vertices.size(); ++k) add(B.to_world(s.vertices[k]), std::uint32_t(k));
      break;
  }
  if (triangle) {
    int kept = 0;
    for (int i = 0; i < n; ++i) {
      const Vec3 on_plane = cand[i].point - cand[i].separation * normal;
      if (inside_triangle(triangle, normal, on_plane, margin)) cand[kept++] = cand[i];
    }
    n = kept;
  }
  // A candidate less than twice as far across from a deeper one as it is above it is dropped:
  // it cannot reach the plane before the body turns by atan ½ (27°) about the deeper one, and the
  // reduction below, which measures spread on the plane, cannot tell it from the one under it.
  // A card 0.4 mm thick lying on the ground has all 8 corners within the 1 mm margin of a resting
  // pair; its manifold kept top corners (speculative: they let it approach) in place of bottom
  // ones, and it sank at 0.5 mm/s until its top face was level with the ground; a cylinder of
  // 1 mm diameter on its side kept its rim points level with its axis and sank to its axis.
  // Such points lie within the margin of the deeper one, so the support lost spans a few mm.
  {
    std::array<bool, kMaxCandidates> hidden{};
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n && !hidden[i]; ++j) {
        const double rise = cand[i].separation - cand[j].separation;
        if (!(rise > 0.0)) continue;
        const Vec3 d = cand[i].point - cand[j].point;
        hidden[i] = (d - d.dot(normal) * normal).squaredNorm() <= 4.0 * rise * rise;
      }
    int kept = 0;
    for (int i = 0; i < n; ++i)
      if (!hidden[i]) cand[kept++] = cand[i];
    n = kept;
  }
  Manifold m;
  m.normal = normal;
  if (n == 0) return m;
  // Reduce to at most 4: the deepest, the farthest from it, the one spanning the largest
  // triangle with those, the one farthest outside that triangle (Box2D/Bullet's rule).
  std::array<int, 4> pick{0, -1, -1, -1};
  int count = n;
  if (n > 4) {
    for (int i = 1; i < n; ++i)
      if (cand[i].separation < cand[pick[0]].separation) pick[0] = i;
    const Vec3& p0 = cand[pick[0]].point;
    double best = -1.0;
    for (int i = 0; i < n; ++i)
      if (const double d = (cand[i].point - p0).squaredNorm(); d > best) best = d, pick[1] = i;
    const Vec3& p1 = cand[pick[1]].point;
    best = -1.0;
    for (int i = 0; i < n; ++i)
      if (const double a = std::abs(area(p0, p1, cand[i].point, normal)); a > best)
        best = a, pick[2] = i;
    const Vec3& p2 = cand[pick[2]].point;
    const double sign = area(p0, p1, p2, normal) >= 0.0 ? 1.0 : -1.0;
    best = 0.0;
    for (int i = 0; i < n; ++i) {
      const Vec3& q = cand[i].point;
      const double inside = std::min({sign * area(p0, p1, q, normal), sign * area(p1, p2, q, normal),
                                      sign * area(p2, p0, q, normal)});
      if (-inside > best) best = -inside, pick[3] = i;
    }
    count = pick[3] < 0 ? 3 : 4;
    // Keep candidate order (deterministic and stable from step to step).
    std::sort(pick.begin(), pick.begin() + count);
  } else {
    for (int i = 0; i < n; ++i) pick[i] = i;
  }
  for (int k = 0; k < count; ++k) {
    const Candidate& c = cand[pick[k]];
    ManifoldPoint& p = m.points[k];
    p.point_b = c.point;
    p.point_a = c.point - c.separation * normal;
    p.separation = c.separation;
    p.id = {FeatureType::face, s.kind == ConvexKind::sphere ? FeatureType::shape : FeatureType::vertex,
            0, c.id};
  }
  m.count = count;
  return m;
}

}  // namespace simreel::sim::detail
