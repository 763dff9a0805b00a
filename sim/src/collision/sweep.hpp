#pragma once
// Swept-sphere tests of one particle against one collider (private to collision/): closed forms
// for plane, box, sphere, cylinder and capsule and the AABB-tree query for meshes (Coutinho §3.4, §2.2).

#include <limits>

#include "collision/collider_impl.hpp"

namespace simreel::sim::detail {

/// (m) how far inside a surface a start point may lie and still count as on it: a few float
/// ulps at the point's magnitude (positions are stored in float).
inline double surface_tol(const Vec3& p) { return 1e-7 + 5e-7 * p.cwiseAbs().maxCoeff(); }

/// (m) the surface tolerance of the inside tests (§3.4.2): a point within it of a solid's surface
/// is on it, not inside (a particle born on the surface must survive float rounding). 1e-6 of the
/// shape's size (`size`: a sphere's radius, a cylinder's larger of radius and half height, a
/// capsule's radius plus half height, a mesh's local half-diagonal) plus surface_tol(p), a few
/// float ulps of the world coordinates.
inline double inside_tol(const Vec3& p, double size) { return 1e-6 * size + surface_tol(p); }

struct Hit {
  double s = std::numeric_limits<double>::infinity();  ///< fraction of the segment
  Vec3 normal = Vec3::Zero();
  Vec3 point = Vec3::Zero();  ///< particle centre at contact
  const Collider* collider = nullptr;
};

/// Updates `best` if the sphere of radius r moving a -> b (world) touches collider c earlier than
/// best.s. `first`: the segment starts in the body's start-of-step pose (relative motion, §2.1).
void sweep(const Collider& c, const Vec3& a, const Vec3& b, double r, bool first, Hit& best);

/// Is the centre p inside the solid (§3.4.2) by more than inside_tol? Boxes are excluded: they
/// push particles out (they are never removed).
bool inside_solid(const Collider& c, const Vec3& p);

}  // namespace simreel::sim::detail
