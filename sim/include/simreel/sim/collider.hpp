#pragma once
/// @file collider.hpp
/// Collider definitions for this slice: infinite plane and box (static or keyframed).

#include <array>

#include "simreel/sim/keyframes.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim {

/// Infinite plane {x : n·(x - point) = 0}; the solid half-space is n·(x - point) < 0.
struct PlaneDef {
  Vec3 point = Vec3::Zero();       ///< (m) any point on the plane, world frame
  Vec3 normal = Vec3::UnitZ();     ///< outward unit normal, world frame (normalised on add)
  Material material;
};

/// Oriented box. Static when `path` is empty, otherwise kinematic: its pose follows the path and
/// it appears in the moved list whenever its pose changes. A kinematic box is taken at its
/// end-of-step pose for the collision test (Coutinho §3.4) and its path velocity (linear, and
/// angular from the rotation keys) enters the relative velocity at contact (§3.7). Particles are
/// tested against the box grown by their radius with square edges, so a corner contact is found
/// up to r (sqrt 2 - 1) early, never late.
struct BoxDef {
  Transform transform;                  ///< pose of the box centre
  Vec3 half_extents{0.5, 0.5, 0.5};     ///< (m) along the box's local axes, each > 0
  KeyframePath path;
  Material material;
};

}  // namespace simreel::sim
