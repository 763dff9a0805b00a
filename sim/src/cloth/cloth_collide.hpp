#pragma once
// Cloth vertices against the world's colliders (private). Coutinho §3.9.2: cloth collisions
// "follow the same principles" as particles (§3.4); a vertex is a point kept `thickness` away from
// every collider surface.

#include <cstdint>
#include <vector>

#include "collision/body_impulses.hpp"
#include "collision/collider_impl.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim::detail {

/// Projects every vertex with free[i] != 0 that ends the step closer than `thickness` to a
/// collider's surface (or inside it) back onto the surface grown by `thickness`, through the face
/// its path x_start -> x entered by (the nearest face if it started inside). Its velocity relative
/// to the collider loses the normal component pointing in (perfectly inelastic: cloth does not
/// bounce) and the tangential part is reduced by friction × the normal speed removed (Coulomb,
/// §3.6.1), to zero at most. `hit[i]` is set to 1 for every vertex touched,
/// 2 for one touched by a kinematic body's shape (kept at 2 for the rest of the step), whose
/// outward normal then goes to `pushed_normal[i]` when given.
/// With `impulses`, each response against a dynamic body's shape logs the vertex's momentum
/// change vertex_mass (v_before - v_after) (N s) on the body at the contact (§3.7, two-way).
/// A switch on the collider kind: plane, box, and (swept, see cloth_collide.cpp) sphere,
/// cylinder, capsule and triangle mesh, static or kinematic.
void collide_cloth(std::vector<Vec3>& x, std::vector<Vec3>& v, const std::vector<Vec3>& x_start,
                   const std::vector<std::uint8_t>& free, const std::vector<Collider>& colliders,
                   double thickness, double friction, std::vector<std::uint8_t>& hit,
                   double vertex_mass = 0.0, BodyImpulses* impulses = nullptr,
                   std::vector<Vec3>* pushed_normal = nullptr);

}  // namespace simreel::sim::detail
