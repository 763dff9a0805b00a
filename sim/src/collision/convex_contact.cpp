// Convex contact query: GJK, then EPA, on the cores; radii added (see convex_contact.hpp).
#include "collision/convex_contact.hpp"

namespace simreel::sim::detail {

ConvexContact collide(const PosedShape& A, const PosedShape& B, double margin,
                      GjkSimplex* cache) {
  ConvexContact c;
  const double ra = A.core_radius(), rb = B.core_radius(), rsum = ra + rb;
  GjkOptions options;
  options.max_distance = margin + rsum;  // the cores' gap at which the shapes' gap is the margin
  const GjkResult g = gjk_distance(A, B, ShapePart::core, cache, options);
  c.gjk_iterations = g.iterations;
  if (cache != nullptr) *cache = g.simplex;
  if (g.status != GjkStatus::overlap) {
    // Disjoint cores: the shapes' signed distance is the cores' distance minus the radii,
    // exact even when the rounded shapes overlap.
    c.depth = rsum - g.distance;
    c.normal = g.normal;
    c.point_a = g.point_a + ra * g.normal;
    c.point_b = g.point_b - rb * g.normal;
    c.exact_gap = g.status == GjkStatus::separated;
    c.touching = c.exact_gap && c.depth >= -margin;
    return c;
  }
  // The cores intersect (a sphere centre inside a box, two capsule axes crossing). The full
  // shapes' Minkowski difference is the cores' grown by ra + rb, so their depth is the cores'
  // depth plus ra + rb, along the same normal: EPA runs on the cores (exact, where a rounded
  // surface would make EPA converge only slowly), and a flat core difference (point, segment,
  // polygon) has core depth 0 along its normal.
  const EpaResult e = epa_penetration(A, B, g.simplex, ShapePart::core);
  c.epa_iterations = e.iterations;
  c.depth = e.depth + rsum;
  c.normal = e.normal;
  c.point_a = e.point_a + ra * e.normal;
  c.point_b = e.point_b - rb * e.normal;
  c.touching = true;
  return c;
}

}  // namespace simreel::sim::detail
