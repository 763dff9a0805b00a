// Cloth vertices against colliders: projection with inelastic normal response and Coulomb
// friction (Coutinho §3.4, §3.6.1, §3.9.2).
#include "cloth/cloth_collide.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "collision/narrow_phase.hpp"

namespace simreel::sim::detail {

namespace {

/// Removes the inward normal velocity relative to the collider (normal n points out) and applies
/// Coulomb friction to the tangential part.
void respond(Vec3& v, const Vec3& n, const Vec3& collider_velocity, double friction) {
  Vec3 rel = v - collider_velocity;
  const double vn = rel.dot(n);
  if (vn >= 0.0) return;  // already leaving
  rel -= vn * n;          // normal part removed: |Δv_n| = -vn
  const double vt = rel.norm();
  const double cut = friction * -vn;
  rel *= vt > cut ? (vt - cut) / vt : 0.0;
  v = collider_velocity + rel;
}

/// Returns true and the outward normal if x was projected out of the plane's grown half-space.
bool plane(const Collider& c, Vec3& x, double thickness, Vec3& n) {
  const double d = c.normal.dot(x - c.point) - thickness;
  if (d >= 0.0) return false;
  x -= d * c.normal;
  n = c.normal;
  return true;
}

/// Box grown by `thickness` (square edges). If x ends inside, it leaves through the face the
/// segment x_start -> x entered by (slab method in the box frame), or the nearest face when
/// x_start was already inside (the box moved onto it).
bool box(const Collider& c, const Vec3& x_start, Vec3& x, double thickness, Vec3& n) {
  const Vec3 e = c.half_extents + Vec3::Constant(thickness);
  Vec3 q = c.R.transpose() * (x - c.center);
  for (int k = 0; k < 3; ++k)
    if (!(std::abs(q[k]) < e[k])) return false;
  const Vec3 q0 = c.R.transpose() * (x_start - c.center);
  int axis = -1;
  bool start_outside = false;
  for (int k = 0; k < 3; ++k) start_outside |= !(std::abs(q0[k]) < e[k]);
  if (start_outside) {
    // Entry time of the segment into each slab; the face entered last is the one crossed.
    double best = -std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
      const double dq = q[k] - q0[k];
      if (std::abs(q0[k]) < e[k] || dq == 0.0) continue;  // inside this slab from the start
      const double t_enter = (std::copysign(e[k], q0[k]) - q0[k]) / dq;
      if (t_enter > best) {
        best = t_enter;
        axis = k;
      }
    }
  }
  double sign = 0.0;
  if (axis < 0) {
    double depth = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
      const double dk = e[k] - std::abs(q[k]);
      if (dk < depth) {
        depth = dk;
        axis = k;
      }
    }
    sign = q[axis] >= 0.0 ? 1.0 : -1.0;
  } else {
    sign = q0[axis] >= 0.0 ? 1.0 : -1.0;
  }
  q[axis] = sign * e[axis];
  x = c.center + c.R * q;
  n = sign * c.R.col(axis);
  return true;
}

constexpr int kMaxSlides = 3;  // contacts followed per vertex per collider (wedges, concave meshes)

/// Could the vertex's path x_start -> x come within `thickness` of the solid? World AABB test,
/// the solid's box grown by its own motion over the step (kinematic colliders) and the thickness.
bool near_solid(const Collider& c, const Vec3& x_start, const Vec3& x, double thickness) {
  const double motion =
      (c.center - c.prev_center).norm() +
      (c.R - c.prev_R).norm() * ((c.aabb_center - c.center).norm() + c.aabb_half.norm());
  const Vec3 grow = c.aabb_half + Vec3::Constant(thickness + motion);
  const Vec3 lo = x_start.cwiseMin(x), hi = x_start.cwiseMax(x);
  return ((lo - c.aabb_center).array() <= grow.array()).all() &&
         ((c.aabb_center - hi).array() <= grow.array()).all();
}

/// Sphere, cylinder, capsule and triangle mesh (static or kinematic). The vertex's path x_start -> x is
/// swept as a sphere of radius `thickness` with the particle pass's closed forms and AABB-tree
/// query (sweep_collider, Coutinho §3.4, §2.2), along the motion relative to a kinematic body, so
/// a fast vertex cannot tunnel. At the first contact the vertex stops on the grown surface and the
/// rest of its displacement, less its normal part, slides on along the tangent plane and is
/// swept again (up to kMaxSlides contacts; after the last one it stays at the contact point).
/// A vertex that ends inside the sphere, cylinder or capsule grown by `thickness` without a swept contact
/// (it started inside the solid: a collider moved onto it) goes out to the nearest point of the
/// grown surface. For meshes the sweep alone keeps vertices out: a vertex that somehow started
/// deep inside a mesh is not pushed out.
bool solid(const Collider& c, const Vec3& x_start, Vec3& x, double thickness, Vec3& n) {
  if (!near_solid(c, x_start, x, thickness)) return false;
  bool touched = false;
  Vec3 a = x_start, b = x;
  for (int k = 0; k < kMaxSlides; ++k) {
    SweepHit h;
    if (!sweep_collider(c, a, b, thickness, k == 0, h)) break;
    touched = true;
    n = h.normal;
    if (k == kMaxSlides - 1) {
      b = h.point;
      break;
    }
    Vec3 rest = (1.0 - h.s) * (b - a);
    rest -= std::min(0.0, rest.dot(n)) * n;
    a = h.point;
    b = h.point + rest;
  }
  x = b;
  if (c.shape == Collider::Shape::sphere) {
    const Vec3 off = x - c.center;
    const double rg = c.radius + thickness, d = off.norm();
    if (d < rg && d > 0.0) {
      n = off / d;
      x = c.center + rg * n;
      touched = true;
    }
  } else if (c.shape == Collider::Shape::capsule) {
    const Vec3 q = c.R.transpose() * (x - c.center);
    const Vec3 axis(0.0, 0.0, std::clamp(q.z(), -c.half_height, c.half_height));
    const Vec3 off = q - axis;
    const double rg = c.radius + thickness, d = off.norm();
    if (d < rg && d > 0.0) {
      n = c.R * (off / d);
      x = c.center + c.R * (axis + rg * (off / d));
      touched = true;
    }
  } else if (c.shape == Collider::Shape::cylinder) {
    Vec3 q = c.R.transpose() * (x - c.center);
    const double rg = c.radius + thickness, hg = c.half_height + thickness;
    const double rho = q.head<2>().norm();
    if (rho < rg && std::abs(q.z()) < hg) {
      Vec3 ln;
      if (rg - rho < hg - std::abs(q.z()) && rho > 0.0) {
        ln = Vec3(q.x() / rho, q.y() / rho, 0.0);
        q.head<2>() = rg * ln.head<2>();
      } else {
        ln = Vec3(0.0, 0.0, q.z() >= 0.0 ? 1.0 : -1.0);
        q.z() = hg * ln.z();
      }
      x = c.center + c.R * q;
      n = c.R * ln;
      touched = true;
    }
  }
  return touched;
}

}  // namespace

void collide_cloth(std::vector<Vec3>& x, std::vector<Vec3>& v, const std::vector<Vec3>& x_start,
                   const std::vector<std::uint8_t>& free, const std::vector<Collider>& colliders,
                   double thickness, double friction, std::vector<std::uint8_t>& hit,
                   double vertex_mass, BodyImpulses* impulses, std::vector<Vec3>* pushed_normal,
                   BodyContacts* body_contacts) {
  const std::size_t n = x.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (!free[i]) continue;
    // Two sweeps so a vertex pushed from one collider into another (a box on the ground) ends
    // clear of both in ordinary stacked configurations.
    for (int sweep = 0; sweep < 2; ++sweep) {
      bool moved = false;
      for (const Collider& c : colliders) {
        Vec3 normal;
        bool touched = false;
        switch (c.shape) {
          case Collider::Shape::plane:
            touched = plane(c, x[i], thickness, normal);
            break;
          case Collider::Shape::box:
            touched = box(c, x_start[i], x[i], thickness, normal);
            break;
          case Collider::Shape::sphere:
          case Collider::Shape::cylinder:
          case Collider::Shape::capsule:
          case Collider::Shape::mesh:
            touched = solid(c, x_start[i], x[i], thickness, normal);
            break;
        }
        if (touched) {
          const Vec3 v_in = v[i];
          respond(v[i], normal, c.point_velocity(x[i]), friction);
          // Two-way (§3.7): the body takes the momentum the vertex lost, at the surface point.
          if (impulses != nullptr && v[i] != v_in)
            impulses->add(c, vertex_mass * (v_in - v[i]), x[i] - thickness * normal);
          if (body_contacts != nullptr && impulses != nullptr && impulses->logs(c)) {
            body_contacts->shape[i] = std::uint32_t(&c - colliders.data());
            body_contacts->point[i] = x[i];
            body_contacts->normal[i] = normal;
          }
          // 2: pushed by a kinematic body (the maximum-deformation pass then holds the vertex).
          const bool pushed = c.moving && (impulses == nullptr || !impulses->logs(c));
          hit[i] = std::max(hit[i], std::uint8_t(pushed ? 2 : 1));
          if (pushed && pushed_normal != nullptr) (*pushed_normal)[i] = normal;
          moved = true;
        }
      }
      if (!moved) break;
    }
  }
}

void hold_dynamic_bodies(const std::vector<Vec3>& x, const std::vector<Vec3>& v,
                         const std::vector<std::uint8_t>& free, double thickness, double h,
                         BodyContacts& contacts, BodyImpulses& impulses) {
  constexpr double kBaumgarte = 0.1;
  // (m/s) The push-out is capped (Box2D's contact push velocity): a vertex the strain pass left
  // deep in the body must not throw it out.
  constexpr double kMaxPushOut = 0.2;
  constexpr int kIterations = 10;
  // Depths below this are the strain pass's rounding, not a pull.
  const double tol = std::max(1e-5, 0.05 * thickness);
  auto& rows = contacts.rows;
  rows.clear();
  contacts.slot.assign(impulses.motion.size(), -1);
  contacts.held_bodies.clear();
  contacts.vel.clear();
  contacts.omega.clear();
  for (std::size_t i = 0; i < x.size(); ++i) {
    const std::uint32_t k = contacts.shape[i];
    if (k == BodyImpulses::kNone || !free[i]) continue;
    const Vec3& n = contacts.normal[i];
    const double d = (contacts.point[i] - x[i]).dot(n);
    if (!(d > tol)) continue;
    const std::uint32_t r = impulses.rigid[k];
    const BodyImpulses::Motion& m = impulses.motion[r];
    if (!(m.inv_mass > 0.0)) continue;  // asleep: immovable this step
    const Vec3 p = contacts.point[i] - thickness * n;
    const Vec3 rn = (p - m.centre).cross(n);
    const double k_inv = m.inv_mass + rn.dot(m.inv_inertia * rn);
    // A vertex moving into the body does not throw it (it weighs next to nothing): the body
    // only may not approach it.
    rows.push_back({k, r, p, n, std::max(0.0, v[i].dot(n)), 1.0 / k_inv, 0.0, d});
    if (contacts.slot[r] < 0) {
      contacts.slot[r] = std::int32_t(contacts.held_bodies.size());
      contacts.held_bodies.push_back(r);
      contacts.vel.push_back(m.velocity + h * m.gravity);  // the bodies stage adds it first
      contacts.omega.push_back(m.angular_velocity);
    }
  }
  if (rows.empty()) return;
  // The bodies stage applies this step's logged impulses first: start from their result.
  for (const BodyImpulses::Entry& e : impulses.entries) {
    const std::uint32_t r = impulses.rigid[e.shape];
    const std::int32_t s = contacts.slot[r];
    if (s < 0) continue;
    const BodyImpulses::Motion& m = impulses.motion[r];
    contacts.vel[s] += m.inv_mass * e.impulse;
    contacts.omega[s] += m.inv_inertia *
                         (e.moment + (impulses.shapes[e.shape].center - m.centre).cross(e.impulse));
  }
  for (int it = 0; it < kIterations; ++it) {
    for (BodyContacts::Row& row : rows) {
      const std::int32_t s = contacts.slot[row.rigid];
      const BodyImpulses::Motion& m = impulses.motion[row.rigid];
      const Vec3 arm = row.point - m.centre;
      const double wn = (contacts.vel[s] + contacts.omega[s].cross(arm)).dot(row.normal);
      const double lambda = std::max(0.0, row.lambda + (wn - row.target) * row.m_eff);
      const double dl = lambda - row.lambda;
      row.lambda = lambda;
      contacts.vel[s] -= (m.inv_mass * dl) * row.normal;
      contacts.omega[s] -= m.inv_inertia * (arm.cross(row.normal) * dl);
    }
  }
  for (const BodyContacts::Row& row : rows)
    if (row.lambda > 0.0) impulses.add(impulses.shapes[row.shape], -row.lambda * row.normal, row.point);
  // The overlap is undone by a push of the whole body, along the depth-weighted mean of the
  // rows' -n: vertices pressing from opposite sides (a body squeezed against the pins) cancel
  // instead of asking for two speeds at once.
  auto& push = contacts.push;
  push.assign(contacts.held_bodies.size(), {Vec3::Zero(), 0.0, 0.0, BodyImpulses::kNone});
  for (const BodyContacts::Row& row : rows) {
    BodyContacts::Push& q = push[std::size_t(contacts.slot[row.rigid])];
    q.direction -= row.depth * row.normal;
    q.depth_sum += row.depth;
    q.depth_max = std::max(q.depth_max, row.depth);
    q.shape = row.shape;
  }
  for (std::size_t s = 0; s < push.size(); ++s) {
    const BodyContacts::Push& q = push[s];
    const BodyImpulses::Motion& m = impulses.motion[contacts.held_bodies[s]];
    const double len = q.direction.norm();
    if (!(len > 0.0)) continue;
    const Vec3 u = q.direction / len;
    const double speed = std::min(kBaumgarte * q.depth_max / h, kMaxPushOut) * len / q.depth_sum;
    const double need = speed - contacts.vel[s].dot(u);
    if (need > 0.0) impulses.add(impulses.shapes[q.shape], (need / m.inv_mass) * u, m.centre);
  }
}

}  // namespace simreel::sim::detail
