#pragma once
// Box–box contact manifold: the separating-axis test over the 15 candidate axes (the 3 face
// normals of each box and the 9 cross products of their edge directions; Gottschalk, Lin &
// Manocha 1996, "OBBTree", and Coutinho §2.4's box–box overlap test), then
//   - a face axis: the incident face of the other box (the face most anti-parallel to the
//     reference normal) clipped against the reference face (clip.hpp): up to 4 points;
//   - an edge axis: one point, the closest points of the two edges.
// Face axes are preferred over edge axes, and A's face over B's, within
// ManifoldOptions::bias_abs + bias_rel * |separation|, so resting stacks keep their reference
// face from step to step. Private.
//
// Conventions as in manifold.hpp: normal unit from A to B, separation (m) < 0 is penetration.

#include "collision/manifold.hpp"
#include "collision/support.hpp"

namespace simreel::sim::detail {

/// Manifold of two posed boxes (both shapes ConvexKind::box; asserts otherwise). Empty (count 0)
/// when some axis separates them by more than options.margin. Deterministic; no heap.
[[nodiscard]] Manifold collide_boxes(const PosedShape& A, const PosedShape& B,
                                     const ManifoldOptions& options = {});

/// Closest points of segments p0-p1 and q0-q1 (world, m): writes them to `on_p`, `on_q`.
/// Parallel segments get the pair at the middle of their overlap (one well-defined answer).
/// Ericson 2005, "Real-Time Collision Detection", §5.1.9, with the parallel case made symmetric.
/// The same as parameters s, t in [0, 1] of on_p = p0 + s (p1 - p0), on_q = q0 + t (q1 - q0)
/// (the cloth's edge–edge contacts use them as barycentric weights).
void closest_parameters_of_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0,
                                    const Vec3& q1, double& s, double& t);
void closest_points_of_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1,
                                Vec3& on_p, Vec3& on_q);

}  // namespace simreel::sim::detail
