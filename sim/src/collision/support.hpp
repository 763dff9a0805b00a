#pragma once
// Support mappings of convex shapes for GJK/EPA (Coutinho §4.7, eqs. 4.38–4.39: the support
// point S_B(p) is the point of B with the largest projection on p, and the support of the
// Minkowski difference A - B is S_A(p) - S_B(-p), so the difference is never built).
//
// Every shape is a *core* grown by a *radius*: a sphere is a point grown by r, a capsule a
// segment grown by r; a box, cylinder or hull is its own core with radius 0. GJK runs on the
// cores and subtracts the radii (van den Bergen 2003, "Collision Detection in Interactive 3D
// Environments", §4.3.1): exact for rounded shapes (a sphere's curved surface would otherwise
// make GJK converge only asymptotically) and robust when they overlap, as long as the cores do
// not. Private.
//
// Frames: ConvexShape is in its local frame (capsule and cylinder axes along local z, box axes
// along local x, y, z, centred on the origin); PosedShape maps it to the world frame with
// x_world = rotation * x_local + translation. Lengths in metres.
//
// Support queries switch on a one-byte kind (no virtual call in GJK's loop). Ties (a direction
// component exactly zero) go to the positive side so results are deterministic.

#include <cmath>
#include <cstdint>
#include <span>

#include "simreel/sim/types.hpp"

namespace simreel::sim::detail {

enum class ConvexKind : std::uint8_t { sphere, box, capsule, cylinder, hull };

/// Which body a support query samples: the core (point, segment, or the shape itself) or the
/// full shape (core grown by the radius).
enum class ShapePart : std::uint8_t { core, full };

/// A convex shape in its local frame: a small value (no heap) built with the factories below.
struct ConvexShape {
  ConvexKind kind = ConvexKind::sphere;
  double radius = 0.0;               ///< (m) sphere, capsule, cylinder; >= 0
  double half_height = 0.0;          ///< (m) capsule core segment / cylinder half length, local z
  Vec3 half_extents = Vec3::Zero();  ///< (m) box, local axes; >= 0
  /// Hull vertices, local frame (m); not owned: the caller keeps them alive (the body's shape
  /// storage). Any point set: its support is that of its convex hull. At least one point.
  std::span<const Vec3> vertices{};

  [[nodiscard]] static ConvexShape sphere(double r) {
    return {.kind = ConvexKind::sphere, .radius = r};
  }
  [[nodiscard]] static ConvexShape box(const Vec3& half) {
    return {.kind = ConvexKind::box, .half_extents = half};
  }
  /// Segment from (0, 0, -half_height) to (0, 0, half_height) grown by r.
  [[nodiscard]] static ConvexShape capsule(double half_height, double r) {
    return {.kind = ConvexKind::capsule, .radius = r, .half_height = half_height};
  }
  /// Flat-ended cylinder of radius r between z = -half_height and z = half_height.
  [[nodiscard]] static ConvexShape cylinder(double r, double half_height) {
    return {.kind = ConvexKind::cylinder, .radius = r, .half_height = half_height};
  }
  [[nodiscard]] static ConvexShape hull(std::span<const Vec3> points) {
    return {.kind = ConvexKind::hull, .vertices = points};
  }

  /// Radius by which the core is grown (m): sphere and capsule radius, 0 for the others.
  [[nodiscard]] double core_radius() const {
    return kind == ConvexKind::sphere || kind == ConvexKind::capsule ? radius : 0.0;
  }

  /// Support point of the core along d (local frame; d need not be unit, may be zero).
  [[nodiscard]] Vec3 core_support(const Vec3& d) const {
    switch (kind) {
      case ConvexKind::sphere:
        return Vec3::Zero();
      case ConvexKind::capsule:
        return {0.0, 0.0, d.z() >= 0.0 ? half_height : -half_height};
      case ConvexKind::box:
        return {d.x() >= 0.0 ? half_extents.x() : -half_extents.x(),
                d.y() >= 0.0 ? half_extents.y() : -half_extents.y(),
                d.z() >= 0.0 ? half_extents.z() : -half_extents.z()};
      case ConvexKind::cylinder: {
        const double z = d.z() >= 0.0 ? half_height : -half_height;
        const double rho = std::hypot(d.x(), d.y());
        if (!(rho > 0.0)) return {0.0, 0.0, z};  // along the axis: the cap's centre
        return {radius * d.x() / rho, radius * d.y() / rho, z};
      }
      case ConvexKind::hull: {
        // Linear scan; the first of equal projections wins (deterministic).
        std::size_t best = 0;
        double best_dot = vertices[0].dot(d);
        for (std::size_t i = 1; i < vertices.size(); ++i) {
          const double p = vertices[i].dot(d);
          if (p > best_dot) {
            best_dot = p;
            best = i;
          }
        }
        return vertices[best];
      }
    }
    return Vec3::Zero();
  }

  /// Support point of the full shape along d (local frame): core support + radius * d / |d|.
  [[nodiscard]] Vec3 support(const Vec3& d, ShapePart part = ShapePart::full) const {
    const Vec3 c = core_support(d);
    const double r = core_radius();
    if (part == ShapePart::core || r == 0.0) return c;
    const double len = d.norm();
    if (!(len > 0.0)) return c;
    return c + (r / len) * d;
  }
};

/// One support point of a posed shape: world frame and the shape's local frame (the local one is
/// what a warm-start cache keeps, since it stays on the shape when the body moves).
struct SupportPoint {
  Vec3 world;
  Vec3 local;
};

/// A shape at a pose: x_world = rotation * x_local + translation. Holds a copy of the (small)
/// shape value; hull vertices stay the caller's.
struct PosedShape {
  ConvexShape shape;
  Mat3 rotation = Mat3::Identity();  ///< local -> world, orthonormal
  Vec3 translation = Vec3::Zero();   ///< (m) world position of the local origin

  PosedShape() = default;
  PosedShape(const ConvexShape& s, const Mat3& R, const Vec3& t)
      : shape(s), rotation(R), translation(t) {}
  PosedShape(const ConvexShape& s, const Transform& pose)
      : shape(s), rotation(pose.rotation.toRotationMatrix()), translation(pose.translation) {}

  [[nodiscard]] Vec3 to_world(const Vec3& local) const { return rotation * local + translation; }
  [[nodiscard]] Vec3 to_local(const Vec3& world) const {
    return rotation.transpose() * (world - translation);
  }
  /// Support point along the world direction d (any length).
  [[nodiscard]] SupportPoint support(const Vec3& d, ShapePart part) const {
    const Vec3 local = shape.support(rotation.transpose() * d, part);
    return {to_world(local), local};
  }
  [[nodiscard]] double core_radius() const { return shape.core_radius(); }
};

}  // namespace simreel::sim::detail
