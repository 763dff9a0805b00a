#pragma once
/// @file convex_decomposition.hpp
/// Convex decomposition of a closed triangle mesh (Coutinho App. F), so a concave mesh can be a
/// dynamic body: each piece becomes a ShapeType::convex_hull of a compound.
///
/// The algorithm follows App. F's outline (after Joe 1994): find the reflex edges (an edge whose
/// interior dihedral angle exceeds π), resolve the deepest by cutting the polyhedron with a plane
/// through it, recurse on the parts. The cut-plane candidates are App. F's: the planes of the two
/// faces at the reflex edge carried across it, then planes turning the interior angle at
/// fractions 1/2, 1/4 and 3/4. Only the cut face through the reflex edge is cut (other crossings
/// of the plane stay joined); a candidate is rejected (App. F condition 15) when that face is not
/// a simple polygon (a hole in it, a pinch). Departures, to keep the code small and robust:
/// - a cut that does not separate the part is allowed (the first cut through a ring): the part
///   stays one, with the cut face twice, the "double-occurring face" of Fig. F.3 that App. F's
///   simplified version avoids, so rings and handles decompose;
/// - among the valid candidates the one leaving the least concavity (hull volume − volume, summed
///   over the parts; fewer parts on a tie) wins, instead of App. F's angle and distance tests;
/// - tessellated curved surfaces have reflex edges everywhere (a torus's inner side), so a part
///   counts as convex once no reflex edge lies deeper than `max_concavity` inside its hull and
///   its hull over-fills it by less than max_concavity × V^(2/3) (the "concavity" of V-HACD, the
///   name Unity, Godot and Blender add-ons use); a last pass merges neighbouring pieces whose
///   union passes the same test.
/// Deterministic: the result depends only on the input (no hashing, no randomness).

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "simreel/sim/types.hpp"

namespace simreel::sim {

struct ConvexDecompositionOptions {
  /// (m) A part is convex enough when no reflex edge lies deeper than this inside its convex
  /// hull. <= 0: 1% of the mesh's bounding-box diagonal.
  double max_concavity = 0.0;
  /// At most this many pieces (>= 1); when reached, the remaining parts are kept as they are
  /// (their hulls over-fill the concavity).
  int max_convex_hulls = 32;
};

/// One convex piece: its vertices (m, the mesh's frame) — the corners of the part of the mesh it
/// covers, cut-face corners included — ready for ShapeDef::points.
using ConvexPiece = std::vector<Vec3>;

/// Convex pieces of the solid bounded by `triangles` over `vertices` (closed, consistently wound
/// counter-clockwise seen from outside, vertices welded: a shared corner is one index). A convex
/// mesh gives one piece holding exactly `vertices` (in their order). Pieces are ordered by where
/// the cuts left them (deterministic). @throws std::invalid_argument if the mesh is not closed and
/// consistently oriented, or bounds no volume (the message says which).
std::vector<ConvexPiece> convex_decomposition(std::span<const Vec3> vertices,
                                              std::span<const std::array<std::uint32_t, 3>> triangles,
                                              const ConvexDecompositionOptions& options = {});

}  // namespace simreel::sim
