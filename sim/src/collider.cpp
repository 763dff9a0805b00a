// Colliders and the particle collision pass: Coutinho §3.4 (swept spheres against a collider
// fixed at its end-of-step pose), §3.6.1 (impulse with restitution and directional Coulomb
// friction, critical friction), §3.6.3 (resting contact under a normal-speed threshold).
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "collider_impl.hpp"
#include "path_math.hpp"
#include "validate.hpp"

namespace simreel::sim::detail {

// ---------------------------------------------------------------------------------------------
// Colliders

void Collider::set_pose(const Transform& t) {
  center = t.translation;
  rotation = t.rotation.normalized();
  R = rotation.toRotationMatrix();
  aabb_half = R.cwiseAbs() * half_extents;
}

void Collider::update(double t) {
  set_pose(path.sample(t));
  velocity = path.velocity(t);
  angular_velocity = detail::angular_velocity(path, t);
}

MovedObject Collider::pose() const {
  MovedObject m;
  if (shape == Shape::plane) {
    // Local +z is the plane's normal, the translation its reference point.
    m.translation = point;
    m.rotation = Quat::FromTwoVectors(Vec3::UnitZ(), normal).toRotationMatrix();
  } else {
    m.translation = center;
    m.rotation = R;
  }
  return m;
}

Collider make_collider(const PlaneDef& def) {
  validate(def);
  Collider c;
  c.shape = Collider::Shape::plane;
  c.material = def.material;
  c.point = def.point;
  c.normal = def.normal.normalized();
  return c;
}

Collider make_collider(const BoxDef& def, double time) {
  validate(def);
  Collider c;
  c.shape = Collider::Shape::box;
  c.material = def.material;
  c.half_extents = def.half_extents;
  c.path = def.path;
  if (c.kinematic()) {
    c.update(time);
  } else {
    c.set_pose(def.transform);
  }
  c.reported_translation = c.center;
  c.reported_rotation = c.rotation;
  return c;
}

// ---------------------------------------------------------------------------------------------
// Collision pass

namespace {

constexpr int kMaxContacts = 4;  // contacts resolved per particle per step (corners, wedges)
constexpr double kSkin = 1e-9;   // (m) penetration a plane sweep ignores (rounding, not motion)

/// (m) how far inside a surface a start point may lie and still count as on it: a few float
/// ulps at the point's magnitude (positions are stored in float).
double surface_tol(const Vec3& p) { return 1e-7 + 5e-7 * p.cwiseAbs().maxCoeff(); }

struct Hit {
  double s = std::numeric_limits<double>::infinity();  ///< fraction of the segment
  Vec3 normal = Vec3::Zero();
  Vec3 point = Vec3::Zero();  ///< particle centre at contact
  const Collider* collider = nullptr;
};

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
  Vec3 lp = la + tmin * d;
  lp[axis] = sign * E[axis];
  best = Hit{tmin, Vec3(sign * c.R.col(axis)), Vec3(c.center + c.R * lp), &c};
}

/// Impulse response of a particle against an immovable collider (Coutinho §3.6.1 with the
/// collider's mass taken as infinite): relative normal velocity v_n' = -e v_n, tangential
/// velocity reduced by the Coulomb impulse mu (1 + e) |v_n| but never reversed — when
/// mu >= |v_t| / ((1 + e) |v_n|), the critical coefficient of eqs. 3.56–3.57, sliding stops.
/// Under the contact threshold (§3.6.3) the contact is resting: e = 0, so the normal velocity is
/// cancelled and friction removes mu |v_n| — the contact friction force mu |N| times the step.
/// `kick` is the approach speed one step of acceleration adds (g h for a particle lying on the
/// floor): it is not counted as impact speed, so resting is recognised at any step size.
Vec3 respond(const Vec3& v, const Vec3& vc, const Vec3& n, const Material& m, double contact_speed,
             double kick) {
  const Vec3 vr = v - vc;
  const double vn = vr.dot(n);
  if (vn >= 0.0) return v;  // already separating
  const bool resting = -vn < contact_speed + kick;
  const double e = resting ? 0.0 : m.restitution;
  const Vec3 vt = vr - vn * n;
  const double vt_len = vt.norm();
  const double dvt = std::min(vt_len, m.friction * (1.0 + e) * (-vn));
  const Vec3 vt_new = vt_len > 0.0 ? Vec3(vt * (1.0 - dvt / vt_len)) : vt;
  return vc + (-e * vn) * n + vt_new;
}

/// A particle found inside a box (the box may have moved onto it) leaves through the face it is
/// least deep behind and takes the box's velocity along that face's normal if it was moving in.
/// (Coutinho §3.4 removes such particles; simreel keeps them, which suits pushing boxes.)
void push_out(const Collider& c, Vec3& p, Vec3& v, double r) {
  Vec3 l = c.R.transpose() * (p - c.center);
  const Vec3 E = c.half_extents + Vec3::Constant(r);
  const Vec3 depth = E - l.cwiseAbs();
  int k = 0;
  if (!(depth.minCoeff(&k) > surface_tol(p))) return;
  const double sign = l[k] >= 0.0 ? 1.0 : -1.0;
  l[k] = sign * E[k];
  p = c.center + c.R * l;
  const Vec3 n = sign * c.R.col(k);
  const double vn = (v - c.point_velocity(p)).dot(n);
  if (vn < 0.0) v -= vn * n;
}

/// Reads back a stored float position. The volatile read is deliberate: GCC 12 -O3 forwards the
/// unrounded doubles to a reload after a vectorised float store (it folds the round trip
/// cvtps2pd(cvtpd2ps(x)) into x), which made the check below pass on values never stored.
Vec3 load_stored(const float* pf) {
  const volatile float* v = pf;
  return Vec3(v[0], v[1], v[2]);
}

/// Where particle i was at the start of its step: stored (RK4) or, for semi-implicit Euler,
/// recovered from x1 = x0 + dt v1 (within float rounding of x1, which surface_tol absorbs).
Vec3 start_of_step(const ParticleStore& s, std::size_t i, const Vec3& p1, const Vec3& v1,
                   double dt) {
  if (s.track_prev) {
    const float* q = &s.prev_position[3 * i];
    return Vec3(q[0], q[1], q[2]);
  }
  return p1 - dt * v1;
}

/// The slow path for one particle that may touch something this step.
void resolve(ParticleStore& s, std::size_t i, double dt, const std::vector<Collider>& colliders,
             double contact_speed, const ForceParams& f) {
  float* pf = &s.position[3 * i];
  float* vf = &s.velocity[3 * i];
  Vec3 b(pf[0], pf[1], pf[2]);
  Vec3 v(vf[0], vf[1], vf[2]);
  Vec3 a = start_of_step(s, i, b, v, dt);
  const double r = s.radius[i];
  const double c_drag = double(f.drag) / double(s.mass[i]);
  const Vec3 g(f.gravity[0], f.gravity[1], f.gravity[2]);

  for (int contact = 0;; ++contact) {
    Hit hit;
    for (const Collider& c : colliders) {
      if (c.shape == Collider::Shape::plane) {
        sweep_plane(c, a, b, r, hit);
      } else {
        sweep_box(c, a, b, r, hit);
      }
    }
    if (hit.collider == nullptr) break;
    const Vec3 acc = g - c_drag * v;
    const double kick = std::max(0.0, -acc.dot(hit.normal)) * dt;
    const Vec3 vc = hit.collider->point_velocity(hit.point);
    v = respond(v, vc, hit.normal, hit.collider->material, contact_speed, kick);
    // The rest of the step with the new velocity against the collider held at its end pose
    // (§3.4), never back into the surface just left. (Not relative to a moving collider: a
    // particle at rest on a box sliding under it must stay where it is, not slide backwards.)
    const double rest = (1.0 - hit.s) * dt;
    Vec3 disp = rest * v;
    const double dn = disp.dot(hit.normal);
    if (dn < 0.0) disp -= dn * hit.normal;
    a = hit.point;
    dt = rest;
    if (contact + 1 == kMaxContacts) {
      b = a;  // out of contacts: stay at the last one, which is outside everything hit so far
      break;
    }
    b = a + disp;
  }

  for (const Collider& c : colliders)
    if (c.shape == Collider::Shape::box) push_out(c, b, v, r);
  for (const Collider& c : colliders) {
    if (c.shape != Collider::Shape::plane) continue;
    const double d = c.normal.dot(b - c.point) - r;
    if (d < 0.0) {
      b -= d * c.normal;
      const double vn = v.dot(c.normal);
      if (vn < 0.0) v -= vn * c.normal;
    }
  }

  for (int k = 0; k < 3; ++k) {
    pf[k] = float(b[k]);
    vf[k] = float(v[k]);
  }
  // The guarantee holds for the stored floats: rounding b to float may put the centre a hair
  // inside a plane; step it out by growing amounts until it is not.
  for (const Collider& c : colliders) {
    if (c.shape != Collider::Shape::plane) continue;
    for (int attempt = 0; attempt < 8; ++attempt) {
      const Vec3 p = load_stored(pf);
      const double d = c.normal.dot(p - c.point) - r;
      if (d >= 0.0) break;
      const double extra = attempt == 0 ? 0.0 : std::ldexp(1.2e-7, attempt) * (1.0 + p.cwiseAbs().maxCoeff());
      const Vec3 q = p + (extra - d) * c.normal;
      for (int k = 0; k < 3; ++k) pf[k] = float(q[k]);
    }
  }
}

}  // namespace

void collide(ParticleStore& s, std::size_t begin, std::size_t end, double h,
             const std::vector<Collider>& colliders, double contact_speed, const ForceParams& f) {
  if (colliders.empty()) return;
  const float* x = s.position.data();
  const float* vel = s.velocity.data();
  for (std::size_t i = begin; i < end; ++i) {
    // Fast rejection: end point clear of every plane, swept bounds clear of every box.
    const Vec3 p1(x[3 * i], x[3 * i + 1], x[3 * i + 2]);
    const double r = s.radius[i];
    const double dt = std::min(double(s.age[i]), h);
    bool near = false;
    for (const Collider& c : colliders) {
      if (c.shape == Collider::Shape::plane) {
        near = c.normal.dot(p1 - c.point) - r < 0.0;
      } else {
        const Vec3 v1(vel[3 * i], vel[3 * i + 1], vel[3 * i + 2]);
        const Vec3 p0 = start_of_step(s, i, p1, v1, dt);
        const Vec3 lo = p0.cwiseMin(p1) - c.center;
        const Vec3 hi = p0.cwiseMax(p1) - c.center;
        const Vec3 ext = c.aabb_half + Vec3::Constant(r + surface_tol(p1));
        near = (lo.array() <= ext.array()).all() && (hi.array() >= -ext.array()).all();
      }
      if (near) break;
    }
    if (near) resolve(s, i, dt, colliders, contact_speed, f);
  }
}

// ---------------------------------------------------------------------------------------------
// Validation

void validate(const Material& m, const std::string& what) {
  if (!(m.restitution >= 0.0 && m.restitution <= 1.0)) {
    std::ostringstream msg;
    msg << what << ".restitution must be in [0, 1] (got " << m.restitution << ")";
    throw std::invalid_argument(msg.str());
  }
  if (!(m.friction >= 0.0) || !std::isfinite(m.friction)) {
    std::ostringstream msg;
    msg << what << ".friction must be >= 0 and finite (got " << m.friction << ")";
    throw std::invalid_argument(msg.str());
  }
}

void validate(const PlaneDef& def) {
  if (!def.point.allFinite() || !def.normal.allFinite())
    throw std::invalid_argument("PlaneDef: point and normal must be finite");
  if (!(def.normal.norm() > 1e-12))
    throw std::invalid_argument("PlaneDef.normal must be non-zero (got (0, 0, 0))");
  validate(def.material, "PlaneDef.material");
}

void validate(const BoxDef& def) {
  if (!(def.half_extents.minCoeff() > 0.0) || !def.half_extents.allFinite()) {
    std::ostringstream msg;
    msg << "BoxDef.half_extents must be > 0 and finite on every axis (got ("
        << def.half_extents.x() << ", " << def.half_extents.y() << ", " << def.half_extents.z()
        << "))";
    throw std::invalid_argument(msg.str());
  }
  if (!def.transform.translation.allFinite() || !def.transform.rotation.coeffs().allFinite() ||
      !(def.transform.rotation.norm() > 1e-12))
    throw std::invalid_argument(
        "BoxDef.transform must be finite with a non-zero rotation quaternion");
  validate(def.path, "BoxDef.path");
  validate(def.material, "BoxDef.material");
}

}  // namespace simreel::sim::detail
