// Box and hull faces, and the supporting features of capsules and cylinders (see
// polytope_faces.hpp).
#include "collision/polytope_faces.hpp"

#include <cmath>

namespace simreel::sim::detail {

HullFaces make_hull_faces(std::span<const Vec3> vertices,
                          std::span<const std::vector<std::uint32_t>> faces) {
  HullFaces h;
  h.normals.reserve(faces.size());
  h.start.reserve(faces.size() + 1);
  h.start.push_back(0);
  for (const auto& f : faces) {
    // Newell's normal: the polygon's vector area, exact for a planar polygon and the best
    // plane for one that is planar only to rounding.
    Vec3 area = Vec3::Zero();
    for (std::size_t i = 0; i < f.size(); ++i)
      area += vertices[f[i]].cross(vertices[f[(i + 1) % f.size()]]);
    h.normals.push_back(area.normalized());
    h.indices.insert(h.indices.end(), f.begin(), f.end());
    h.start.push_back(std::uint32_t(h.indices.size()));
  }
  return h;
}

int most_aligned_face(const PosedShape& s, const HullFaces* faces, const Vec3& dir,
                      double* alignment) {
  const Vec3 d = s.rotation.transpose() * dir.normalized();
  int best = 0;
  double best_dot = 0.0;
  if (s.shape.kind == ConvexKind::box) {
    // Face 2a is +axis a, face 2a + 1 is -axis a: the largest |d_a| wins, the first on a tie.
    best_dot = -1.0;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(d[a]) > best_dot) {
        best_dot = std::abs(d[a]);
        best = 2 * a + (d[a] < 0.0 ? 1 : 0);
      }
    }
  } else {
    best_dot = faces->normals[0].dot(d);
    for (int f = 1; f < faces->face_count(); ++f) {
      const double p = faces->normals[f].dot(d);
      if (p > best_dot) {
        best_dot = p;
        best = f;
      }
    }
  }
  if (alignment != nullptr) *alignment = best_dot;
  return best;
}

bool face_polygon(const PosedShape& s, const HullFaces* faces, int face, FacePolygon& out) {
  out.type = FeatureType::face;
  out.index = std::uint32_t(face);
  out.radius = 0.0;
  if (s.shape.kind == ConvexKind::box) {
    const int a = face / 2, u = (a + 1) % 3, v = (a + 2) % 3;
    const bool positive = face % 2 == 0;
    // Corners counter-clockwise about the outward normal: (u, v, a) is right-handed, so seen
    // from +a the order (-,-), (+,-), (+,+), (-,+) turns counter-clockwise; from -a reversed.
    static constexpr int kPos[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    static constexpr int kNeg[4][2] = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
    const auto& corner = positive ? kPos : kNeg;
    const Vec3& h = s.shape.half_extents;
    for (int k = 0; k < 4; ++k) {
      Vec3 local;
      bool plus[3];
      plus[a] = positive;
      plus[u] = corner[k][0] == 1;
      plus[v] = corner[k][1] == 1;
      for (int c = 0; c < 3; ++c) local[c] = plus[c] ? h[c] : -h[c];
      out.vertices[k] = s.to_world(local);
      out.vertex_ids[k] = box_vertex_id(plus[0], plus[1], plus[2]);
    }
    out.count = 4;
    out.normal = (positive ? 1.0 : -1.0) * s.rotation.col(a);
    return true;
  }
  const std::uint32_t b = faces->start[face], e = faces->start[face + 1];
  out.count = 0;
  if (e - b > std::uint32_t(kMaxClipVertices)) return false;
  for (std::uint32_t i = b; i < e; ++i) {
    const std::uint32_t vi = faces->indices[i];
    out.vertices[out.count] = s.to_world(s.shape.vertices[vi]);
    out.vertex_ids[out.count] = vi;
    ++out.count;
  }
  out.normal = s.rotation * faces->normals[face];
  return true;
}

bool rounded_feature(const PosedShape& s, const Vec3& n, double parallel_sin, FacePolygon& out) {
  const ConvexShape& sh = s.shape;
  const Vec3 axis = s.rotation.col(2);
  const double c = axis.dot(n);  // cosine between the shape's axis and the face normal
  out.normal = n;
  if (sh.kind == ConvexKind::capsule) {
    out.type = FeatureType::edge;
    out.index = 0;
    out.radius = sh.radius;
    out.count = 2;
    out.vertices[0] = s.to_world({0.0, 0.0, -sh.half_height});
    out.vertices[1] = s.to_world({0.0, 0.0, sh.half_height});
    out.vertex_ids[0] = 0;
    out.vertex_ids[1] = 1;
    return true;
  }
  if (sh.kind != ConvexKind::cylinder) return false;
  out.radius = 0.0;
  if (std::abs(c) >= std::sqrt(1.0 - parallel_sin * parallel_sin)) {
    // Standing on a cap: the cap facing the face (axis against n) as a square of rim points,
    // an inscribed square: every point is on the cylinder, the support area is 2/pi of the disc.
    // (Clipping needs no particular winding of the incident polygon.)
    const bool top = c < 0.0;
    const double z = top ? sh.half_height : -sh.half_height;
    const double r = sh.radius;
    const Vec3 rim[4] = {{r, 0.0, z}, {0.0, r, z}, {-r, 0.0, z}, {0.0, -r, z}};
    out.type = FeatureType::face;
    out.index = top ? 0 : 1;
    out.count = 4;
    for (int k = 0; k < 4; ++k) {
      out.vertices[k] = s.to_world(rim[k]);
      out.vertex_ids[k] = std::uint32_t(k + (top ? 0 : 4));
    }
    return true;
  }
  if (std::abs(c) <= parallel_sin) {
    // Lying on its side: the side line nearest the face, from cap rim to cap rim.
    const Vec3 d = s.rotation.transpose() * (-n);
    const double rho = std::hypot(d.x(), d.y());
    if (!(rho > 0.0)) return false;
    const double x = sh.radius * d.x() / rho, y = sh.radius * d.y() / rho;
    out.type = FeatureType::edge;
    out.index = 0;
    out.count = 2;
    out.vertices[0] = s.to_world({x, y, -sh.half_height});
    out.vertices[1] = s.to_world({x, y, sh.half_height});
    out.vertex_ids[0] = 8;
    out.vertex_ids[1] = 9;
    return true;
  }
  return false;
}

}  // namespace simreel::sim::detail
