// Swept spheres against colliders (Coutinho §3.4, App. A): the first contact of a particle's
// step with a plane, box, sphere, cylinder, capsule or triangle mesh, in the collider's frame.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "collision/narrow_phase.hpp"
#include "collision/sweep.hpp"

namespace simreel::sim::detail {

namespace {

constexpr double kSkin = np::kSkin;  // (m) penetration a sweep ignores (rounding, not motion)

/// Sphere of radius r moving a -> b against the plane offset by r (closed form, Coutinho §3.4
/// with App. A's segment–plane intersection). A start point already below counts as a contact
/// at s = 0 if the particle keeps going down; it is put back on the surface.
void sweep_plane(const Collider& c, const Vec3& a, const Vec3& b, double r, Hit& best) {
  const double d0 = c.normal.dot(a - c.point) - r;
  const double d1 = c.normal.dot(b - c.point) - r;
  if (!(d1 < -kSkin && d1 < d0)) return;
  const double s = d0 > 0.0 ? d0 / (d0 - d1) : 0.0;
  if (!(s < best.s)) return;
  Vec3 p = a + s * (b - a);
  p -= (c.normal.dot(p - c.point) - r) * c.normal;
  best = Hit{s, c.normal, p, &c};
}

/// Sphere moving a -> b against the box expanded by r (slab test in the box frame; the
/// expanded box has square edges, so contacts near edges are found up to r (sqrt 2 - 1) early,
/// never late). A start point inside by more than surface_tol is left to push_out.
void sweep_box(const Collider& c, const Vec3& a, const Vec3& b, double r, Hit& best) {
  const Mat3 Rt = c.R.transpose();
  const Vec3 la = Rt * (a - c.center);
  const Vec3 d = Rt * (b - a);
  const Vec3 E = c.half_extents + Vec3::Constant(r);
  double tmin = -std::numeric_limits<double>::infinity();
  double tmax = std::numeric_limits<double>::infinity();
  int axis = -1;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0.0) {
      if (std::abs(la[k]) > E[k]) return;
      continue;
    }
    double t1 = (-E[k] - la[k]) / d[k];
    double t2 = (E[k] - la[k]) / d[k];
    if (t1 > t2) std::swap(t1, t2);
    if (t1 > tmin) {
      tmin = t1;
      axis = k;
    }
    tmax = std::min(tmax, t2);
    if (tmin > tmax) return;
  }
  if (axis < 0 || tmin > 1.0 || tmax < 0.0) return;
  if (tmin < 0.0) {
    if (-tmin * std::abs(d[axis]) > surface_tol(a)) return;  // deep inside at the start
    tmin = 0.0;
  }
  if (!(tmin < best.s)) return;
  const double sign = d[axis] > 0.0 ? -1.0 : 1.0;
  // Moving along the face (or ending within the skin of it): not a contact. Depth is linear
  // along the segment, so the end point's is the deepest.
  if (!(E[axis] - sign * (la[axis] + d[axis]) > kSkin)) return;
  Vec3 lp = la + tmin * d;
  lp[axis] = sign * E[axis];
  best = Hit{tmin, Vec3(sign * c.R.col(axis)), Vec3(c.center + c.R * lp), &c};
}

/// The swept segment in a solid's frame: from a — taken in the body's start-of-step pose on the
/// first sweep of the step, so the segment follows the relative motion of a kinematic body, and
/// in its end pose for the remainder after a contact — to b in the end pose (§2.1, §3.4).
void local_segment(const Collider& c, const Vec3& a, const Vec3& b, bool first, Vec3& la, Vec3& ld) {
  if (c.unposed) {
    la = a;
    ld = b - a;
    return;
  }
  la = first ? Vec3(c.prev_R.transpose() * (a - c.prev_center)) : Vec3(c.R.transpose() * (a - c.center));
  ld = c.R.transpose() * (b - c.center) - la;
}

/// Sphere moving a -> b against the collider sphere grown by r: closed-form ray–sphere. A start
/// point between the sphere and the grown sphere moving in is a contact at s = 0; one inside the
/// sphere itself is left to the §3.4.2 removal.
void sweep_sphere(const Collider& c, const Vec3& a, const Vec3& b, double r, bool first,
                  Hit& best) {
  Vec3 m, d;
  local_segment(c, a, b, first, m, d);
  const double Rg = c.radius + r;
  const double A = d.squaredNorm(), B = m.dot(d), C = m.squaredNorm() - Rg * Rg;
  if (C <= 0.0 && m.norm() < c.radius) return;  // inside the sphere itself: §3.4.2 removal
  double s;
  if (!np::first_entry(A, B, C, Rg, s)) return;
  if (!(s < best.s)) return;
  const Vec3 n = c.R * (m + s * d).normalized();
  best = Hit{s, n, Vec3(c.center + Rg * n), &c};
}

/// Sphere moving a -> b against the capped cylinder grown by r with square rims (radius R + r,
/// half height H + r): the entry time is the later of the entries into the infinite cylinder
/// (closed-form quadratic) and the slab |z| <= H + r, in the cylinder's frame.
void sweep_cylinder(const Collider& c, const Vec3& a, const Vec3& b, double r, bool first,
                    Hit& best) {
  Vec3 la, ld;
  local_segment(c, a, b, first, la, ld);
  const double Rg = c.radius + r, Hg = c.half_height + r;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double t0 = -kInf, t1 = kInf;
  const double A = ld.head<2>().squaredNorm(), B = la.head<2>().dot(ld.head<2>()),
               C = la.head<2>().squaredNorm() - Rg * Rg;
  if (A == 0.0) {
    if (C > 0.0) return;
  } else {
    const double disc = B * B - A * C;
    if (disc < 0.0) return;
    t0 = (-B - std::sqrt(disc)) / A;
    t1 = (-B + std::sqrt(disc)) / A;
  }
  double z0 = -kInf, z1 = kInf;
  if (ld.z() == 0.0) {
    if (std::abs(la.z()) > Hg) return;
  } else {
    z0 = (-Hg - la.z()) / ld.z();
    z1 = (Hg - la.z()) / ld.z();
    if (z0 > z1) std::swap(z0, z1);
  }
  const double enter = std::max(t0, z0), exit = std::min(t1, z1);
  if (enter > exit || exit < 0.0 || enter > 1.0) return;
  bool side = t0 >= z0;
  double s = enter;
  if (enter < 0.0) {  // the start point is inside the grown cylinder
    const double rho = la.head<2>().norm();
    if (rho < c.radius && std::abs(la.z()) < c.half_height) return;  // inside: removal
    side = Rg - rho < Hg - std::abs(la.z());
    s = 0.0;
    // It must go deeper than the skin past the surface it starts on: not along the top face
    // (depth linear in s) nor off the round side along its tangent (least |.|² at -B / A).
    if (side) {
      const double t = A > 0.0 ? std::min(1.0, std::max(0.0, -B / A)) : 1.0;
      if (!(C + t * (2.0 * B + A * t) < -2.0 * Rg * kSkin)) return;
    } else {
      const double zs = la.z() >= 0.0 ? 1.0 : -1.0;
      if (!(Hg - zs * (la.z() + ld.z()) > kSkin)) return;
    }
  }
  if (!(s < best.s)) return;
  Vec3 lp = la + s * ld;
  Vec3 ln;
  if (side) {
    const double rho = lp.head<2>().norm();
    if (!(rho > 0.0)) return;
    ln = Vec3(lp.x() / rho, lp.y() / rho, 0.0);
    lp.head<2>() = ln.head<2>() * Rg;
  } else {
    ln = Vec3(0.0, 0.0, lp.z() >= 0.0 ? 1.0 : -1.0);
    lp.z() = ln.z() * Hg;
  }
  if (!(ln.dot(ld) < 0.0)) return;  // moving out along the contact normal
  best = Hit{s, Vec3(c.R * ln), Vec3(c.center + c.R * lp), &c};
}

/// Sphere moving a -> b against the capsule (segment from -H to +H along local z grown by the
/// radius R) grown by r: the exact union of the infinite cylinder of radius R + r about the
/// segment's line, clipped to |z| <= H, and the two end spheres of radius R + r. The first entry
/// into the union is the earliest of the first entries into the clipped cylinder (closed-form
/// quadratic; an entry point beyond the segment's ends lies inside an end sphere, which is entered
/// no later) and into the end spheres (ray–sphere, as sweep_sphere). A start point between the
/// capsule and the grown capsule moving in is a contact at s = 0; one inside the capsule itself
/// is left to the §3.4.2 removal.
void sweep_capsule(const Collider& c, const Vec3& a, const Vec3& b, double r, bool first,
                   Hit& best) {
  Vec3 m, d;
  local_segment(c, a, b, first, m, d);
  const double H = c.half_height, Rg = c.radius + r;
  if ((m - Vec3(0.0, 0.0, std::clamp(m.z(), -H, H))).squaredNorm() < c.radius * c.radius)
    return;  // inside the capsule itself: §3.4.2 removal
  double s_best = std::numeric_limits<double>::infinity();
  Vec3 axis_point = Vec3::Zero();  // the segment point the contact normal leaves from
  double s;
  if (np::first_entry(d.head<2>().squaredNorm(), m.head<2>().dot(d.head<2>()),
                      m.head<2>().squaredNorm() - Rg * Rg, Rg, s) &&
      std::abs(m.z() + s * d.z()) <= H) {
    s_best = s;
    axis_point = Vec3(0.0, 0.0, m.z() + s * d.z());
  }
  for (const double z : {-H, H}) {
    const Vec3 e(0.0, 0.0, z);
    const Vec3 me = m - e;
    if (np::first_entry(d.squaredNorm(), me.dot(d), me.squaredNorm() - Rg * Rg, Rg, s) &&
        s < s_best) {
      s_best = s;
      axis_point = e;
    }
  }
  if (!(s_best < best.s)) return;
  const Vec3 off = m + s_best * d - axis_point;
  const double len = off.norm();
  if (!(len > 0.0)) return;
  const Vec3 ln = off / len;
  best = Hit{s_best, Vec3(c.R * ln), Vec3(c.center + c.R * (axis_point + Rg * ln)), &c};
}

/// Sphere moving a -> b against a triangle mesh: the segment goes into the mesh frame (§2.1), the
/// mesh's grid (§2.3.1; for a long segment the AABB tree, §2.2) gives the triangles near the
/// segment's box grown by r, and each is swept exactly (narrow_phase.hpp, §3.7), in the tree's
/// order either way (the grid hands out only triangles whose own box overlaps; one that does
/// not cannot be touched, so the first hit is the same).
void sweep_mesh(const Collider& c, const Vec3& a, const Vec3& b, double r, bool first,
                Hit& best) {
  Vec3 la, ld;
  local_segment(c, a, b, first, la, ld);
  const Vec3 lb = la + ld;
  const Vec3 grow = Vec3::Constant(r);
  SweepHit h;
  h.s = best.s;
  const MeshShape& m = *c.mesh;
  const Vec3 lo = la.cwiseMin(lb) - grow, hi = la.cwiseMax(lb) + grow;
  const SweepSegment seg(la, ld);
  const auto test = [&](const SweepTriangle& t, std::uint32_t) { sweep_triangle(t, seg, r, h); };
  if (!m.grid.query(lo, hi, test))
    m.bvh.query(lo, hi, [&](std::uint32_t t) { sweep_triangle(m.triangles[t], la, ld, r, h); });
  if (!(h.s < best.s)) return;
  best = c.unposed ? Hit{h.s, h.normal, h.point, &c}
                   : Hit{h.s, Vec3(c.R * h.normal), Vec3(c.center + c.R * h.point), &c};
}

}  // namespace

void sweep(const Collider& c, const Vec3& a, const Vec3& b, double r, bool first, Hit& best) {
  switch (c.shape) {
    case Collider::Shape::plane: sweep_plane(c, a, b, r, best); break;
    case Collider::Shape::box: sweep_box(c, a, b, r, best); break;
    case Collider::Shape::sphere: sweep_sphere(c, a, b, r, first, best); break;
    case Collider::Shape::cylinder: sweep_cylinder(c, a, b, r, first, best); break;
    case Collider::Shape::capsule: sweep_capsule(c, a, b, r, first, best); break;
    case Collider::Shape::mesh: sweep_mesh(c, a, b, r, first, best); break;
  }
}

bool inside_solid(const Collider& c, const Vec3& p) {
  switch (c.shape) {
    case Collider::Shape::sphere: {
      const double tol = inside_tol(p, c.radius);
      const double ri = c.radius - tol;
      return ri > 0.0 && (p - c.center).squaredNorm() < ri * ri;
    }
    case Collider::Shape::cylinder: {
      const double tol = inside_tol(p, std::max(c.radius, c.half_height));
      const Vec3 l = c.R.transpose() * (p - c.center);
      const double ri = c.radius - tol;
      return ri > 0.0 && l.head<2>().squaredNorm() < ri * ri && std::abs(l.z()) < c.half_height - tol;
    }
    case Collider::Shape::capsule: {
      const double tol = inside_tol(p, c.radius + c.half_height);
      const Vec3 l = c.R.transpose() * (p - c.center);
      const double z = std::clamp(l.z(), -c.half_height, c.half_height);
      const double ri = c.radius - tol;
      return ri > 0.0 && (l - Vec3(0.0, 0.0, z)).squaredNorm() < ri * ri;
    }
    case Collider::Shape::mesh: {
      if (!c.mesh->closed) return false;
      const Vec3 l = c.R.transpose() * (p - c.center);
      return c.mesh->contains(l) && !c.mesh->near_surface(l, inside_tol(p, c.mesh->local_half.norm()));
    }
    default: return false;
  }
}

bool sweep_collider(const Collider& c, const Vec3& a, const Vec3& b, double r, bool first,
                    SweepHit& hit) {
  Hit best;
  best.s = hit.s;
  sweep(c, a, b, r, first, best);
  if (best.collider == nullptr) return false;
  hit.s = best.s;
  hit.normal = best.normal;
  hit.point = best.point;
  return true;
}

void constrain_displacement(ParticleStore& s, std::size_t i, const Vec3& from,
                            const std::vector<Collider>& colliders) {
  float* pf = &s.position[3 * i];
  const Vec3 to(pf[0], pf[1], pf[2]);
  Hit hit;
  for (const Collider& c : colliders) sweep(c, from, to, s.radius[i], false, hit);
  if (hit.collider == nullptr) return;
  for (int k = 0; k < 3; ++k) pf[k] = float(hit.point[k]);
}

}  // namespace simreel::sim::detail
