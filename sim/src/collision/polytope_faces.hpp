#pragma once
// Planar faces of the shapes a manifold clips: the six faces of a box (a fixed table) and the
// merged planar faces of a convex hull (built once, at registration, from convex_hull's
// `faces`), plus the supporting feature a rounded or curved shape offers a face (capsule core
// segment; cylinder cap or side line). Private; used by collide_boxes() and collide_manifold().
//
// Frames: HullFaces is in the shape's local frame; the FacePolygons returned are world frame
// (m), through the PosedShape.

#include <cstdint>
#include <span>
#include <vector>

#include "collision/clip.hpp"
#include "collision/support.hpp"

namespace simreel::sim::detail {

/// The planar faces of a hull shape, local frame. Vertex indices refer to the hull shape's
/// `vertices` span (give ConvexShape::hull the same vertex array the faces were built on).
struct HullFaces {
  std::vector<Vec3> normals;           ///< (P) unit outward normals
  std::vector<std::uint32_t> start;    ///< (P + 1) face p is indices[start[p] .. start[p + 1])
  std::vector<std::uint32_t> indices;  ///< vertex indices, counter-clockwise seen from outside
  [[nodiscard]] int face_count() const { return int(normals.size()); }
};

/// Faces from a vertex array and convex polygons over it (ConvexHull::vertices and ::faces, or
/// any closed convex polyhedron wound counter-clockwise from outside). Normals by Newell's
/// method, so a polygon whose vertices are coplanar only to rounding still gets a good normal.
/// Allocates: call once per shape, at registration.
[[nodiscard]] HullFaces make_hull_faces(std::span<const Vec3> vertices,
                                        std::span<const std::vector<std::uint32_t>> faces);

/// A box vertex index: bit 0, 1, 2 set for the +x, +y, +z half extent.
[[nodiscard]] inline std::uint32_t box_vertex_id(bool px, bool py, bool pz) {
  return std::uint32_t(px) | std::uint32_t(py) << 1 | std::uint32_t(pz) << 2;
}
/// The box edge parallel to `axis` at the (u, v) signs of the two other axes in cyclic order.
[[nodiscard]] inline std::uint32_t box_edge_id(int axis, bool pu, bool pv) {
  return std::uint32_t(4 * axis + 2 * int(pu) + int(pv));
}

/// Whether faces can be clipped on this shape: a box, or a hull with faces given.
[[nodiscard]] inline bool has_faces(const PosedShape& s, const HullFaces* faces) {
  return s.shape.kind == ConvexKind::box ||
         (s.shape.kind == ConvexKind::hull && faces != nullptr && faces->face_count() > 0);
}

/// The face of a polytope (has_faces) whose outward world normal has the largest dot product
/// with `dir` (any length); the first of equals. Writes that dot product (of unit normal and
/// unit dir) to `alignment` when given.
[[nodiscard]] int most_aligned_face(const PosedShape& s, const HullFaces* faces, const Vec3& dir,
                                    double* alignment = nullptr);

/// Face `face` of a polytope as a world polygon (vertices, ids, outward normal, index). Returns
/// false (out.count 0) when the face has more than kMaxClipVertices vertices.
bool face_polygon(const PosedShape& s, const HullFaces* faces, int face, FacePolygon& out);

/// The feature of a capsule or cylinder that rests on a face whose outward normal is `n` (world,
/// pointing toward the shape): the capsule's core segment (radius kept in out.radius); the
/// cylinder's bottom cap as an inscribed square of four rim points when its axis is within
/// parallel_sin of n, its lowest side line when the axis is within parallel_sin of the face.
/// Returns false when there is none (a tilted cylinder, a sphere, any other kind). Ids: capsule
/// segment edge 0 with ends 0 (-z) and 1 (+z); cylinder cap face 0 (+z) or 1 (-z) with rim
/// vertices 0–3 (+z) or 4–7 (-z); cylinder side line edge 0 with ends 8 (-z) and 9 (+z).
bool rounded_feature(const PosedShape& s, const Vec3& n, double parallel_sin, FacePolygon& out);

}  // namespace simreel::sim::detail
