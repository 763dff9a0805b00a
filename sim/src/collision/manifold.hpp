#pragma once
// Contact manifold: the up-to-four contact points two convex shapes share, one normal for all
// of them, and for each point the pair of features (vertex, edge, face) that made it. Plain
// data, fixed capacity (no heap). Private; built by collide_boxes() (box_box.hpp) and
// collide_manifold() (contact_manifold.hpp), carried from step to step by warm_start()
// (persistent_manifold.hpp).
//
// Why several points: GJK/EPA (Coutinho §4.7) gives one closest-point pair; a box resting on a
// face then rocks about that point. Coutinho §4.4 replaces the face–face case by one
// vertex–face contact per face vertex; the points here are that idea made robust by clipping
// (Sutherland–Hodgman), as in Box2D (`b2ClipPolygons`), Jolt (`ManifoldBetweenTwoFaces`) and
// Bullet (`btBoxBoxDetector`).
//
// Conventions (world frame, metres):
//   - `normal` is unit and points from A to B;
//   - separation = (point_b - point_a) · normal: > 0 a gap, < 0 a penetration of that depth;
//   - point_a lies on A's surface, point_b on B's;
//   - points are in a deterministic order (the same input gives the same order).

#include <array>
#include <cstdint>
#include <utility>

#include "simreel/sim/types.hpp"

namespace simreel::sim::detail {

inline constexpr int kMaxManifoldPoints = 4;

/// Kind of a shape feature in a FeatureId.
enum class FeatureType : std::uint8_t {
  none,    ///< unset
  vertex,  ///< a polytope vertex or a capsule/segment end
  edge,    ///< a polytope edge or a capsule core segment
  face,    ///< a planar face (polytope face, cylinder cap)
  shape,   ///< the shape as a whole: a closest point on a curved surface (sphere, rim)
};

/// Which feature of A and which of B made a contact point. Stable while the contact persists
/// (the same two features touch), so a solver can match points across steps (warm starting).
/// Indices: a vertex is its vertex index (box: bit 0/1/2 set for +x/+y/+z); a face its face index
/// (box: 2 * axis + 1 for the negative side); a polytope edge is either a box edge
/// (4 * axis + 2 * [u > 0] + [v > 0], u, v the two other axes in cyclic order) or an edge of a face
/// polygon, (face << 16) | (edge k from polygon vertex k to k + 1). Compare with ==.
struct FeatureId {
  FeatureType type_a = FeatureType::none;
  FeatureType type_b = FeatureType::none;
  std::uint32_t index_a = 0;
  std::uint32_t index_b = 0;

  bool operator==(const FeatureId&) const = default;
  /// The same id seen with A and B exchanged.
  [[nodiscard]] FeatureId swapped() const { return {type_b, type_a, index_b, index_a}; }
};

/// One contact point of a manifold, with the solver's accumulated impulses that warm starting
/// carries from one step to the next.
struct ManifoldPoint {
  Vec3 point_a = Vec3::Zero();  ///< (m) world, on A's surface
  Vec3 point_b = Vec3::Zero();  ///< (m) world, on B's surface
  double separation = 0.0;      ///< (m) (point_b - point_a) · normal; < 0 is penetration
  FeatureId id;
  double normal_impulse = 0.0;  ///< (N s) accumulated along the normal, >= 0; 0 when built
  /// (N s) accumulated friction impulse applied to B (A receives the opposite), world frame,
  /// perpendicular to the normal: a world vector, so it does not depend on a tangent basis that
  /// may turn between steps; 0 when built.
  Vec3 tangent_impulse = Vec3::Zero();
};

/// Contact points of one shape pair. count 0: the shapes are farther apart than the margin.
struct Manifold {
  std::array<ManifoldPoint, kMaxManifoldPoints> points{};
  int count = 0;
  Vec3 normal = Vec3::UnitZ();  ///< unit, world, from A to B (meaningless when count == 0)

  /// Most negative separation (m), +infinity-like (1e300) when empty.
  [[nodiscard]] double min_separation() const {
    double s = 1e300;
    for (int i = 0; i < count; ++i) s = points[i].separation < s ? points[i].separation : s;
    return s;
  }
};

/// The same manifold with A and B exchanged: normal negated, point_a/point_b and the two halves
/// of every id swapped, impulses negated (B's impulse on A is the opposite one); order kept.
[[nodiscard]] inline Manifold swapped(const Manifold& m) {
  Manifold s = m;
  s.normal = -m.normal;
  for (int i = 0; i < m.count; ++i) {
    ManifoldPoint& p = s.points[i];
    std::swap(p.point_a, p.point_b);
    p.id = m.points[i].id.swapped();
    p.tangent_impulse = -m.points[i].tangent_impulse;
  }
  return s;
}

/// Settings of the manifold builders.
struct ManifoldOptions {
  /// (m) Speculative margin >= 0: points separated by up to this are kept (a solver uses them to
  /// stop an approaching body before it penetrates); pairs farther apart give no points.
  double margin = 0.0;
  /// A face axis is kept over a (slightly better) edge axis, and A's face over B's, unless the
  /// other separates by more than bias_abs + bias_rel * |separation| (m): resting stacks then
  /// keep their reference face from step to step instead of flickering between axes (Box2D's
  /// `0.1 * linearSlop` flip tolerance; Bullet's box–box 1.05 fudge factor).
  double bias_abs = 5e-4;
  double bias_rel = 0.05;
  /// Sine of the largest angle at which a cylinder's axis counts as parallel (side on a face) or
  /// perpendicular (cap on a face) to the reference face, and two capsule axes as parallel.
  double parallel_sin = 0.02;
};

}  // namespace simreel::sim::detail
