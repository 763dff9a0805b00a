#pragma once
/// @file hull_mesh.hpp
/// The convex hull a ShapeType::convex_hull shape will be, for callers outside the engine (the
/// program draws a hull body with it; Coutinho §2.2.4). The same quickhull the engine runs when
/// the shape is added (deterministic: it depends only on the points), so what is drawn is what
/// collides.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "simreel/sim/types.hpp"

namespace simreel::sim {

/// A closed convex polyhedron over a subset of the input points (shape frame, m).
struct HullMesh {
  std::vector<Vec3> vertices;
  /// Planar faces (coplanar triangles merged) as convex polygons of vertex indices,
  /// counter-clockwise seen from outside.
  std::vector<std::vector<std::uint32_t>> faces;
  /// The faces' fan triangulation, counter-clockwise from outside (outward normal (b-a) × (c-a)).
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

/// Convex hull of `points`. @throws std::invalid_argument for fewer than 4 points, a non-finite
/// point, or points that bound no volume (all coincident, collinear or coplanar), saying which.
HullMesh hull_mesh(std::span<const Vec3> points);

}  // namespace simreel::sim
