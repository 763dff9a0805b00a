#pragma once
// Contact query between two posed convex shapes: GJK on the cores (Coutinho §4.7), and EPA on
// the cores when they overlap (van den Bergen 2001); either way the radii are added at the end,
// which is exact because the shapes' Minkowski difference is the cores' grown by ra + rb
// (van den Bergen 2003, §4.3.1). A core difference without volume (two sphere centres, a sphere
// centre on a capsule axis, crossing capsule axes) has depth ra + rb along its normal. One
// contact point pair: the base a manifold builder (face clipping, persistent manifolds)
// extends. Private.
//
// Convention: `normal` is unit and points from A to B (world); `depth` > 0 is penetration along
// it, depth < 0 a gap of -depth (signed distance = -depth); point_a on A's surface, point_b on
// B's, point_a - point_b = depth * normal (up to tolerance).

#include <cstdint>

#include "collision/epa.hpp"
#include "collision/gjk.hpp"

namespace simreel::sim::detail {

struct ConvexContact {
  bool touching = false;        ///< depth >= -margin
  double depth = 0.0;           ///< (m) penetration (> 0) or minus the gap (< 0)
  Vec3 normal = Vec3::UnitZ();  ///< unit, from A to B, world
  Vec3 point_a = Vec3::Zero();  ///< world (m), on A
  Vec3 point_b = Vec3::Zero();  ///< world (m), on B
  int gjk_iterations = 0;       ///< both GJK runs together
  int epa_iterations = 0;       ///< 0 unless the cores overlapped (growing the simplex included)
  bool exact_gap = true;        ///< false: separated beyond margin, -depth is only a lower bound
};

/// Contact between A and B with a contact margin (m, >= 0): pairs farther apart than the margin
/// stop early (touching false, depth a bound). `cache`, when given, warm-starts GJK from its
/// simplex and receives the new one (keep one per shape pair, in the same A/B order).
[[nodiscard]] ConvexContact collide(const PosedShape& A, const PosedShape& B, double margin = 0.0,
                                    GjkSimplex* cache = nullptr);

}  // namespace simreel::sim::detail
