#pragma once
/// @file joint.hpp
/// Joints between rigid bodies (Coutinho Ch. 5, articulated rigid-body systems): the definition
/// a World registers (World::add_joint) and what it reports of one (World::joint_state).
///
/// Every joint of the world is an equality constraint on the velocities of the two bodies it
/// joins; the constraint impulses of all joints are found together from one sparse linear system
/// per solver sweep (the impulse form of eq. 5.12, §5.2–5.3), solved with the contacts so that a
/// collision impulse propagates through the joints (§5.4). Numerical drift of the anchors is
/// removed by projecting the positions back onto the joints after each step (the book's
/// zero-rest-length spring of §5.4 made exact). Beyond the book: hinge and fixed joints, limits,
/// motors, damping and breaking.

#include <limits>
#include <string>

#include "simreel/sim/handle.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim {

/// The relative motion a joint allows.
enum class JointType : std::uint8_t {
  /// Ball and socket (the book's joint, §5.2, Fig. 5.1): the two anchor points coincide; any
  /// relative rotation. 3 constraint rows.
  spherical,
  /// Revolute: the anchors coincide and the bodies turn about one common axis. 5 rows.
  hinge,
  /// Weld: no relative motion at all. 6 rows.
  fixed,
};

/// A joint between body_a and body_b. Either may be null (the static world, e.g. a pendulum's
/// pivot), not both; a static or kinematic body acts as the world does (a kinematic one drags
/// the joint along its path). Geometry is given in the world frame at registration and stored in
/// each body's frame: registering a joint never moves a body.
struct JointDef {
  JointType type = JointType::spherical;
  BodyHandle body_a;  ///< null = the world
  BodyHandle body_b;  ///< null = the world
  /// (m) world frame at registration: the joint point, fixed in both bodies from then on.
  Vec3 anchor = Vec3::Zero();
  /// Unit (normalised here), world frame at registration. Hinge: the axis of rotation. Spherical:
  /// the twist axis of the cone-and-twist limits (a ragdoll limb's long axis).
  Vec3 axis = Vec3::UnitZ();

  /// Hinge: the angle (rad) of body b relative to body a about the axis, measured right-handed
  /// from its value at registration (0), is kept in [lower_angle, upper_angle] when
  /// limit_enabled. Requires lower_angle <= 0 <= upper_angle (the joint starts inside them).
  bool limit_enabled = false;
  double lower_angle = 0.0;  ///< (rad) hinge lower limit
  double upper_angle = 0.0;  ///< (rad) hinge upper limit
  /// Spherical, when limit_enabled: the swing cone's half angle (rad, in (0, π)): the angle
  /// between the axis as carried by body a and as carried by body b stays below it.
  double cone_angle = 0.0;
  /// Spherical, when limit_enabled: the twist of body b about the axis relative to body a (rad,
  /// 0 at registration) stays in [twist_lower, twist_upper] (twist_lower <= 0 <= twist_upper).
  /// Equal values of ±π (the default) leave the twist free.
  double twist_lower = -3.141592653589793;
  double twist_upper = 3.141592653589793;

  /// (N m s/rad) >= 0: a viscous torque -c (ω_b - ω_a) between the bodies (hinge: about its
  /// axis), applied implicitly (stable for any c).
  double damping = 0.0;

  /// Hinge motor: drives the relative angular speed about the axis to motor_speed (rad/s) with
  /// a torque of at most max_motor_torque (N m, >= 0). A motor with speed 0 is a brake.
  bool motor_enabled = false;
  double motor_speed = 0.0;
  double max_motor_torque = 0.0;

  /// (N) The joint breaks (stops acting for good; World::joint_state reports it) the first step
  /// its constraint force exceeds this. Infinity (default): never.
  double break_force = std::numeric_limits<double>::infinity();

  /// Whether the two joined bodies also collide with each other (default no: the links of a
  /// chain overlap at their joints).
  bool collide_connected = false;

  std::string name;  ///< for messages
};

/// What a joint does now (World::joint_state), for exports and tests.
struct JointReading {
  /// (N) world frame: the constraint force the joint applied to body b over the last step
  /// (impulse / step); the force on body a is its negative (Coutinho's ±P_i, §5.2). Anchored at
  /// the anchor point.
  Vec3 force = Vec3::Zero();
  /// (N m) world frame: the constraint torque on body b over the last step (hinge, fixed, limits,
  /// motor, damping), beyond the moment of `force` about the anchor.
  Vec3 torque = Vec3::Zero();
  /// (m) distance between the anchor as carried by body a and as carried by body b (drift).
  double anchor_error = 0.0;
  /// (rad) hinge: the angle of body b relative to body a about the axis (0 at registration).
  /// Spherical: the swing angle between the axis as carried by each body. Fixed: 0.
  double angle = 0.0;
  /// Spherical: the twist about the axis (rad, 0 at registration); otherwise 0.
  double twist = 0.0;
  /// (m) world: the anchor as carried by body a.
  Vec3 anchor = Vec3::Zero();
  bool broken = false;  ///< broke at its break_force (it then applies nothing)
};

}  // namespace simreel::sim
