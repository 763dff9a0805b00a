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
///
/// Issue 16: a vertex that a kinematic body pushed this step is held like a pin (the body has
/// the last word). When such a body pushed the sheet at all and the start of the step is itself
/// over the limit (the body stretched it at the end of the last step), no point of the paths is
/// within the limit; rewinding then froze the sheet around the body, which stretched it without
/// end (a ball rising under a sheet on the floor doubled its size). The start is first brought
/// within the limit by Provot's projection (project_origin), and the pass runs again from there;
/// a vertex's velocity then follows its corrected displacement from x_start.
bool Cloth::State::max_deformation_pass() {
  if (!std::isfinite(def.max_strain)) return false;
  const std::size_t passes_before = strain_passes;
  const ClothTopology& T = *topo;
  const double stretch_max = 1.0 + def.max_strain;
  // Solve for a limit a hair inside the true one so rounding never leaves a spring over it.
  const double target_scale = stretch_max * (1.0 - 1e-9);
  // A vertex a kinematic body pushed this step is held like a pin: the body has the last word
  // against the strain limit, and the sheet around it follows (project_origin).
  bool pushed = false;
  for (std::size_t i = 0; i < n; ++i) {
    held[i] = !free[i] || hit[i] == 2;
    pushed = pushed || hit[i] == 2;
  }
  for (std::size_t i = 0; i < n; ++i) {
    origin[i] = held[i] ? x[i] : x_start[i];
    path[i] = x[i] - origin[i];
    t[i] = 1.0;
    changed_in[i] = -1;
  }
  constexpr std::size_t kMaxPasses = 64;
  bool any_moved = false, origin_over = false, projected = false, origin_moved = false;
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
      if (book_pass && pushed && !projected &&
          (origin[a] - origin[b]).squaredNorm() > stretch_max * stretch_max * L * L)
        origin_over = true;
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
      if (!held[a] && tp * ta < tw[a]) { tw[a] = tp * ta; changed = moved = true; changed_in[a] = pass; }
      if (!held[b] && tp * tb < tw[b]) { tw[b] = tp * tb; changed = moved = true; changed_in[b] = pass; }
      if (!moved) changed_in[a] = changed_in[b] = pass;  // still over: look again next pass
    }
    if (!violated) break;
    ++strain_passes;
    any_moved = true;
    if (origin_over && !projected) {
      projected = true;
      // The start of the step is itself over the limit (a kinematic body had the last word at
      // the end of the previous step): no point of the paths is within it. The start is first
      // brought within the limit by Provot's projection, then the book's pass runs again.
      origin_moved = project_origin(target_scale);
      for (std::size_t i = 0; i < n; ++i) {
        path[i] = held[i] ? Vec3::Zero() : Vec3(x[i] - origin[i]);
        t[i] = 1.0;
        changed_in[i] = -1;
      }
      strain_passes = passes_before;
      continue;
    }
    if (book_pass)
      for (std::size_t i = 0; i < n; ++i) t[i] = t_next[i];
    if (!changed && strain_passes - passes_before > kMaxPasses) break;  // only the start state itself violates
  }
  if (!any_moved) return false;
  for (std::size_t i = 0; i < n; ++i) {
    if (origin_moved && free[i] && held[i]) {  // held, slid by project_origin
      v[i] += (origin[i] - x[i]) / step_h;
      x[i] = origin[i];
      continue;
    }
    if (held[i] || t[i] == 1.0) continue;
    x[i] = origin[i] + t[i] * path[i];
    // Velocity consistent with the corrected displacement over the step: the displacement is
    // t (x - x_start) + (1 - t) (origin - x_start), and h v was x - x_start.
    v[i] *= t[i];
    if (origin_moved) v[i] += (1.0 - t[i]) / step_h * (origin[i] - x_start[i]);
  }
  return true;
}

/// Provot 1995 (the model Coutinho §3.9.2 follows, p. 152): every stretch or shear spring longer
/// than the limit at the start of the step has its free ends moved towards each other along it,
/// each by half the excess (all of it when the other end cannot move), Gauss-Seidel in spring
/// order, until none is over `scale` × rest length or kProjectSweeps sweeps ran. Vertices held by
/// a kinematic body do not move in the first stage. If only springs between two held vertices
/// are then left over the limit (the body stretched the sheet where it touches it, a sheet that
/// is free to follow), a second stage lets held vertices slide along the body's tangent plane
/// (or away from it), which keeps them outside a convex body. Otherwise the body stretches a
/// sheet held elsewhere (pins): it wins, and the held vertices stay. Returns true if it moved
/// an origin.
bool Cloth::State::project_origin(double scale) {
  constexpr int kProjectSweeps = 256;
  constexpr double kInside = 1.0 - 1e-4, kUnresolved = 1.0 + 1e-3;
  const ClothTopology& T = *topo;
  bool moved = false;
  const auto project = [&](bool slide_held) {
    const auto slide = [&](std::uint32_t i, Vec3 c) -> Vec3 {
      if (free[i] && held[i]) c -= std::min(0.0, c.dot(pushed_normal[i])) * pushed_normal[i];
      return c;
    };
    for (int sweep = 0; sweep < kProjectSweeps; ++sweep) {
      bool over = false;
      for (std::size_t s = 0; s < T.limited_count; ++s) {
        const std::uint32_t a = T.spring_a[s], b = T.spring_b[s];
        const bool ma = free[a] && (slide_held || !held[a]), mb = free[b] && (slide_held || !held[b]);
        if (!ma && !mb) continue;
        const Vec3 d = origin[b] - origin[a];
        const double l = d.norm(), L = T.rest_length[s];
        // Corrected a little past the limit, so a sweep's later corrections, which pull a
        // corrected spring out again, seldom take it back over: the sweeps end when one
        // corrects nothing, so every spring is then within the limit.
        if (!(l > kInside * scale * L)) continue;
        over = true;
        const double wa = ma ? 1.0 : 0.0, wb = mb ? 1.0 : 0.0;
        const Vec3 corr = (l - kInside * kInside * scale * L) / (l * (wa + wb)) * d;
        if (ma) origin[a] += slide(a, corr);
        if (mb) origin[b] += slide(b, -corr);
        moved = true;
      }
      if (!over) return;
    }
  };
  project(false);
  // A spring with a vertex free to move still over the limit by more than the first stage's
  // convergence leaves: the body wins.
  bool over = false;
  for (std::size_t s = 0; s < T.limited_count; ++s) {
    const std::uint32_t a = T.spring_a[s], b = T.spring_b[s];
    const double l = (origin[b] - origin[a]).norm(), L = T.rest_length[s];
    if (l <= scale * L) continue;
    over = true;
    if (l > kUnresolved * scale * L && ((free[a] && !held[a]) || (free[b] && !held[b])))
      return moved;
  }
  if (over) project(true);
  return moved;
}

}  // namespace simreel::sim
