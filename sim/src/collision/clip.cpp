// Sutherland–Hodgman clipping of an incident face against a reference face, with feature ids
// (see clip.hpp).
#include "collision/clip.hpp"

#include <algorithm>
#include <cmath>

namespace simreel::sim::detail {

namespace {

/// A vertex of the polygon being clipped. id.a = reference feature, id.b = incident feature (the
/// A/B order is fixed when the points are written). The edge that leaves the vertex toward the
/// next one is either part of an incident edge or lies along a reference side plane: a new
/// vertex on that edge takes its feature from it.
struct ClipVertex {
  Vec3 p = Vec3::Zero();
  FeatureId id;
  bool out_on_reference = false;  ///< the outgoing edge lies along reference side plane out_index
  std::uint32_t out_index = 0;    ///< that side plane's index, or the incident edge's id
};

using ClipBuffer = std::array<ClipVertex, kMaxClipVertices>;

/// Id of the reference corner where side planes k0 and k1 meet (adjacent in a convex polygon).
FeatureId corner_id(const FacePolygon& ref, const FacePolygon& inc, int k0, int k1) {
  const int n = ref.count;
  FeatureId id{FeatureType::vertex, inc.type, 0, inc.index};
  if ((k0 + 1) % n == k1) {
    id.index_a = ref.vertex_ids[k1];
  } else if ((k1 + 1) % n == k0) {
    id.index_a = ref.vertex_ids[k0];
  } else {
    // Two non-adjacent planes meeting inside the face only happens to rounding: name the point
    // by the later plane's edge so the id stays well defined.
    id.type_a = FeatureType::edge;
    id.index_a = polygon_edge_id(ref, k1);
  }
  return id;
}

/// The id of a point where the edge leaving `from` crosses side plane k.
FeatureId crossing_id(const FacePolygon& ref, const FacePolygon& inc, const ClipVertex& from,
                      int k) {
  if (from.out_on_reference) return corner_id(ref, inc, int(from.out_index), k);
  return {FeatureType::edge, FeatureType::edge, polygon_edge_id(ref, k), from.out_index};
}

/// Clips the closed polygon `in` (n vertices) by side plane k (outward normal m through q):
/// keeps the part with m·(p - q) <= eps. Returns the new count (at most n + 1).
int clip_polygon(const FacePolygon& ref, const FacePolygon& inc, const ClipBuffer& in, int n,
                 int k, const Vec3& m, const Vec3& q, double eps, ClipBuffer& out) {
  int count = 0;
  for (int i = 0; i < n; ++i) {
    const ClipVertex& a = in[i];
    const ClipVertex& b = in[(i + 1) % n];
    const double da = m.dot(a.p - q), db = m.dot(b.p - q);
    const bool a_in = da <= eps, b_in = db <= eps;
    if (a_in != b_in) {
      // The crossing point of edge a -> b. Its outgoing edge runs along the plane when b is
      // outside (toward the point where the polygon comes back in), else along a's edge.
      ClipVertex x;
      x.p = a.p + (da / (da - db)) * (b.p - a.p);
      x.id = crossing_id(ref, inc, a, k);
      x.out_on_reference = b_in ? a.out_on_reference : true;
      x.out_index = b_in ? a.out_index : std::uint32_t(k);
      out[count++] = x;
    }
    if (b_in) out[count++] = b;
  }
  return count;
}

}  // namespace

int reduce_contact_points(const Vec3* points, const double* separations, int n,
                          const Vec3& normal, std::array<int, kMaxManifoldPoints>& chosen) {
  if (n <= kMaxManifoldPoints) {
    for (int i = 0; i < n; ++i) chosen[i] = i;
    return n;
  }
  // The deepest point carries the largest force; the others widen the support polygon, which is
  // what keeps a resting body from rocking (Bullet's sortCachedPoints and Jolt's
  // PruneContactPoints make the same choice).
  int i0 = 0;
  for (int i = 1; i < n; ++i)
    if (separations[i] < separations[i0]) i0 = i;
  int i1 = -1;
  double best = -1.0;
  for (int i = 0; i < n; ++i) {
    const double d = (points[i] - points[i0]).squaredNorm();
    if (i != i0 && d > best) {
      best = d;
      i1 = i;
    }
  }
  const Vec3 e = points[i1] - points[i0];
  int i2 = -1, i3 = -1;
  double most = 0.0, least = 0.0;
  for (int i = 0; i < n; ++i) {
    if (i == i0 || i == i1) continue;
    const double area = normal.dot(e.cross(points[i] - points[i0]));
    if (area > most) {
      most = area;
      i2 = i;
    }
    if (area < least) {
      least = area;
      i3 = i;
    }
  }
  int count = 0;
  for (const int i : {i0, i1, i2, i3})
    if (i >= 0) chosen[count++] = i;
  // Ascending by insertion (four entries; std::sort here trips GCC 12's -Warray-bounds).
  for (int a = 1; a < count; ++a)
    for (int b = a; b > 0 && chosen[b - 1] > chosen[b]; --b) std::swap(chosen[b - 1], chosen[b]);
  return count;
}

bool clip_faces(const FacePolygon& reference, const FacePolygon& incident, double margin,
                bool reference_is_a, Manifold& out) {
  const FacePolygon& ref = reference;
  const FacePolygon& inc = incident;
  if (ref.count < 3 || inc.count < 2 || inc.count + ref.count > kMaxClipVertices) return false;
  const Vec3& n = ref.normal;

  // Points within eps outside a side plane count as inside: an incident vertex lying on the
  // plane to rounding (equal boxes stacked flush) then stays one point, not two near-duplicates.
  double scale = 0.0;
  for (int i = 1; i < ref.count; ++i)
    scale = std::max(scale, (ref.vertices[i] - ref.vertices[0]).cwiseAbs().maxCoeff());
  const double eps = 1e-9 * scale;

  ClipBuffer buf_a, buf_b;
  int count = 0;
  if (inc.count == 2) {
    // A segment (capsule core, cylinder side line): clip its parameter range [t0, t1] by each
    // side plane (Cyrus–Beck); Sutherland–Hodgman on a two-vertex "polygon" would double points.
    const Vec3 p0 = inc.vertices[0], p1 = inc.vertices[1];
    double t0 = 0.0, t1 = 1.0;
    FeatureId id0{FeatureType::face, FeatureType::vertex, ref.index, inc.vertex_ids[0]};
    FeatureId id1{FeatureType::face, FeatureType::vertex, ref.index, inc.vertex_ids[1]};
    for (int k = 0; k < ref.count; ++k) {
      const Vec3& q = ref.vertices[k];
      const Vec3 m = (ref.vertices[(k + 1) % ref.count] - q).cross(n);
      const double d0 = m.dot(p0 - q), d1 = m.dot(p1 - q);
      const double len = m.norm();
      const bool in0 = d0 <= eps * len, in1 = d1 <= eps * len;
      if (!in0 && !in1) {
        out.count = 0;
        return true;
      }
      const FeatureId cross{FeatureType::edge, FeatureType::edge, polygon_edge_id(ref, k),
                            polygon_edge_id(inc, 0)};
      if (!in0) {
        const double t = d0 / (d0 - d1);
        if (t > t0) {
          t0 = t;
          id0 = cross;
        }
      } else if (!in1) {
        const double t = d0 / (d0 - d1);
        if (t < t1) {
          t1 = t;
          id1 = cross;
        }
      }
    }
    if (t0 > t1) {
      out.count = 0;
      return true;
    }
    buf_a[0] = {p0 + t0 * (p1 - p0), id0};
    buf_a[1] = {p0 + t1 * (p1 - p0), id1};
    count = t1 > t0 ? 2 : 1;
  } else {
    for (int i = 0; i < inc.count; ++i) {
      buf_a[i].p = inc.vertices[i];
      buf_a[i].id = {FeatureType::face, FeatureType::vertex, ref.index, inc.vertex_ids[i]};
      buf_a[i].out_on_reference = false;
      buf_a[i].out_index = polygon_edge_id(inc, i);
    }
    count = inc.count;
    ClipBuffer* src = &buf_a;
    ClipBuffer* dst = &buf_b;
    for (int k = 0; k < ref.count && count > 0; ++k) {
      const Vec3& q = ref.vertices[k];
      Vec3 m = (ref.vertices[(k + 1) % ref.count] - q).cross(n);
      const double len = m.norm();
      if (!(len > 0.0)) continue;  // a repeated vertex: no plane
      m /= len;
      count = clip_polygon(ref, inc, *src, count, k, m, q, eps, *dst);
      std::swap(src, dst);
    }
    if (src != &buf_a) buf_a = *src;
  }

  // Keep the points at or below the margin; measure them from the reference plane.
  std::array<Vec3, kMaxClipVertices> on_ref;
  std::array<double, kMaxClipVertices> sep;
  std::array<int, kMaxClipVertices> keep;
  int kept = 0;
  for (int i = 0; i < count; ++i) {
    const double h = n.dot(buf_a[i].p - ref.vertices[0]);
    const double s = h - inc.radius;
    if (!(s <= margin)) continue;
    on_ref[kept] = buf_a[i].p - h * n;
    sep[kept] = s;
    keep[kept] = i;
    ++kept;
  }
  std::array<int, kMaxManifoldPoints> chosen{};
  const int m = reduce_contact_points(on_ref.data(), sep.data(), kept, n, chosen);

  out.count = m;
  out.normal = reference_is_a ? n : Vec3(-n);
  for (int j = 0; j < m; ++j) {
    const int c = chosen[j];
    const ClipVertex& v = buf_a[keep[c]];
    ManifoldPoint& p = out.points[j];
    p = ManifoldPoint{};
    const Vec3 on_inc = v.p - inc.radius * n;  // the rounded shape's surface below its core
    p.point_a = reference_is_a ? on_ref[c] : on_inc;
    p.point_b = reference_is_a ? on_inc : on_ref[c];
    p.separation = sep[c];
    p.id = reference_is_a ? v.id : v.id.swapped();
  }
  return true;
}

}  // namespace simreel::sim::detail
