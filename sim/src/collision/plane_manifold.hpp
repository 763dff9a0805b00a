#pragma once
// Contact manifold of a convex shape (support.hpp kinds) against a plane or a triangle's plane
// (Coutinho §4.4: a face–face contact becomes one vertex–face contact per vertex of the face in
// contact). The plane is A, the convex B: normal = the plane's normal, point_a on the plane,
// point_b on the convex. Candidate points are the features that can reach the plane — the box's
// 8 corners, a hull's vertices, a capsule's two end caps, a cylinder's rim points (four per cap,
// the inscribed square as in contact_manifold.hpp), a sphere's lowest point — kept when their
// separation is within the margin and reduced to the 4 that span the largest area (deepest
// first). Ids: A's feature is the plane face (0), B's the candidate's vertex index, so
// warm_start() carries impulses of a resting box corner by corner. Private; no heap.

#include "collision/manifold.hpp"
#include "collision/support.hpp"

namespace simreel::sim::detail {

/// Manifold of the plane through `point` (world, m) with unit outward `normal` (world) against
/// B. When `triangle` is given (3 world points on the plane), only candidates whose projection
/// falls inside the triangle (grown by `margin`) are kept: a face contact of B on one triangle of
/// a mesh. Empty (count 0) when no candidate is within `margin` (m, >= 0).
[[nodiscard]] Manifold collide_plane(const Vec3& point, const Vec3& normal, const PosedShape& B,
                                     double margin, const Vec3* triangle = nullptr);

}  // namespace simreel::sim::detail
