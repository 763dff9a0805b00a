#pragma once
/// @file collider.hpp
/// Collider definitions: infinite plane, sphere, box, cylinder and triangle mesh, each static or
/// kinematic (following a keyframed path). Coutinho Ch. 2 (bounding volumes, hierarchies, grids)
/// and §3.4–3.7 (particles as swept spheres, impulse response, resting contact).
///
/// Common rules for the solid colliders (sphere, box, cylinder, mesh):
/// - Static when `path` is empty, otherwise kinematic: the pose follows the path, the collider
///   appears in the moved list whenever its pose changes, it is taken at its end-of-step pose for
///   the collision test (§3.4) and its path velocity (linear, and angular from the rotation keys)
///   enters the relative velocity at contact (§3.7).
/// - A particle whose centre is found inside a closed solid after its step (a kinematic body moved
///   onto it, or a cluster pushed it in) is removed and counted (§3.4.2, World::removed_inside_count),
///   except for boxes, which push it out through the nearest face (pushing boxes).

#include <array>
#include <cstdint>
#include <vector>

#include "simreel/sim/keyframes.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim {

/// Infinite plane {x : n·(x - point) = 0}; the solid half-space is n·(x - point) < 0.
struct PlaneDef {
  Vec3 point = Vec3::Zero();       ///< (m) any point on the plane, world frame
  Vec3 normal = Vec3::UnitZ();     ///< outward unit normal, world frame (normalised on add)
  Material material;
};

/// Oriented box. Particles are tested against the box grown by their radius with square edges,
/// so a corner contact is found up to r (sqrt 2 - 1) early, never late.
struct BoxDef {
  Transform transform;                  ///< pose of the box centre
  Vec3 half_extents{0.5, 0.5, 0.5};     ///< (m) along the box's local axes, each > 0
  KeyframePath path;
  Material material;
};

/// Solid sphere; the swept test against the sphere grown by the particle radius is exact
/// (closed-form ray–sphere, Coutinho App. A).
struct SphereDef {
  Transform transform;  ///< pose of the centre (the rotation matters only for a spinning path)
  double radius = 0.5;  ///< (m) > 0
  KeyframePath path;
  Material material;
};

/// Solid capped cylinder along its local z axis, centred on the transform's origin. Tested
/// against the cylinder grown by the particle radius with square rims (radius R + r, half height
/// H + r), so a rim contact is found slightly early, never late.
struct CylinderDef {
  Transform transform;
  double radius = 0.5;       ///< (m) > 0
  double half_height = 0.5;  ///< (m) > 0, along local z
  KeyframePath path;
  Material material;
};

/// Triangle mesh in its local frame (already scaled; metres). Triangles collide on both sides;
/// a particle hits the first face, edge or vertex its swept sphere touches, with that feature's
/// normal (Coutinho §3.7). An AABB tree is built once at registration in the local frame (§2.2)
/// and queries transform the particle's swept segment into that frame (§2.1). A mesh whose every
/// edge is shared by exactly two triangles is closed: particles found inside it are removed.
struct MeshDef {
  std::vector<Vec3> vertices;                       ///< (n) local positions (m)
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< (m) vertex indices, each < n
  Transform transform;                              ///< local -> world (rigid; scale the vertices)
  KeyframePath path;
  Material material;
};

}  // namespace simreel::sim
