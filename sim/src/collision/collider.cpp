// Colliders at run time: definitions -> Collider (pose, world bounds, a mesh's AABB tree built
// once in its local frame, Coutinho §2.1–2.2), kinematic poses from the path, and the validation
// of collider definitions. The sweeps are in sweep.cpp, the resting-contact features in
// surface_contacts.cpp, the particle pass in particle_response.cpp.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "collision/collider_impl.hpp"
#include "collision/narrow_phase.hpp"
#include "core/path_math.hpp"
#include "core/validate.hpp"

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
