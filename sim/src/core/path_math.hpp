#pragma once
// Kinematics of a keyframed path beyond the public sample()/velocity() (private).

#include "simreel/sim/keyframes.hpp"

namespace simreel::sim::detail {

/// Angular velocity (rad/s, world frame) at time t by central difference of the sampled
/// rotations over +-h: omega = axis * angle(q(t+h) q(t-h)^-1) / 2h.
Vec3 angular_velocity(const KeyframePath& path, double t, double h = 1e-4);

}  // namespace simreel::sim::detail
