#pragma once
// Colliders at run time and the particle collision pass (private).
// Coutinho §3.4 (swept spheres, collider fixed at its end-of-step pose), §3.6.1 (impulse with
// restitution and Coulomb friction, critical friction), §3.6.3 (resting contact).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "particle_store.hpp"
#include "simreel/sim/collider.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim::detail {

struct Collider {
  enum class Shape : std::uint8_t { plane, box };
  Shape shape = Shape::plane;
  std::uint16_t generation = 1;
  Material material;

  // plane
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();  ///< unit

  // box: definition
  Vec3 half_extents = Vec3::Zero();
  KeyframePath path;  ///< empty: static
  // box: pose at the end of the current step (Coutinho §3.4: the body is taken as fixed there)
  Vec3 center = Vec3::Zero();
  Quat rotation = Quat::Identity();
  Mat3 R = Mat3::Identity();     ///< local -> world
  Vec3 velocity = Vec3::Zero();  ///< (m/s) of the centre, from the path
  Vec3 angular_velocity = Vec3::Zero();  ///< (rad/s), world frame
  Vec3 aabb_half = Vec3::Zero();  ///< world AABB half size of the box (unexpanded)

  // what the moved list last reported
  Vec3 reported_translation = Vec3::Zero();
  Quat reported_rotation = Quat::Identity();

  [[nodiscard]] bool kinematic() const { return shape == Shape::box && !path.empty(); }
  void set_pose(const Transform& t);
  /// Moves a kinematic box to its pose and velocities at time t.
  void update(double t);
  /// Velocity (m/s) of the collider's material point at world position p.
  [[nodiscard]] Vec3 point_velocity(const Vec3& p) const {
    return shape == Shape::plane ? Vec3::Zero() : Vec3(velocity + angular_velocity.cross(p - center));
  }
  [[nodiscard]] MovedObject pose() const;
};

Collider make_collider(const PlaneDef& def);
Collider make_collider(const BoxDef& def, double time);

/// Collides particles [begin, end) of one system with every collider, after integration. Each
/// particle's motion over the step is the segment from its start-of-step position to its
/// position, travelled in min(age, h) seconds (a newborn moves only for its age).
void collide(ParticleStore& s, std::size_t begin, std::size_t end, double h,
             const std::vector<Collider>& colliders, double contact_speed, const ForceParams& f);

}  // namespace simreel::sim::detail
