#pragma once
// A body at run time (private to core/): how it moves, and where its shapes are. The shapes
// themselves (collision/collider_impl.hpp) live in WorldState::shapes, grouped per body in the
// order of the bodies' dense array, so the collision passes loop over one flat array.

#include <cstdint>
#include <string>
#include <vector>

#include "collision/collider_impl.hpp"
#include "simreel/sim/body.hpp"
#include "simreel/sim/moved_object.hpp"

namespace simreel::sim::detail {

struct Body {
  BodyType type = BodyType::static_body;
  std::string name;
  KeyframePath path;  ///< kinematic bodies
  /// Pose of the body frame as given or sampled from the path (rotation not normalised: the
  /// shapes normalise it, as the single colliders always did).
  Transform pose;
  Vec3 velocity = Vec3::Zero();          ///< (m/s) of the body origin, world
  Vec3 angular_velocity = Vec3::Zero();  ///< (rad/s), world
  double linear_damping = 0.0;           ///< (1/s)
  double angular_damping = 0.0;          ///< (1/s)
  /// Index of its rigid entry (BodyDynamics::rigid) for dynamic and kinematic bodies, else
  /// kNoRigid (body_dynamics.hpp).
  std::uint32_t rigid = 0xffffffffu;
  Vec3 local_com = Vec3::Zero();  ///< (m) dynamic: centre of mass in the body frame
  Vec3 gravity = Vec3::Zero();    ///< (m/s²) dynamic: world
  double drag_coefficient = 0.0;  ///< C_d, dynamic: air drag (BodyDef::drag_coefficient)
  double drag_area = 0.0;         ///< (m²) dynamic: A of the air drag and of a blast's share
  std::uint32_t first_shape = 0;  ///< its shapes: WorldState::shapes[first_shape, + shape_count)
  std::uint32_t shape_count = 0;
  // What the moved list last reported.
  Vec3 reported_translation = Vec3::Zero();
  Quat reported_rotation = Quat::Identity();

  [[nodiscard]] bool kinematic() const { return type == BodyType::kinematic; }
  [[nodiscard]] bool dynamic() const { return type == BodyType::dynamic; }
  /// Moves a kinematic body and its shapes to the path's pose and velocities at time t (s).
  void move_to(double t, std::vector<Collider>& shapes);
  /// The pose reported to the renderer: the body frame (rotation normalised), except a body
  /// made of one plane with an identity offset, which reports the plane's pose (Collider::pose).
  [[nodiscard]] MovedObject report_pose(const std::vector<Collider>& shapes) const;
};

}  // namespace simreel::sim::detail
