// Resting-contact features of a sphere against a collider's surface (Coutinho §3.6.3): the
// closest face, edge or vertex within a margin, for the particle solve's one-body constraints.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "collision/sweep.hpp"

namespace simreel::sim::detail {

namespace {

/// Closest point of triangle t to p (Ericson, Real-Time Collision Detection §5.1.5: Voronoi
/// regions of the vertices, edges and face).
Vec3 closest_on_triangle(const Triangle& t, const Vec3& p) {
  const Vec3 ab = t.b - t.a, ac = t.c - t.a, ap = p - t.a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return t.a;
  const Vec3 bp = p - t.b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return t.b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return t.a + (d1 / (d1 - d3)) * ab;
  const Vec3 cp = p - t.c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return t.c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return t.a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0)
    return t.b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (t.c - t.b);
  const double denom = 1.0 / (va + vb + vc);
  return t.a + ab * (vb * denom) + ac * (vc * denom);
}

/// Adds (n, gap) to out[0, count) kept sorted by gap, unless a contact with nearly the same
/// normal is there (then the nearer one stays).
void add_surface_contact(const Vec3& n, double gap, SurfaceContact* out, int& count, int max_out) {
  for (int k = 0; k < count; ++k) {
    if (out[k].normal.dot(n) > 0.999) {
      if (gap < out[k].gap) {
        for (int j = k; j + 1 < count; ++j) out[j] = out[j + 1];
        --count;
        break;
      }
      return;
    }
  }
  int at = count;
  while (at > 0 && out[at - 1].gap > gap) --at;
  if (at >= max_out) return;
  if (count == max_out) --count;
  for (int j = count; j > at; --j) out[j] = out[j - 1];
  out[at] = SurfaceContact{n, gap};
  ++count;
}

}  // namespace

int surface_contacts(const Collider& c, const Vec3& p, double r, double margin,
                     SurfaceContact* out, int max_out) {
  if (max_out <= 0) return 0;
  if (c.shape == Collider::Shape::plane) {
    const double gap = c.normal.dot(p - c.point) - r;
    if (!(gap < margin)) return 0;
    out[0] = SurfaceContact{c.normal, gap};
    return 1;
  }
  const double reach = r + margin;
  if (((p - c.aabb_center).cwiseAbs().array() > (c.aabb_half.array() + reach)).any()) return 0;
  const Vec3 l = c.R.transpose() * (p - c.center);
  Vec3 ln;
  double dist;  // centre to surface, negative inside (boxes only)
  switch (c.shape) {
    case Collider::Shape::sphere: {
      const double d = l.norm();
      if (!(d >= c.radius)) return 0;
      ln = l / d;
      dist = d - c.radius;
      break;
    }
    case Collider::Shape::box: {
      const Vec3 q = l.cwiseMax(-c.half_extents).cwiseMin(c.half_extents);
      const Vec3 off = l - q;
      const double d = off.norm();
      if (d > 0.0) {
        ln = off / d;
        dist = d;
      } else {
        const Vec3 depth = c.half_extents - l.cwiseAbs();
        int k = 0;
        dist = -depth.minCoeff(&k);
        ln = Vec3::Zero();
        ln[k] = l[k] >= 0.0 ? 1.0 : -1.0;
      }
      break;
    }
    case Collider::Shape::cylinder: {
      const double rho = l.head<2>().norm();
      const double dr = rho - c.radius, dz = std::abs(l.z()) - c.half_height;
      const double sz = l.z() >= 0.0 ? 1.0 : -1.0;
      if (dr > 0.0 && dz > 0.0) {  // nearest the rim
        const Vec3 q(c.radius * l.x() / rho, c.radius * l.y() / rho, sz * c.half_height);
        const Vec3 off = l - q;
        dist = off.norm();
        ln = off / dist;
      } else if (dr > 0.0) {
        ln = Vec3(l.x() / rho, l.y() / rho, 0.0);
        dist = dr;
      } else if (dz > 0.0) {
        ln = Vec3(0.0, 0.0, sz);
        dist = dz;
      } else {
        return 0;
      }
      break;
    }
    case Collider::Shape::capsule: {
      const Vec3 off = l - Vec3(0.0, 0.0, std::clamp(l.z(), -c.half_height, c.half_height));
      const double d = off.norm();
      if (!(d >= c.radius)) return 0;
      ln = off / d;
      dist = d - c.radius;
      break;
    }
    case Collider::Shape::mesh: {
      const MeshShape& m = *c.mesh;
      int count = 0;
      const auto near = [&](std::uint32_t t) {
        const Vec3 off = l - closest_on_triangle(m.triangles[t], l);
        const double d = off.norm();
        if (!(d > 0.0) || !(d - r < margin)) return;
        add_surface_contact(Vec3(c.R * (off / d)), d - r, out, count, max_out);
      };
      // The grid first (§2.3.1): a particle inside a bowl or above a floor lies in empty cells,
      // where the tree would descend through the large boxes that hold it. Both hand out the
      // triangles in the tree's order; the tree adds leaf-mates whose boxes miss the query box,
      // which lie farther than `reach` and add nothing.
      const Vec3 lo = l - Vec3::Constant(reach), hi = l + Vec3::Constant(reach);
      if (!m.grid.query(lo, hi, [&](const SweepTriangle&, std::uint32_t t) { near(t); }))
        m.bvh.query(lo, hi, near);
      return count;
    }
    default: return 0;
  }
  const double gap = dist - r;
  if (!(gap < margin)) return 0;
  out[0] = SurfaceContact{Vec3(c.R * ln), gap};
  return 1;
}
}  // namespace simreel::sim::detail
