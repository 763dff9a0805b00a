#pragma once
// GJK distance between two posed convex shapes (Gilbert, Johnson & Keerthi 1988; Coutinho §4.7,
// eqs. 4.36–4.48; van den Bergen 1999, "A Fast and Robust GJK Implementation for Collision
// Detection of Convex Objects", for the termination tests). The sub-algorithm that finds the
// closest point of the current simplex is the *signed-volume* one (Montanari, Petrinic &
// Barbieri 2017, "Improving the GJK algorithm for faster and more reliable distance queries
// between convex objects"): barycentric coordinates of the origin's projection from signed
// lengths, areas and volumes, recursing only into the sub-faces whose coordinate is not
// positive, and into all of them when a simplex is degenerate (collinear or coplanar), so
// Johnson's ill-conditioned determinant tests are never needed. Private.
//
// Convention: the Minkowski difference is D = A - B; v is its point closest to the origin,
// v = point_a - point_b; the separating normal points from A to B: normal = -v / |v|.

#include <array>
#include <cstdint>
#include <limits>

#include "collision/support.hpp"

namespace simreel::sim::detail {

/// One vertex of a GJK simplex: w = a - b, with a on A and b on B (world frame, m), and a, b in
/// their shapes' local frames (what a persistent contact keeps to warm-start the next step).
struct SimplexVertex {
  Vec3 w = Vec3::Zero();
  Vec3 a = Vec3::Zero();
  Vec3 b = Vec3::Zero();
  Vec3 a_local = Vec3::Zero();
  Vec3 b_local = Vec3::Zero();
};

/// A simplex of 0–4 vertices of D (count 0: none, start cold).
struct GjkSimplex {
  std::array<SimplexVertex, 4> v;
  int count = 0;
};

struct GjkOptions {
  int max_iterations = 64;  ///< support evaluations at most (it never loops past this)
  /// Stop when |v|² - v·w <= rel_tol |v|²: the distance is then known to a relative error of
  /// about rel_tol (van den Bergen 1999, §4; Coutinho eq. 4.48's lower bound v·w / |v|).
  /// Polytopes and rounded cores end exactly; against a curved surface (the cylinder's rim)
  /// the distance converges to rel_tol but the normal only to about sqrt(rel_tol).
  double rel_tol = 1e-10;
  /// The shapes count as overlapping when |v| <= overlap_tol * max |w| over the simplex (the
  /// origin is on the simplex up to rounding).
  double overlap_tol = 1e-12;
  /// (m) Early out: stop once the lower bound v·w / |v| exceeds this (a broad-phase pair that
  /// is farther apart than a contact margin needs no exact distance). Infinity: never.
  double max_distance = std::numeric_limits<double>::infinity();
};

enum class GjkStatus : std::uint8_t {
  separated,  ///< distance > 0 found to tolerance; points and normal valid
  overlap,    ///< the parts intersect (or touch to rounding): distance 0, run EPA for depth
  beyond,     ///< stopped early: distance is a lower bound > max_distance; points approximate
};

struct GjkResult {
  GjkStatus status = GjkStatus::separated;
  double distance = 0.0;          ///< (m) between the sampled parts, >= 0; 0 on overlap
  Vec3 point_a = Vec3::Zero();    ///< closest point on A, world (m)
  Vec3 point_b = Vec3::Zero();    ///< closest point on B, world (m)
  Vec3 normal = Vec3::UnitZ();    ///< unit, from A to B (world); unit z on overlap (undefined)
  int iterations = 0;             ///< support evaluations used
  GjkSimplex simplex;             ///< final simplex: the start of EPA, the warm-start cache
};

/// Distance between the `part`s (cores or full shapes) of A and B. `warm`, when given and not
/// empty, is a previous call's simplex (its local points are re-posed; the shapes must be the
/// same); otherwise GJK starts from the support along the centre difference. Never throws;
/// always returns after at most max_iterations support evaluations with finite values.
[[nodiscard]] GjkResult gjk_distance(const PosedShape& A, const PosedShape& B,
                                     ShapePart part = ShapePart::core,
                                     const GjkSimplex* warm = nullptr,
                                     const GjkOptions& options = {});

/// The closest point of a simplex (1–4 vertices w) to the origin, with barycentric weights over
/// the vertices it keeps. Exposed for the tests.
struct SimplexClosest {
  std::array<int, 4> index{};        ///< kept vertices, increasing
  std::array<double, 4> lambda{};    ///< their weights, sum 1, each > 0 except in a 1-simplex
  int count = 0;
  Vec3 v = Vec3::Zero();             ///< closest point (zero when the origin is inside a tetrahedron)
};
[[nodiscard]] SimplexClosest closest_on_simplex(const std::array<Vec3, 4>& w, int count);

}  // namespace simreel::sim::detail
