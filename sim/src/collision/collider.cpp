// Shapes at run time: ShapeDef -> Collider (geometry, a mesh's AABB tree built once in its
// local frame, Coutinho §2.1–2.2), the shape's world pose from its body's (body pose ∘ offset),
// and the validation of shape definitions. The sweeps are in sweep.cpp, the resting-contact
// features in surface_contacts.cpp, the particle pass in particle_response.cpp.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "collision/collider_impl.hpp"
#include "collision/narrow_phase.hpp"
#include "core/validate.hpp"
#include "rigid/convex_hull.hpp"

namespace simreel::sim::detail {

// ---------------------------------------------------------------------------------------------
// Colliders

bool MeshShape::contains(const Vec3& p) const {
  if (!closed || ((p - local_center).cwiseAbs().array() > local_half.array()).any()) return false;
  // A fixed oblique direction: rays along a coordinate axis graze the edges of axis-aligned
  // meshes, where a crossing may count twice or not at all.
  const Vec3 dir = Vec3(0.2138, 0.1402, 0.9668).normalized();
  const double len = 2.0 * ((p - local_center).norm() + local_half.norm());
  // Only the leaves along the ray: the box the ray spans holds most of a bowl's triangles.
  // The pad (far above the rounding of ray_crosses' barycentric test) keeps every triangle it
  // counts among those visited, so the parity is the one a test of every triangle gives.
  int crossings = 0;
  bvh.ray_query(p, dir, len, 1e-9 * len, [&](std::uint32_t t) {
    crossings += ray_crosses(triangles[t], p, dir, len) ? 1 : 0;
  });
  return (crossings & 1) != 0;
}

namespace {

/// Squared distance from p to triangle t (closest point by Voronoi regions, Ericson 2005 §5.1.5).
double distance2_to_triangle(const Triangle& t, const Vec3& p) {
  const Vec3 ab = t.b - t.a, ac = t.c - t.a, ap = p - t.a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return ap.squaredNorm();
  const Vec3 bp = p - t.b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return (ap - (d1 / (d1 - d3)) * ab).squaredNorm();
  const Vec3 cp = p - t.c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return (ap - (d2 / (d2 - d6)) * ac).squaredNorm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
    return (bp - ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (t.c - t.b)).squaredNorm();
  const double den = va + vb + vc;
  if (!(den != 0.0)) return std::min({ap.squaredNorm(), bp.squaredNorm(), cp.squaredNorm()});
  const double v = vb / den, w = vc / den;
  return (ap - v * ab - w * ac).squaredNorm();
}

}  // namespace

bool MeshShape::near_surface(const Vec3& p, double tol) const {
  const Vec3 e = Vec3::Constant(tol);
  bool near = false;
  bvh.query(p - e, p + e, [&](std::uint32_t t) {
    near = near || distance2_to_triangle(triangles[t], p) <= tol * tol;
  });
  return near;
}

namespace {

[[nodiscard]] bool is_identity(const Quat& q) {
  return q.x() == 0.0 && q.y() == 0.0 && q.z() == 0.0 && q.w() == 1.0;
}

}  // namespace

void Collider::set_pose(const Transform& t) {
  if (shape == Shape::plane) {
    // The centre and rotation of a plane stay zero and identity (they are hashed as such).
    point = t.translation;
    normal = is_identity(t.rotation) ? local_normal
                                     : Vec3((t.rotation.normalized() * local_normal).normalized());
    return;
  }
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
    case Shape::capsule:
      aabb_center = center;
      aabb_half = R.col(2).cwiseAbs() * half_height + Vec3::Constant(radius);
      break;
    case Shape::mesh:
      aabb_center = center + R * mesh->local_center;
      aabb_half = R.cwiseAbs() * mesh->local_half;
      break;
    case Shape::plane:
      break;
  }
  note_pose();
}

void Collider::follow(const Transform& body_pose, const Vec3& v, const Vec3& w) {
  prev_center = center;
  prev_R = R;
  if (offset_identity) {
    set_pose(body_pose);
    velocity = v;
  } else {
    const Quat q = body_pose.rotation.normalized();
    set_pose(Transform{body_pose.translation + q * offset.translation, q * offset.rotation});
    velocity = v + w.cross(center - body_pose.translation);
  }
  angular_velocity = w;
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

namespace {

std::shared_ptr<const MeshShape> make_mesh(const ShapeDef& def, const std::string& what) {
  if (def.triangles.empty()) throw std::invalid_argument(what + ".triangles must not be empty");
  for (const Vec3& v : def.vertices)
    if (!v.allFinite()) throw std::invalid_argument(what + ".vertices must be finite");
  auto shape = std::make_shared<MeshShape>();
  shape->triangles.reserve(def.triangles.size());
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  edges.reserve(3 * def.triangles.size());
  for (std::size_t t = 0; t < def.triangles.size(); ++t) {
    const auto& tri = def.triangles[t];
    for (std::uint32_t k : tri)
      if (k >= def.vertices.size()) {
        std::ostringstream m;
        m << what << ".triangles[" << t << "] refers to vertex " << k << " of "
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
    throw std::invalid_argument(what + ".triangles are all degenerate (zero area)");
  std::sort(edges.begin(), edges.end());
  bool closed = true;
  for (std::size_t i = 0; i < edges.size() && closed;) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    closed = j - i == 2;
    i = j;
  }
  shape->closed = closed;
  // Sharp convex and open edges with their vertices (cloth contacts, cloth_contacts.hpp).
  {
    std::vector<std::array<std::uint32_t, 3>> he;  // (i, j, kept triangle)
    for (std::size_t t = 0, kept = 0; t < def.triangles.size(); ++t) {
      const auto& tri = def.triangles[t];
      const Vec3 n = (def.vertices[tri[1]] - def.vertices[tri[0]])
                         .cross(def.vertices[tri[2]] - def.vertices[tri[0]]);
      if (!(n.norm() > 0.0)) continue;
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t i = tri[std::size_t(k)], j = tri[std::size_t((k + 1) % 3)];
        he.push_back({std::min(i, j), std::max(i, j), std::uint32_t(kept)});
      }
      ++kept;
    }
    std::sort(he.begin(), he.end());
    std::vector<std::int64_t> remap(def.vertices.size(), -1);
    auto vid = [&](std::uint32_t v) {
      if (remap[v] < 0) {
        remap[v] = std::int64_t(shape->sharp_vertices.size());
        shape->sharp_vertices.push_back(def.vertices[v]);
      }
      return std::uint32_t(remap[v]);
    };
    const double cos_sharp = std::cos(20.0 * 3.14159265358979323846 / 180.0);
    for (std::size_t i = 0; i < he.size();) {
      std::size_t j = i;
      while (j < he.size() && he[j][0] == he[i][0] && he[j][1] == he[i][1]) ++j;
      bool sharp = j - i != 2;
      if (!sharp) {
        const Triangle& t1 = shape->triangles[he[i][2]];
        const Triangle& t2 = shape->triangles[he[i + 1][2]];
        const Vec3 c2 = (t2.a + t2.b + t2.c) / 3.0;
        const bool convex = (c2 - def.vertices[he[i][0]]).dot(t1.normal) < 0.0;
        sharp = convex && t1.normal.dot(t2.normal) < cos_sharp;
      }
      if (sharp) {
        shape->sharp_edges.push_back({vid(he[i][0]), vid(he[i][1])});
        Vec3 out = Vec3::Zero();
        if (j - i == 2)
          out = shape->triangles[he[i][2]].normal + shape->triangles[he[i + 1][2]].normal;
        shape->sharp_edge_out.push_back(out);
        shape->sharp_vertex_out.resize(shape->sharp_vertices.size(), Vec3::Zero());
        shape->sharp_vertex_out[remap[he[i][0]]] += out;
        shape->sharp_vertex_out[remap[he[i][1]]] += out;
      }
      i = j;
    }
  }
  shape->bvh = Bvh(shape->triangles);
  shape->grid = MeshGrid(shape->triangles, shape->bvh.visit_order());
  const Aabb& b = shape->bvh.bounds();
  shape->local_center = 0.5 * (b.lo + b.hi);
  shape->local_half = 0.5 * (b.hi - b.lo);
  return shape;
}

}  // namespace

Collider make_collider(const ShapeDef& def, const std::string& what) {
  Collider c;
  switch (def.type) {
    case ShapeType::plane:
      if (!def.normal.allFinite() || !(def.normal.norm() > 1e-12)) {
        std::ostringstream m;
        m << what << ".normal must be finite and non-zero (got (" << def.normal.transpose()
          << "))";
        throw std::invalid_argument(m.str());
      }
      c.shape = Collider::Shape::plane;
      c.local_normal = def.normal.normalized();
      c.normal = c.local_normal;
      break;
    case ShapeType::sphere:
      require_in(def.radius, ranges::kColliderSize, what + ".radius");
      c.shape = Collider::Shape::sphere;
      break;
    case ShapeType::box:
      for (int k = 0; k < 3; ++k)
        require_in(def.half_extents[k], ranges::kColliderSize,
                   what + ".half_extents[" + std::to_string(k) + "]");
      c.shape = Collider::Shape::box;
      break;
    case ShapeType::cylinder:
    case ShapeType::capsule:
      require_in(def.radius, ranges::kColliderSize, what + ".radius");
      require_in(def.half_height, ranges::kColliderSize, what + ".half_height");
      c.shape = def.type == ShapeType::cylinder ? Collider::Shape::cylinder
                                                : Collider::Shape::capsule;
      break;
    case ShapeType::mesh:
      c.mesh = make_mesh(def, what);
      c.shape = Collider::Shape::mesh;
      break;
    case ShapeType::convex_hull: {
      for (std::size_t i = 0; i < def.points.size(); ++i)
        if (!def.points[i].allFinite())
          throw std::invalid_argument(what + ".points[" + std::to_string(i) + "] must be finite");
      ConvexHull h;
      try {
        h = convex_hull(def.points);
      } catch (const std::exception& e) {
        // "convex_hull: all points are coplanar ..." -> "<what>.points: all points are coplanar ..."
        std::string m = e.what();
        if (m.rfind("convex_hull: ", 0) == 0) m = m.substr(13);
        throw std::invalid_argument(what + ".points: " + m + " (a convex hull needs at least 4 "
                                           "points that are not all in one plane)");
      }
      auto hull = std::make_shared<HullShape>();
      hull->faces = make_hull_faces(h.vertices, h.faces);
      for (const auto& t : h.triangles)
        hull->area += 0.5 * (h.vertices[t[1]] - h.vertices[t[0]])
                                .cross(h.vertices[t[2]] - h.vertices[t[0]])
                                .norm();
      ShapeDef m;
      m.type = ShapeType::mesh;
      m.vertices = h.vertices;
      m.triangles = h.triangles;
      c.mesh = make_mesh(m, what);
      hull->vertices = std::move(h.vertices);
      hull->triangles = std::move(h.triangles);
      c.hull = std::move(hull);
      c.shape = Collider::Shape::mesh;
      break;
    }
    default:
      throw std::invalid_argument(what + ".type is not a shape type");
  }
  const bool round = def.type == ShapeType::sphere || def.type == ShapeType::cylinder ||
                     def.type == ShapeType::capsule;
  c.radius = round ? def.radius : 0.0;
  c.half_height = round && def.type != ShapeType::sphere ? def.half_height : 0.0;
  c.half_extents = def.type == ShapeType::box ? def.half_extents : Vec3::Zero();
  if (!def.offset.translation.allFinite() || !def.offset.rotation.coeffs().allFinite() ||
      !(def.offset.rotation.norm() > 1e-12))
    throw std::invalid_argument(what +
                                ".offset must be finite with a non-zero rotation quaternion");
  c.offset = def.offset;
  c.offset_identity = def.offset.translation == Vec3::Zero() && is_identity(def.offset.rotation);
  validate(def.material, what + ".material");
  c.material = def.material;
  return c;
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

}  // namespace simreel::sim::detail

namespace simreel::sim {

ShapeDef ShapeDef::sphere(double radius, const Transform& offset) {
  ShapeDef s;
  s.type = ShapeType::sphere;
  s.radius = radius;
  s.offset = offset;
  return s;
}

ShapeDef ShapeDef::box(const Vec3& half_extents, const Transform& offset) {
  ShapeDef s;
  s.type = ShapeType::box;
  s.half_extents = half_extents;
  s.offset = offset;
  return s;
}

ShapeDef ShapeDef::cylinder(double radius, double half_height, const Transform& offset) {
  ShapeDef s = sphere(radius, offset);
  s.type = ShapeType::cylinder;
  s.half_height = half_height;
  return s;
}

ShapeDef ShapeDef::capsule(double radius, double half_height, const Transform& offset) {
  ShapeDef s = cylinder(radius, half_height, offset);
  s.type = ShapeType::capsule;
  return s;
}

ShapeDef ShapeDef::convex_hull(std::vector<Vec3> points, const Transform& offset) {
  ShapeDef s;
  s.type = ShapeType::convex_hull;
  s.points = std::move(points);
  s.offset = offset;
  return s;
}

ShapeDef ShapeDef::plane(const Vec3& normal, const Transform& offset) {
  ShapeDef s;
  s.type = ShapeType::plane;
  s.normal = normal;
  s.offset = offset;
  return s;
}

}  // namespace simreel::sim
