#pragma once
/// @file body.hpp
/// Bodies apart from their shapes (after Box2D v3's b2BodyDef / b2ShapeDef): a BodyDef says how
/// a body moves (type, pose, path, velocity, damping); each ShapeDef of it says what it collides
/// with (geometry, material, offset in the body frame). Coutinho Ch. 2 (shapes, bounding volumes
/// and hierarchies), §3.4–3.7 (particles as swept spheres against bodies, impulse response,
/// moving bodies), Ch. 4 (rigid-body dynamics: what a dynamic body will be).
///
/// Frames: the body frame is placed in the world by the body's pose (BodyDef::pose, or its path
/// for a kinematic body); a shape's frame is placed in the body frame by ShapeDef::offset, so a
/// shape's world pose is body pose ∘ offset. A body with one shape and an identity offset
/// behaves exactly like the single colliders of collider.hpp (World::add_sphere and the others
/// build such a body).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "simreel/sim/keyframes.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim {

/// How a body moves.
enum class BodyType : std::uint8_t {
  /// Never moves: its pose is BodyDef::pose; its velocities must be zero and its path empty.
  static_body,
  /// Follows BodyDef::path (not empty); its velocities come from the path (linear, and angular
  /// from the rotation keys) and enter the relative velocity of a contact (§3.7). It appears in
  /// World::advance()'s moved list whenever its pose changes. Contacts do not push it.
  kinematic,
  /// Moved by gravity and contacts (Coutinho Ch. 4): mass properties from its shapes' densities
  /// (or BodyDef::mass), state x, q, v, L integrated by semi-implicit Euler, contacts with every
  /// other body's solid and plane shapes solved by sequential impulses with friction and
  /// restitution (§4.8). Shapes: sphere, box, capsule, cylinder, convex_hull (a dynamic mesh or
  /// plane is rejected; several shapes at offsets make a compound). It appears in the moved
  /// list after every advance() in which it moved. Particles and cloth vertices that hit it
  /// push it back (their momentum change, summed over a step, enters the bodies' step:
  /// Coutinho §3.7), and force fields push it (ForceFieldDef::bodies). Not yet: continuous
  /// collision.
  dynamic,
};

/// The geometry of a shape.
enum class ShapeType : std::uint8_t {
  plane,     ///< infinite plane through the shape origin; `normal`; static bodies only
  sphere,    ///< `radius` about the shape origin
  box,       ///< `half_extents` along the shape axes, centred on the shape origin
  cylinder,  ///< capped cylinder along local z: `radius`, `half_height`
  capsule,   ///< segment from -half_height to +half_height along local z grown by `radius`
  mesh,      ///< triangle mesh: `vertices`, `triangles`
  /// Convex hull of `points` (quickhull, built once at add time; Coutinho §2.2.4): static,
  /// kinematic and dynamic bodies. Bodies collide with it through its vertices and planar faces
  /// (GJK/EPA + face clipping); particles and cloth collide with its triangles, as with a
  /// closed mesh; its mass properties come from its boundary (App. D).
  convex_hull,
};

/// One shape of a body: geometry in the shape frame, material, and the shape frame's pose in the
/// body frame. Only the fields of its `type` are read (and checked).
///
/// Particles collide with every shape as swept spheres (Coutinho §3.4): closed forms for plane,
/// sphere, box (the box grown by the particle radius with square edges: a corner contact is found
/// up to r (sqrt 2 - 1) early, never late), cylinder (square rims likewise) and capsule (exact),
/// and an AABB tree built once in the shape frame for meshes (§2.2). A particle whose centre is
/// found inside a sphere, cylinder, capsule or closed mesh after its step is removed (§3.4.2,
/// World::removed_inside_count); one inside a box leaves through the nearest face.
struct ShapeDef {
  ShapeType type = ShapeType::sphere;
  /// Pose of the shape frame in the body frame (m; rotation). A plane's offset moves and turns
  /// the plane with it.
  Transform offset;
  double radius = 0.5;       ///< (m) > 0: sphere, cylinder, capsule
  double half_height = 0.5;  ///< (m) > 0: cylinder, capsule (half the segment), along local z
  Vec3 half_extents{0.5, 0.5, 0.5};  ///< (m) each > 0: box, along the shape axes
  /// Plane: outward normal in the shape frame (non-zero; normalised on add). The solid half-space
  /// is the side it points away from.
  Vec3 normal = Vec3::UnitZ();
  /// Mesh: (n) vertex positions in the shape frame (m, already scaled), finite.
  std::vector<Vec3> vertices;
  /// Mesh: (m) triangles as vertex indices, each < n; two-sided. A mesh whose every edge is
  /// shared by exactly two triangles is closed (particles found inside it are removed).
  std::vector<std::array<std::uint32_t, 3>> triangles;
  /// Convex hull: (n >= 4) points in the shape frame (m), finite, not all coplanar; the shape is
  /// their convex hull (interior and duplicate points are dropped).
  std::vector<Vec3> points;
  Material material;  ///< response of particles and cloth against this shape (§3.6.1); also
                      ///< restitution and friction of body contacts (pair: max e, sqrt(mu_a mu_b))
  /// (kg/m³) > 0: uniform density of a dynamic body's solid shape (its mass and inertia, App. D);
  /// ignored for static and kinematic bodies. Water is 1000, wood ~600, steel ~7800.
  double density = 1000.0;

  /// Shorthands for the common shapes (material default, identity offset unless given).
  static ShapeDef sphere(double radius, const Transform& offset = {});
  static ShapeDef box(const Vec3& half_extents, const Transform& offset = {});
  static ShapeDef cylinder(double radius, double half_height, const Transform& offset = {});
  static ShapeDef capsule(double radius, double half_height, const Transform& offset = {});
  static ShapeDef plane(const Vec3& normal = Vec3::UnitZ(), const Transform& offset = {});
  static ShapeDef convex_hull(std::vector<Vec3> points, const Transform& offset = {});
};

/// A body: how it moves, and its shapes (at least one). Registered by World::add_body, named by
/// a BodyHandle, removed (with all its shapes) by World::remove.
struct BodyDef {
  BodyType type = BodyType::static_body;
  /// Pose of the body frame in the world (m; rotation) for a static body, the initial pose of a
  /// dynamic one (its centre of mass is tracked inside; the moved list reports this frame, which
  /// need not be the centre of mass). A kinematic body takes
  /// its pose from `path` (this field is then ignored).
  Transform pose;
  /// Kinematic bodies: the keyframed path of the body frame, world frame (must not be empty).
  /// Static bodies: must be empty.
  KeyframePath path;
  /// (m/s) velocity of the body origin, world frame. Must be zero for static and kinematic
  /// bodies (a kinematic body's velocity comes from its path); the initial velocity of a
  /// dynamic body (Ch. 4).
  Vec3 linear_velocity = Vec3::Zero();
  /// (rad/s) angular velocity, world frame. Zero unless dynamic, like linear_velocity.
  Vec3 angular_velocity = Vec3::Zero();
  /// (1/s) >= 0, dynamic bodies: linear drag force -c m v (Coutinho §4.3.2), so v decays as
  /// e^{-c t} with no other force.
  double linear_damping = 0.0;
  /// (1/s) >= 0, dynamic bodies: drag torque -c Ī ω with Ī the mean principal moment of
  /// inertia (ω decays as e^{-c t} for a body with equal moments).
  double angular_damping = 0.0;
  /// (kg) dynamic bodies: > 0 overrides the total mass from the shapes' densities (inertia scales
  /// with it, centre of mass unchanged); 0 (default) keeps the densities' mass.
  double mass = 0.0;
  /// (m/s²) world: the gravitational acceleration on a dynamic body (per body, as particle
  /// systems have their own; zero for a body that floats).
  Vec3 gravity{0.0, 0.0, -9.81};
  /// Dynamic bodies, air drag of force fields with an air velocity (a uniform field's wind, curl
  /// noise): F = ½ ρ_air C_d A |u - v| (u - v) at the centre of mass, ρ_air = 1.225 kg/m³.
  /// C_d (dimensionless) >= 0; ~1.05 for a cube face-on, 0.47 for a sphere.
  double drag_coefficient = 1.0;
  /// (m²) >= 0, the area A of that drag and of a blast's share; 0 (default): the mean projected
  /// area of the shapes, a quarter of their surface area (Cauchy's formula for a convex body;
  /// summed over the shapes of a compound one).
  double drag_area = 0.0;
  std::vector<ShapeDef> shapes;  ///< at least one; planes only on static bodies
  std::string name;              ///< for messages
};

/// A dynamic body's motion (World::motion): what its momentum is now.
struct BodyMotion {
  double mass = 0.0;                     ///< (kg)
  Vec3 center_of_mass = Vec3::Zero();    ///< (m) world
  Vec3 linear_velocity = Vec3::Zero();   ///< (m/s) of the centre of mass, world
  Vec3 angular_velocity = Vec3::Zero();  ///< (rad/s) world
  Vec3 linear_momentum = Vec3::Zero();   ///< (kg m/s) m v, world
  Vec3 angular_momentum = Vec3::Zero();  ///< (kg m²/s) about the centre of mass, world
};

}  // namespace simreel::sim
