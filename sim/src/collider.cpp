// Colliders and the particle collision pass: Coutinho §2.1–2.2 (queries in the body's frame, AABB
// tree), §3.4 (swept spheres against a collider fixed at its end-of-step pose), §3.4.2 (particles
// found inside a body are removed), §3.6.1 (impulse with restitution and Coulomb friction,
// critical friction), §3.6.3 (resting contact under a normal-speed threshold, static friction).
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "collider_impl.hpp"
#include "narrow_phase.hpp"
#include "path_math.hpp"
#include "validate.hpp"

namespace simreel::sim::detail {

// ---------------------------------------------------------------------------------------------
// Colliders

bool MeshShape::contains(const Vec3& p) const {
  if (!closed || ((p - local_center).cwiseAbs().array() > local_half.array()).any()) return false;
  // A fixed oblique direction: rays along a coordinate axis graze the edges of axis-aligned
  // meshes, where a crossing may count twice or not at all.
  const Vec3 dir = Vec3(0.2138, 0.1402, 0.9668).normalized();
  const double len = 2.0 * ((p - local_center).norm() + local_half.norm());
  const Vec3 q = p + len * dir;
  int crossings = 0;
  bvh.query(p.cwiseMin(q), p.cwiseMax(q), [&](std::uint32_t t) {
    crossings += ray_crosses(triangles[t], p, dir, len) ? 1 : 0;
  });
  return (crossings & 1) != 0;
}

void Collider::set_pose(const Transform& t) {
  center = t.translation;
  rotation = t.rotation.normalized();
  R = rotation.toRotationMatrix();
  switch (shape) {
    case Shape::box:
      aabb_center = center;
      aabb_half = R.cwiseAbs() * half_extents;
      break;
    case Shape::sphere:
      aabb_center = center;
      aabb_half = Vec3::Constant(radius);
      break;
    case Shape::cylinder:
      aabb_center = center;
      aabb_half = R.cwiseAbs() * Vec3(radius, radius, half_height);
      break;
    case Shape::mesh:
      aabb_center = center + R * mesh->local_center;
      aabb_half = R.cwiseAbs() * mesh->local_half;
      break;
    case Shape::plane:
      break;
  }
}

void Collider::update(double t) {
  prev_center = center;
  prev_R = R;
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

namespace {

/// Pose setup shared by the solids: static at `transform`, or on its path at `time`.
Collider& place(Collider& c, const Transform& transform, const KeyframePath& path, double time) {
  c.path = path;
  if (c.kinematic()) {
    c.update(time);
  } else {
    c.set_pose(transform);
  }
  c.prev_center = c.center;
  c.prev_R = c.R;
  c.reported_translation = c.center;
  c.reported_rotation = c.rotation;
  return c;
}

void validate_pose(const Transform& t, const KeyframePath& path, const std::string& what) {
  if (!t.translation.allFinite() || !t.rotation.coeffs().allFinite() ||
      !(t.rotation.norm() > 1e-12))
    throw std::invalid_argument(what +
                                ".transform must be finite with a non-zero rotation quaternion");
  validate(path, what + ".path");
}

}  // namespace

Collider make_collider(const BoxDef& def, double time) {
  validate(def);
  Collider c;
  c.shape = Collider::Shape::box;
  c.material = def.material;
  c.half_extents = def.half_extents;
  return place(c, def.transform, def.path, time);
}

Collider make_collider(const SphereDef& def, double time) {
  if (!(def.radius > 0.0) || !std::isfinite(def.radius)) {
    std::ostringstream m;
    m << "SphereDef.radius must be > 0 and finite (got " << def.radius << ")";
    throw std::invalid_argument(m.str());
  }
  validate_pose(def.transform, def.path, "SphereDef");
  validate(def.material, "SphereDef.material");
  Collider c;
  c.shape = Collider::Shape::sphere;
  c.material = def.material;
  c.radius = def.radius;
  return place(c, def.transform, def.path, time);
}

Collider make_collider(const CylinderDef& def, double time) {
  if (!(def.radius > 0.0) || !std::isfinite(def.radius) || !(def.half_height > 0.0) ||
      !std::isfinite(def.half_height)) {
    std::ostringstream m;
    m << "CylinderDef.radius and half_height must be > 0 and finite (got " << def.radius << ", "
      << def.half_height << ")";
    throw std::invalid_argument(m.str());
  }
  validate_pose(def.transform, def.path, "CylinderDef");
  validate(def.material, "CylinderDef.material");
  Collider c;
  c.shape = Collider::Shape::cylinder;
  c.material = def.material;
  c.radius = def.radius;
  c.half_height = def.half_height;
  return place(c, def.transform, def.path, time);
}

Collider make_collider(const MeshDef& def, double time) {
  if (def.triangles.empty())
    throw std::invalid_argument("MeshDef.triangles must not be empty");
  for (const Vec3& v : def.vertices)
    if (!v.allFinite()) throw std::invalid_argument("MeshDef.vertices must be finite");
  auto shape = std::make_shared<MeshShape>();
  shape->triangles.reserve(def.triangles.size());
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  edges.reserve(3 * def.triangles.size());
  for (std::size_t t = 0; t < def.triangles.size(); ++t) {
    const auto& tri = def.triangles[t];
    for (std::uint32_t k : tri)
      if (k >= def.vertices.size()) {
        std::ostringstream m;
        m << "MeshDef.triangles[" << t << "] refers to vertex " << k << " of "
          << def.vertices.size();
        throw std::invalid_argument(m.str());
      }
    Triangle x{def.vertices[tri[0]], def.vertices[tri[1]], def.vertices[tri[2]], Vec3::Zero()};
    const Vec3 n = (x.b - x.a).cross(x.c - x.a);
    if (!(n.norm() > 0.0)) continue;  // degenerate: its edges belong to the neighbours
    x.normal = n.normalized();
    shape->triangles.push_back(x);
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t i = tri[std::size_t(k)], j = tri[std::size_t((k + 1) % 3)];
      edges.emplace_back(std::min(i, j), std::max(i, j));
    }
  }
  if (shape->triangles.empty())
    throw std::invalid_argument("MeshDef.triangles are all degenerate (zero area)");
  validate_pose(def.transform, def.path, "MeshDef");
  validate(def.material, "MeshDef.material");
  std::sort(edges.begin(), edges.end());
  bool closed = true;
  for (std::size_t i = 0; i < edges.size() && closed;) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    closed = j - i == 2;
    i = j;
  }
  shape->closed = closed;
  shape->bvh = Bvh(shape->triangles);
  const Aabb& b = shape->bvh.bounds();
  shape->local_center = 0.5 * (b.lo + b.hi);
  shape->local_half = 0.5 * (b.hi - b.lo);
  Collider c;
  c.shape = Collider::Shape::mesh;
  c.material = def.material;
  c.mesh = std::move(shape);
  return place(c, def.transform, def.path, time);
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

/// The swept segment in a solid's frame: from a — taken in the body's start-of-step pose on the
/// first sweep of the step, so the segment follows the relative motion of a kinematic body, and
/// in its end pose for the remainder after a contact — to b in the end pose (§2.1, §3.4).
void local_segment(const Collider& c, const Vec3& a, const Vec3& b, bool first, Vec3& la, Vec3& ld) {
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
  if (!np::first_entry(A, B, C, s)) return;
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

/// Sphere moving a -> b against a triangle mesh: the segment goes into the mesh frame (§2.1), the
/// AABB tree gives the triangles near the segment's box grown by r (§2.2), and each is swept
/// exactly (narrow_phase.hpp, §3.7).
void sweep_mesh(const Collider& c, const Vec3& a, const Vec3& b, double r, bool first,
                Hit& best) {
  Vec3 la, ld;
  local_segment(c, a, b, first, la, ld);
  const Vec3 lb = la + ld;
  const Vec3 grow = Vec3::Constant(r);
  SweepHit h;
  h.s = best.s;
  const MeshShape& m = *c.mesh;
  m.bvh.query(la.cwiseMin(lb) - grow, la.cwiseMax(lb) + grow,
              [&](std::uint32_t t) { sweep_triangle(m.triangles[t], la, ld, r, h); });
  if (!(h.s < best.s)) return;
  best = Hit{h.s, Vec3(c.R * h.normal), Vec3(c.center + c.R * h.point), &c};
}

void sweep(const Collider& c, const Vec3& a, const Vec3& b, double r, bool first, Hit& best) {
  switch (c.shape) {
    case Collider::Shape::plane: sweep_plane(c, a, b, r, best); break;
    case Collider::Shape::box: sweep_box(c, a, b, r, best); break;
    case Collider::Shape::sphere: sweep_sphere(c, a, b, r, first, best); break;
    case Collider::Shape::cylinder: sweep_cylinder(c, a, b, r, first, best); break;
    case Collider::Shape::mesh: sweep_mesh(c, a, b, r, first, best); break;
  }
}

/// Is the centre p inside the solid (§3.4.2)? Boxes are excluded: they push particles out.
bool inside_solid(const Collider& c, const Vec3& p) {
  switch (c.shape) {
    case Collider::Shape::sphere: return (p - c.center).squaredNorm() < c.radius * c.radius;
    case Collider::Shape::cylinder: {
      const Vec3 l = c.R.transpose() * (p - c.center);
      return l.head<2>().squaredNorm() < c.radius * c.radius && std::abs(l.z()) < c.half_height;
    }
    case Collider::Shape::mesh:
      return c.mesh->closed && c.mesh->contains(c.R.transpose() * (p - c.center));
    default: return false;
  }
}

}  // namespace

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

/// Impulse response of a particle against an immovable collider (Coutinho §3.6.1 with the
/// collider's mass taken as infinite): relative normal velocity v_n' = -e v_n, tangential
/// velocity reduced by the Coulomb impulse mu (1 + e) |v_n| but never reversed — when
/// mu >= |v_t| / ((1 + e) |v_n|), the critical coefficient of eqs. 3.56–3.57, sliding stops
/// exactly. The tangent axes are taken along and across the relative sliding velocity, where
/// the book's directional model (eqs. 3.37–3.40) with one coefficient for both axes reduces to
/// this. Under the contact threshold (§3.6.3) the contact is resting: e = 0, so the normal
/// velocity is cancelled and friction removes mu |v_n| — the contact friction force mu |N|
/// times the step. A resting contact whose tangential speed is no more than this step's
/// tangential push (it was not sliding) uses the static coefficient: it holds on an incline of
/// angle theta when mu_s >= tan theta, and otherwise slides with a = g (sin theta - mu_d cos theta).
/// `kick` is the velocity one step of acceleration adds (g h for a particle lying on the floor):
/// its normal part is not counted as impact speed, so resting is recognised at any step size.
Vec3 respond(const Vec3& v, const Vec3& vc, const Vec3& n, const Material& m, double contact_speed,
             const Vec3& kick) {
  const Vec3 vr = v - vc;
  const double vn = vr.dot(n);
  if (vn >= 0.0) return v;  // already separating
  const double kick_n = std::max(0.0, -kick.dot(n));
  const double kick_t = (kick - kick.dot(n) * n).norm();
  const bool resting = -vn < contact_speed + kick_n;
  double e = resting ? 0.0 : m.restitution;
  const Vec3 vt = vr - vn * n;
  const double vt_len = vt.norm();
  double mu = resting && vt_len <= kick_t * (1.0 + 1e-6) + 1e-12 ? m.static_mu() : m.friction;
  if (m.on_hit == HitAction::stick) {
    e = 0.0;
    mu = std::numeric_limits<double>::infinity();
  }
  const double dvt = std::min(vt_len, mu * (1.0 + e) * (-vn));
  const Vec3 vt_new = vt_len > 0.0 ? Vec3(vt * (1.0 - dvt / vt_len)) : vt;
  return vc + (-e * vn) * n + vt_new;
}

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
    case Collider::Shape::mesh: {
      const MeshShape& m = *c.mesh;
      int count = 0;
      m.bvh.query(l - Vec3::Constant(reach), l + Vec3::Constant(reach), [&](std::uint32_t t) {
        const Vec3 off = l - closest_on_triangle(m.triangles[t], l);
        const double d = off.norm();
        if (!(d > 0.0) || !(d - r < margin)) return;
        add_surface_contact(Vec3(c.R * (off / d)), d - r, out, count, max_out);
      });
      return count;
    }
    default: return 0;
  }
  const double gap = dist - r;
  if (!(gap < margin)) return 0;
  out[0] = SurfaceContact{Vec3(c.R * ln), gap};
  return 1;
}

namespace {

/// A particle found inside a box (the box may have moved onto it) leaves through the face it is
/// least deep behind and takes the box's velocity along that face's normal if it was moving in.
/// (Coutinho §3.4.2 removes such particles; simreel keeps them for boxes, which suits pushing
/// boxes; the other solids remove them.)
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

/// Droplets of a split hit (HitAction::split): see SplitOnHit.
void splash(const Material& m, const Vec3& contact, const Vec3& n, const Vec3& v_rel,
            const Vec3& vc, double r, double mass, CollisionContext& ctx) {
  const SplitOnHit& sp = m.split;
  if (r < sp.min_radius || ctx.spawns == nullptr || ctx.rng == nullptr) return;
  const double rd = r * sp.size_fraction;
  const double speed = sp.speed_fraction * v_rel.norm();
  const Vec3 t = n.unitOrthogonal();
  const Vec3 k = n.cross(t);
  const double cos_max = std::cos(sp.spread_deg * 3.14159265358979323846 / 180.0);
  const Vec3 surface = contact - r * n;
  for (int j = 0; j < sp.count; ++j) {
    const double cz = 1.0 - ctx.rng->uniform() * (1.0 - cos_max);  // uniform over the cap
    const double phi = 2.0 * 3.14159265358979323846 * ctx.rng->uniform();
    const double sz = std::sqrt(std::max(0.0, 1.0 - cz * cz));
    const Vec3 dir = cz * n + sz * (std::cos(phi) * t + std::sin(phi) * k);
    ctx.spawns->push_back(SpawnRequest{Vec3(surface + 1.01 * rd * n), Vec3(vc + speed * dir), rd,
                                       mass * sp.size_fraction * sp.size_fraction *
                                           sp.size_fraction,
                                       sp.lifetime});
  }
}

/// The slow path for one particle that may touch something this step.
void resolve(ParticleStore& s, std::size_t i, double dt, const std::vector<Collider>& colliders,
             CollisionContext& ctx, const ForceParams& f) {
  float* pf = &s.position[3 * i];
  float* vf = &s.velocity[3 * i];
  Vec3 b(pf[0], pf[1], pf[2]);
  Vec3 v(vf[0], vf[1], vf[2]);
  Vec3 a = start_of_step(s, i, b, v, dt);
  const double r = s.radius[i];
  const double c_drag = double(f.drag) / double(s.mass[i]);
  const Vec3 g(f.gravity[0], f.gravity[1], f.gravity[2]);
  bool dead = false;

  for (int contact = 0;; ++contact) {
    Hit hit;
    for (const Collider& c : colliders) sweep(c, a, b, r, contact == 0, hit);
    if (hit.collider == nullptr) break;
    Material mat = hit.collider->material;
    if (ctx.on_hit != nullptr) {
      mat.on_hit = *ctx.on_hit;
      mat.split = *ctx.on_hit_split;
    }
    const Vec3 vc = hit.collider->point_velocity(hit.point);
    if (mat.on_hit == HitAction::kill || mat.on_hit == HitAction::split) {
      if (mat.on_hit == HitAction::split)
        splash(mat, hit.point, hit.normal, v - vc, vc, r, s.mass[i], ctx);
      dead = true;
      b = hit.point;
      break;
    }
    const Vec3 kick = (g - c_drag * v) * dt;
    v = respond(v, vc, hit.normal, mat, ctx.contact_speed, kick);
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

  if (!dead) {
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
    for (const Collider& c : colliders) {
      if (c.shape == Collider::Shape::plane || c.shape == Collider::Shape::box) continue;
      if (((b - c.aabb_center).cwiseAbs().array() > c.aabb_half.array()).any()) continue;
      if (inside_solid(c, b)) {
        dead = true;  // §3.4.2
        ++ctx.removed_inside;
        break;
      }
    }
  }
  if (dead) s.age[i] = s.lifetime[i];

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
             const std::vector<Collider>& colliders, CollisionContext& ctx, const ForceParams& f) {
  if (colliders.empty()) return;
  const float* x = s.position.data();
  const float* vel = s.velocity.data();
  for (std::size_t i = begin; i < end; ++i) {
    // Fast rejection: end point clear of every plane, swept bounds clear of every solid.
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
        const Vec3 lo = p0.cwiseMin(p1) - c.aabb_center;
        const Vec3 hi = p0.cwiseMax(p1) - c.aabb_center;
        const Vec3 ext = c.aabb_half + Vec3::Constant(r + surface_tol(p1));
        near = (lo.array() <= ext.array()).all() && (hi.array() >= -ext.array()).all();
      }
      if (near) break;
    }
    if (near) resolve(s, i, dt, colliders, ctx, f);
  }
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

// ---------------------------------------------------------------------------------------------
// Validation

void validate(const Material& m, const std::string& what) {
  require_in(m.restitution, ranges::kRestitution, what + ".restitution");
  require_in(m.friction, ranges::kFriction, what + ".friction");
  if (!std::isfinite(m.static_friction)) {
    std::ostringstream msg;
    msg << what << ".static_friction must be finite (got " << m.static_friction << ")";
    throw std::invalid_argument(msg.str());
  }
  const SplitOnHit& sp = m.split;
  require_in((long long)sp.count, ranges::kHitSplitCount, what + ".split.count");
  require_in(sp.speed_fraction, ranges::kHitSplitSpeedFraction, what + ".split.speed_fraction");
  require_in(sp.size_fraction, ranges::kHitSplitSizeFraction, what + ".split.size_fraction");
  require_in(sp.lifetime, ranges::kHitSplitLifetime, what + ".split.lifetime");
  require_in(sp.spread_deg, ranges::kHitSplitSpreadDeg, what + ".split.spread_deg");
  require_in(sp.min_radius, ranges::kHitSplitMinRadius, what + ".split.min_radius");
}

void validate(const PlaneDef& def) {
  if (!def.point.allFinite() || !def.normal.allFinite())
    throw std::invalid_argument("PlaneDef: point and normal must be finite");
  if (!(def.normal.norm() > 1e-12))
    throw std::invalid_argument("PlaneDef.normal must be non-zero (got (0, 0, 0))");
  validate(def.material, "PlaneDef.material");
}

void validate(const BoxDef& def) {
  for (int k = 0; k < 3; ++k)
    require_in(def.half_extents[k], ranges::kColliderSize, "BoxDef.half_extents[" + std::to_string(k) + "]");
  if (!def.transform.translation.allFinite() || !def.transform.rotation.coeffs().allFinite() ||
      !(def.transform.rotation.norm() > 1e-12))
    throw std::invalid_argument(
        "BoxDef.transform must be finite with a non-zero rotation quaternion");
  validate(def.path, "BoxDef.path");
  validate(def.material, "BoxDef.material");
}

}  // namespace simreel::sim::detail
