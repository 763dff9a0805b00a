#pragma once
// Warm starting across steps: the accumulated impulses of last step's manifold are carried to
// this step's points that are "the same contact", so an iterative solver starts near its
// converged answer (a resting stack then needs few iterations and does not jitter). Matching is
// by feature id, as Box2D's `b2UpdateContact` does with its point ids; a point whose id is new
// (its features changed, or it came from GJK/EPA's single point) takes the impulse of the
// nearest old point within a distance (Bullet's btPersistentManifold matches by distance only).
// Old points that find no partner drop their impulse. Private.

#include "collision/manifold.hpp"

namespace simreel::sim::detail {

struct WarmStartOptions {
  /// (m) An unmatched new point takes an old point's impulse when their midpoints
  /// ((point_a + point_b) / 2, world) are this close: about the distance a contact point moves
  /// in one step at rest (Bullet's contact breaking threshold is 0.02 m).
  double match_distance = 0.01;
  /// Nothing is carried when the normal turned by more than acos of this: impulses along the
  /// old normal would push the wrong way.
  double min_normal_cos = 0.95;
};

/// Sets the impulses of `current`'s points from `previous` (same shape pair, same A/B order):
/// first every point whose id equals an old point's id, then the rest by nearest midpoint within
/// match_distance; each old point is used at most once. The carried friction impulse loses its
/// component along the new normal. Points that match nothing get zero impulses. Returns how many
/// points received an impulse. Deterministic (order of the points only).
int warm_start(const Manifold& previous, Manifold& current, const WarmStartOptions& options = {});

}  // namespace simreel::sim::detail
