#pragma once
// EPA: penetration depth of two overlapping convex shapes (van den Bergen 2001, "Proximity
// Queries and Penetration Depth Computation on 3D Game Objects", GDC; the expanding polytope
// of the Minkowski difference D = A - B, grown from GJK's final simplex). Each iteration takes
// the polytope face closest to the origin, adds D's support point along its normal, and
// replaces the faces that point sees by a fan over the horizon; it stops when the support
// point is no farther out than the face (relative tolerance). Private.
//
// Convention: `normal` points from A to B (world): translating B by depth * normal (or A by
// -depth * normal) makes the shapes just touch. point_a is A's point deepest inside B, point_b
// B's point deepest inside A; point_a - point_b = depth * normal.
//
// Bounded: at most max_iterations support evaluations, fixed-capacity buffers on the stack
// (kEpaMaxVertices, kEpaMaxFaces), no heap. When the polytope cannot be grown (D flat: two
// coplanar flat shapes) or a buffer would overflow, it returns the best face so far.

#include <cstdint>

#include "collision/gjk.hpp"

namespace simreel::sim::detail {

inline constexpr int kEpaMaxVertices = 128;
inline constexpr int kEpaMaxFaces = 256;

struct EpaOptions {
  int max_iterations = 64;  ///< support evaluations at most (<= kEpaMaxVertices - 4)
  /// Stop when the new support point lies within rel_tol * (size of D) of the closest face.
  double rel_tol = 1e-10;
};

enum class EpaStatus : std::uint8_t {
  converged,  ///< depth found to tolerance
  limit,      ///< iterations or capacity ran out: depth is a lower bound (best face so far)
  flat,       ///< D has no volume (no tetrahedron could be built): depth 0, normal approximate
};

struct EpaResult {
  EpaStatus status = EpaStatus::converged;
  double depth = 0.0;             ///< (m) >= 0, the minimum translation distance
  Vec3 normal = Vec3::UnitZ();    ///< unit, from A to B (world)
  Vec3 point_a = Vec3::Zero();    ///< world (m), on A's surface
  Vec3 point_b = Vec3::Zero();    ///< world (m), on B's surface
  int iterations = 0;             ///< support evaluations used (growing the simplex included)
};

/// Penetration of the `part`s of A and B, which must overlap (GJK status overlap); `start` is
/// GJK's final simplex (1–4 vertices; grown to a tetrahedron here). Never throws, never hangs;
/// finite output for any finite input.
[[nodiscard]] EpaResult epa_penetration(const PosedShape& A, const PosedShape& B,
                                        const GjkSimplex& start,
                                        ShapePart part = ShapePart::full,
                                        const EpaOptions& options = {});

}  // namespace simreel::sim::detail
