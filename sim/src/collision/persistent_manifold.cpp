// Carrying accumulated impulses from one step's manifold to the next (see
// persistent_manifold.hpp).
#include "collision/persistent_manifold.hpp"

namespace simreel::sim::detail {

namespace {

Vec3 midpoint(const ManifoldPoint& p) { return 0.5 * (p.point_a + p.point_b); }

void carry(const ManifoldPoint& from, const Vec3& normal, ManifoldPoint& to) {
  to.normal_impulse = from.normal_impulse;
  // Friction acts in the tangent plane; the part of the old friction impulse along the new
  // normal would add to (or cancel) the normal impulse the solver controls.
  to.tangent_impulse = from.tangent_impulse - normal.dot(from.tangent_impulse) * normal;
}

}  // namespace

int warm_start(const Manifold& previous, Manifold& current, const WarmStartOptions& options) {
  for (int i = 0; i < current.count; ++i) {
    current.points[i].normal_impulse = 0.0;
    current.points[i].tangent_impulse = Vec3::Zero();
  }
  if (previous.count == 0 || current.count == 0) return 0;
  if (!(previous.normal.dot(current.normal) >= options.min_normal_cos)) return 0;

  bool old_used[kMaxManifoldPoints] = {};
  bool matched[kMaxManifoldPoints] = {};
  int carried = 0;
  // Ids first: the same pair of features is the same contact, however far it slid.
  for (int i = 0; i < current.count; ++i) {
    for (int j = 0; j < previous.count; ++j) {
      if (old_used[j] || !(previous.points[j].id == current.points[i].id)) continue;
      carry(previous.points[j], current.normal, current.points[i]);
      old_used[j] = matched[i] = true;
      ++carried;
      break;
    }
  }
  // Then the nearest unused old point within the distance (the first of equals).
  const double r2 = options.match_distance * options.match_distance;
  for (int i = 0; i < current.count; ++i) {
    if (matched[i]) continue;
    int best = -1;
    double best_d2 = 0.0;
    for (int j = 0; j < previous.count; ++j) {
      if (old_used[j]) continue;
      const double d2 = (midpoint(previous.points[j]) - midpoint(current.points[i])).squaredNorm();
      if (d2 <= r2 && (best < 0 || d2 < best_d2)) {
        best = j;
        best_d2 = d2;
      }
    }
    if (best < 0) continue;
    carry(previous.points[best], current.normal, current.points[i]);
    old_used[best] = matched[i] = true;
    ++carried;
  }
  return carried;
}

}  // namespace simreel::sim::detail
