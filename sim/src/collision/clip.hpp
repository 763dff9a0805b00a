#pragma once
// Face clipping: the contact points of a reference face and an incident face (or segment).
// The incident polygon is clipped against the side planes of the reference face
// (Sutherland & Hodgman 1974, "Reentrant Polygon Clipping", CACM 17(1)); the points that lie
// below the reference plane, or above it by no more than the speculative margin, are the
// contacts, reduced to at most four (the deepest, then the widest area). This is Coutinho §4.4's
// "face–face case as one vertex–face case per face vertex", with the face's vertices first cut
// to the part that actually faces the other face; Coutinho §4.7 clips an edge against a feature's
// Voronoi planes the same way. Private.
//
// Every clipped point records the features it came from: an incident vertex inside the
// reference face (reference face, incident vertex), an incident edge crossing a side plane
// (reference edge, incident edge), a reference corner inside the incident face (reference
// vertex, incident face). These ids are what warm starting matches across steps.
//
// Fixed capacity (kMaxClipVertices), no heap; faces with more vertices than the capacity allows
// are rejected (clip_faces returns false) and the caller falls back to one point.

#include <array>
#include <cstdint>

#include "collision/manifold.hpp"

namespace simreel::sim::detail {

/// Vertices a clipped polygon may hold: the incident face's plus one per reference side plane.
inline constexpr int kMaxClipVertices = 64;

/// A convex planar polygon of a shape (or a segment, count 2), world frame (m).
struct FacePolygon {
  std::array<Vec3, kMaxClipVertices> vertices;  ///< counter-clockwise seen from outside
  std::array<std::uint32_t, kMaxClipVertices> vertex_ids{};  ///< the shape's vertex index of each
  int count = 0;
  Vec3 normal = Vec3::UnitZ();  ///< unit outward normal of the face (reference faces only)
  /// face: a polygon (edge k is (index << 16) | k); edge: a segment whose edge id is `index`.
  FeatureType type = FeatureType::face;
  std::uint32_t index = 0;  ///< face index, or the segment's edge index
  double radius = 0.0;      ///< (m) the polygon is the core of a shape grown by this (capsule)
};

/// The id an edge k of `poly` (from vertex k to k + 1) gets.
[[nodiscard]] inline std::uint32_t polygon_edge_id(const FacePolygon& poly, int k) {
  return poly.type == FeatureType::face ? (poly.index << 16) | std::uint32_t(k) : poly.index;
}

/// Clips `incident` (a polygon of 3+ vertices or a segment of 2; counter-clockwise order not
/// needed) against the side planes of `reference` (a convex polygon, counter-clockwise about its
/// outward normal, which points toward the incident shape) and writes the contact points into
/// `out`: separation = distance above the reference plane minus incident.radius, at most
/// kMaxManifoldPoints, those with separation <= margin only. reference_is_a says whether the
/// reference face belongs to A (normal = reference normal) or to B (normal = its opposite);
/// ids are written A-first accordingly. Returns false (out untouched) when a polygon exceeds the
/// capacity; true otherwise, with out.count possibly 0 (nothing within the margin).
bool clip_faces(const FacePolygon& reference, const FacePolygon& incident, double margin,
                bool reference_is_a, Manifold& out);

/// Indices (ascending, so the input's cyclic order is kept) of at most kMaxManifoldPoints of the
/// n points to keep: the deepest (smallest separation, the first of equals), the one farthest
/// from it, then the two that span the largest triangles on either side of that line (normal:
/// the plane's orientation). Exposed for the tests. Returns how many were chosen (min(n, 4)).
int reduce_contact_points(const Vec3* points, const double* separations, int n,
                          const Vec3& normal, std::array<int, kMaxManifoldPoints>& chosen);

}  // namespace simreel::sim::detail
