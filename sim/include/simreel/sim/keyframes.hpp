#pragma once
/// @file keyframes.hpp
/// A keyframed rigid path: what moves kinematic colliders (and later emitters and pins).

#include <vector>

#include "simreel/sim/types.hpp"

namespace simreel::sim {

struct Keyframe {
  double time = 0.0;                ///< (s) since the start of the simulation
  Vec3 position = Vec3::Zero();     ///< (m), world frame
  Quat rotation = Quat::Identity();
};

/// Piecewise path through keyframes: positions interpolated linearly (or by Catmull–Rom when
/// `smooth`), rotations by slerp. Before the first key the first pose holds; after the last,
/// the last pose holds, or the path repeats with period (last.time - first.time) when `loop`.
struct KeyframePath {
  std::vector<Keyframe> keys;  ///< sorted by strictly increasing time; may be empty
  bool loop = false;
  bool smooth = true;

  [[nodiscard]] bool empty() const { return keys.empty(); }
  /// Pose at time t (s). Requires !empty().
  [[nodiscard]] Transform sample(double t) const;
  /// Linear velocity (m/s) at time t by central difference over +-h (used for the relative
  /// velocity of a moving collider at contact).
  [[nodiscard]] Vec3 velocity(double t, double h = 1e-4) const;
};

}  // namespace simreel::sim
