#pragma once
/// @file body_spring.hpp
/// Damped springs between two bodies' points, or a body's point and a world point (Coutinho
/// §4.3.3, eqs. 4.21–4.22: eq. 3.6's particle spring generalised to points on rigid bodies).

#include <string>

#include "simreel/sim/handle.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim {

/// A spring from anchor_a (on body_a) to anchor_b (on body_b). Either body may be null (the
/// world: the anchor is a fixed world point), not both; at least one must be dynamic. Anchors are
/// read in the world frame at registration and fixed in their bodies' frames from then on. With
/// d = p_b - p_a and u = d / |d| the force on body a is
///   F = (stiffness (|d| - rest_length) + damping (v_b(p_b) - v_a(p_a))·u) u
/// at p_a, and -F on body b at p_b (a stretched spring pulls them together). Forces are
/// explicit: a stiff spring needs k/m < (2/h)² with h the internal step (WorldDef::max_step).
struct BodySpringDef {
  BodyHandle body_a;  ///< null = the world
  BodyHandle body_b;  ///< null = the world
  Vec3 anchor_a = Vec3::Zero();  ///< (m) world frame at registration
  Vec3 anchor_b = Vec3::Zero();  ///< (m) world frame at registration
  /// (m) >= 0; negative (default): the anchors' distance at registration.
  double rest_length = -1.0;
  double stiffness = 0.0;  ///< (N/m) >= 0
  double damping = 0.0;    ///< (N s/m) >= 0, along the spring
  std::string name;        ///< for messages
};

}  // namespace simreel::sim
