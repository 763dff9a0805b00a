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
/// it appears in the moved list whenever its pose changes.
struct BoxDef {
  Transform transform;                  ///< pose of the box centre
  Vec3 half_extents{0.5, 0.5, 0.5};     ///< (m) along the box's local axes, each > 0
  KeyframePath path;
  Material material;
};

}  // namespace simreel::sim
