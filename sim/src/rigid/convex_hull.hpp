#pragma once
// 3-D convex hull of a point cloud by quickhull (Barber, Dobkin & Huhdanpaa 1996, "The
// Quickhull Algorithm for Convex Hulls", ACM TOMS 22(4)); Coutinho §2.2.4 builds the same hull by
// gift wrapping, O(n h), where quickhull is O(n log n) on average. Private; convex-hull shapes
// of the rigid-body issue are built with it at registration, in the shape's local frame.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "simreel/sim/types.hpp"

namespace simreel::sim::detail {

struct ConvexHullOptions {
  /// Distance tolerance as a fraction of the bounding-box diagonal of the input. A point within
  /// the tolerance of a face's plane counts as on it (coplanar points and duplicates do not
  /// become vertices; nearly coplanar triangles are merged). The tolerance actually used is
  /// never below 16 ulp of the largest coordinate, so clouds far from the origin stay robust.
  double relative_tolerance = 1e-10;
  /// Merge coplanar triangles into planar polygons (`ConvexHull::faces`), drop the vertices that
  /// lie inside a face or on a straight edge, and re-triangulate each polygon as a fan. Off:
  /// the raw quickhull triangles, `faces` empty.
  bool merge_coplanar = true;
};

/// A closed convex polyhedron: outward-wound triangles over a subset of the input points.
struct ConvexHull {
  std::vector<Vec3> vertices;              ///< (V) positions (m), the input's frame
  std::vector<std::uint32_t> input_index;  ///< (V) index of each vertex in the input, ascending
  /// (F) vertex indices, counter-clockwise seen from outside (outward normal (b-a) × (c-a));
  /// closed and consistently oriented, ready for mesh_mass().
  std::vector<std::array<std::uint32_t, 3>> triangles;
  /// (P) with merge_coplanar: the planar faces as convex polygons of vertex indices,
  /// counter-clockwise seen from outside; `triangles` is their fan triangulation. Else empty.
  std::vector<std::vector<std::uint32_t>> faces;
  double tolerance = 0.0;  ///< (m) the distance tolerance that was used
};

/// Convex hull of `points` (n, m). Every input point lies behind or within `tolerance` of the
/// plane of every output triangle. Output order is deterministic (it depends only on the input).
///
/// Throws std::invalid_argument, saying which, for degenerate input: fewer than 4 points, a
/// non-finite point, all points coincident, all collinear, or all coplanar (within the
/// tolerance) — none of these bounds a volume. Throws std::runtime_error if rounding breaks the
/// construction (a horizon that is not a simple loop); not seen on the tested clouds.
ConvexHull convex_hull(std::span<const Vec3> points, const ConvexHullOptions& options = {});

}  // namespace simreel::sim::detail
