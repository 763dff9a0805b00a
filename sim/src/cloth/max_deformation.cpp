// The maximum-deformation pass of Coutinho §3.9.2: springs stretched beyond max_strain are
// brought back by moving their vertices back along their paths of the step.
#include <algorithm>
#include <cmath>
#include <limits>

#include "cloth/cloth_state.hpp"

namespace simreel::sim {

/// Coutinho §3.9.2, the maximum-deformation pass. Each vertex moved along the straight path
/// x_start -> x; a stretch or shear spring longer than (1 + max_strain) L brings its two vertices
/// back along their paths to the common parameter t_p where it is exactly at the limit (the larger
/// root in [0, 1] of |k1 + t k2|² = d_max², eq. 3.106); a vertex on several such springs takes the
/// minimum t_p. Pinned vertices do not move back (their path is imposed): their end is taken as
/// both ends of their path. The book's one pass uses a common t per spring; with per-vertex minima
/// a spring whose two vertices took different t can still be over the limit, so the pass is
/// repeated (each repeat only shortens paths, and t = 0 everywhere is the valid start state) until
/// no spring is over the limit: a departure from the book, counted in ClothStats::strain_passes.
bool Cloth::State::max_deformation_pass() {
  if (!std::isfinite(def.max_strain)) return false;
  const std::size_t passes_before = strain_passes;
  const ClothTopology& T = *topo;
  const double stretch_max = 1.0 + def.max_strain;
  // Solve for a limit a hair inside the true one so rounding never leaves a spring over it.
  const double target_scale = stretch_max * (1.0 - 1e-9);
  for (std::size_t i = 0; i < n; ++i) {
    origin[i] = free[i] ? x_start[i] : x[i];
    path[i] = x[i] - origin[i];
    t[i] = 1.0;
    changed_in[i] = -1;
  }
  constexpr std::size_t kMaxPasses = 64;
  bool any_moved = false;
  for (;;) {
    bool violated = false, changed = false;
    // The first pass is the book's: every t_p from the positions the integrator gave, minima
    // applied together. Repeats (if needed) update t in place, which converges faster.
    const bool book_pass = strain_passes == passes_before;
    std::vector<double>& tw = book_pass ? t_next : t;
    if (book_pass)
      for (std::size_t i = 0; i < n; ++i) t_next[i] = t[i];
    // A repeat only revisits springs with an end whose t changed in the previous pass or this
    // one: every other spring has the positions it had when last found within the limit, so
    // skipping it changes nothing (the result is the same as checking all of them).
    const auto pass = std::int32_t(strain_passes - passes_before);
    for (std::size_t s = 0; s < T.limited_count; ++s) {
      const std::uint32_t a = T.spring_a[s], b = T.spring_b[s];
      if (!book_pass && changed_in[a] < pass - 1 && changed_in[b] < pass - 1) continue;
      const double L = T.rest_length[s];
      const Vec3 pa = origin[a] + t[a] * path[a], pb = origin[b] + t[b] * path[b];
      const double l2 = (pa - pb).squaredNorm();
      if (l2 <= stretch_max * stretch_max * L * L) continue;
      violated = true;
      double tp = 0.0;  // after kMaxPasses: both back to the start of the step (last resort)
      if (strain_passes - passes_before < kMaxPasses) {
        const Vec3 k1 = origin[a] - origin[b];
        const Vec3 k2 = t[a] * path[a] - t[b] * path[b];
        const double A = k2.squaredNorm();
        const double B = 2.0 * k1.dot(k2);
        const double dmax = target_scale * L;
        const double C = k1.squaredNorm() - dmax * dmax;
        const double disc = B * B - 4.0 * A * C;
        if (A > 0.0 && disc >= 0.0) {
          const double sq = std::sqrt(disc);
          const double qq = -0.5 * (B + std::copysign(sq, B));  // stable roots
          double r1 = qq / A, r2 = qq != 0.0 ? C / qq : r1;
          if (r1 > r2) std::swap(r1, r2);
          if (r2 >= 0.0 && r2 <= 1.0) tp = r2;
          else if (r1 >= 0.0 && r1 <= 1.0) tp = r1;
          else tp = std::clamp(-B / (2.0 * A), 0.0, 1.0);  // start over the limit: closest point
        } else if (A > 0.0) {
          tp = std::clamp(-B / (2.0 * A), 0.0, 1.0);
        }
      }
      const double ta = t[a], tb = t[b];
      bool moved = false;
      if (free[a] && tp * ta < tw[a]) { tw[a] = tp * ta; changed = moved = true; changed_in[a] = pass; }
      if (free[b] && tp * tb < tw[b]) { tw[b] = tp * tb; changed = moved = true; changed_in[b] = pass; }
      if (!moved) changed_in[a] = changed_in[b] = pass;  // still over: look again next pass
    }
    if (!violated) break;
    ++strain_passes;
    any_moved = true;
    if (book_pass)
      for (std::size_t i = 0; i < n; ++i) t[i] = t_next[i];
    if (!changed && strain_passes - passes_before > kMaxPasses) break;  // only the start state itself violates
  }
  if (!any_moved) return false;
  for (std::size_t i = 0; i < n; ++i) {
    if (!free[i] || t[i] == 1.0) continue;
    x[i] = origin[i] + t[i] * path[i];
    // Velocity consistent with the corrected displacement over the step.
    v[i] *= t[i];
  }
  return true;
}

}  // namespace simreel::sim
