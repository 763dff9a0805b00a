#pragma once
/// @file world.hpp
/// The World: registers objects, advances by a caller-given sampling time in internal steps,
/// and reports what moved (Coutinho §1.4.1, the interface with the rendering engine).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "simreel/sim/body.hpp"
#include "simreel/sim/body_spring.hpp"
#include "simreel/sim/cloth.hpp"
#include "simreel/sim/collider.hpp"
#include "simreel/sim/forces.hpp"
#include "simreel/sim/handle.hpp"
#include "simreel/sim/joint.hpp"
#include "simreel/sim/moved_object.hpp"
#include "simreel/sim/particle_system.hpp"
#include "simreel/sim/state_error.hpp"
#include "simreel/sim/types.hpp"
#include "simreel/sim/world_def.hpp"

namespace simreel::sim {

/// Thrown when the state stops being finite: names the object, step and time.
class NonFiniteState : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class World {
 public:
  /// @throws std::invalid_argument if max_step <= 0 or not finite.
  explicit World(const WorldDef& def = {});
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;

  // --- Bodies (body.hpp; Coutinho Ch. 2 shapes, §3.7 moving bodies) ---------------------------
  /// Registers a body and its shapes. Each shape is posed in the world at body pose ∘ offset
  /// (a kinematic body's shapes all follow its path) and collides with particles and cloth; a
  /// mesh's AABB tree is built here, once, in its frame (Coutinho §2.2), O(n log n) in the
  /// triangle count. The body is named by one handle: World::pose gives its frame's pose, the
  /// moved list reports it once per advance() in which it moved, World::remove removes it with
  /// every shape.
  /// A dynamic body gets its mass properties here (§4.1, App. D: closed forms per shape,
  /// combined by the parallel-axis theorem) and is simulated by the `bodies` stage.
  /// @throws std::invalid_argument naming the field ("BodyDef.shapes[1].radius", ...) when there
  ///         is no shape, a dynamic body has a mesh or plane shape, a non-positive density or a
  ///         negative mass, a static body has a path or a non-zero velocity, a kinematic body has no path
  ///         or a non-zero velocity, a damping is negative, a pose or offset is not finite, a
  ///         plane is on a body that is not static, or a shape's parameters are out of range.
  BodyHandle add_body(const BodyDef& def);

  /// The single colliders of the scene format (collider.hpp): each registers a body with one
  /// shape at an identity offset (static when its path is empty, else kinematic), exactly as
  /// add_body would, and returns its handle. Messages name the collider definition's fields
  /// ("SphereDef.radius"). @throws std::invalid_argument on an invalid definition (non-positive
  /// size, zero normal, restitution outside [0, 1], ...).
  ColliderHandle add_plane(const PlaneDef& def);
  ColliderHandle add_box(const BoxDef& def);
  ColliderHandle add_sphere(const SphereDef& def);
  ColliderHandle add_cylinder(const CylinderDef& def);
  ColliderHandle add_mesh(const MeshDef& def);

  /// Registers a particle system. @throws std::invalid_argument on an invalid definition.
  ParticleSystemHandle add_particle_system(const ParticleSystemDef& def);

  /// Adds one particle to a system now, outside its emitter (tests, tools, scripted effects):
  /// age 0, colour from the system's gradient, the system's next id (returned). It is integrated
  /// and collided from the next advance() on. Position (m) and velocity (m/s) are world frame and
  /// not checked: a non-finite value is reported by advance() as NonFiniteState.
  /// @throws std::out_of_range if the handle is stale; std::invalid_argument unless mass (kg) > 0,
  ///         radius (m) > 0 and lifetime (s) >= 0; std::length_error if the system already holds
  ///         EmitterDef::max_particles live particles.
  std::uint64_t spawn_particle(ParticleSystemHandle h, const Vec3& position, const Vec3& velocity,
                               double mass, double radius, double lifetime);

  /// Adds a force field (Coutinho §3.3) acting from the next step on the systems it names (all
  /// when its list is empty, including systems added later). Its curl noise is seeded from
  /// (WorldDef::seed, count of fields ever added before it).
  /// @throws std::invalid_argument on a non-positive radius/half extent/frequency, a zero vortex
  ///         axis, a negative drag or a non-finite value; std::out_of_range on a stale system
  ///         handle.
  ForceFieldHandle add_force_field(const ForceFieldDef& def);
  /// Adds an animated zero-rest-length attractor spring (§3.3.5) on one system.
  /// @throws std::invalid_argument on negative stiffness/damping; std::out_of_range on a stale
  ///         handle.
  AttractorSpringHandle add_attractor_spring(const AttractorSpringDef& def);
  /// Connects two live particles of a system, named by id, with a damped spring (eq. 3.6); a
  /// negative rest length takes their current distance. The spring is dropped when either dies.
  /// @throws std::invalid_argument if an id is not alive, a == b, or k_s/k_d < 0;
  ///         std::out_of_range on a stale handle.
  void add_spring(ParticleSystemHandle h, const SpringDef& spring);
  /// Adds a sub-emitter (SubEmitterDef) to `parent`: from the next step on, its particles that
  /// trigger give birth to particles of `def.system`. Sub-emitters of a parent fire in the order
  /// they were added. A sub-emitter whose target is removed is dropped.
  /// @throws std::out_of_range on a stale parent or target handle; std::invalid_argument unless
  ///         count is in [1, 10^6], probability and inherit_velocity in [0, 1].
  void add_sub_emitter(ParticleSystemHandle parent, const SubEmitterDef& def);
  /// Integrator (sub)steps accepted so far by the system (an adaptive system may take several
  /// per internal step, or one per several), and trial steps it rejected (adaptive only).
  [[nodiscard]] std::uint64_t integrator_steps(ParticleSystemHandle h) const;
  [[nodiscard]] std::uint64_t rejected_steps(ParticleSystemHandle h) const;

  /// Advances the simulation by `sampling_time` (s, > 0) in internal steps of at most
  /// WorldDef::max_step. Returns the objects whose pose changed since the last call (kinematic
  /// bodies, once each with the body's pose; registration order until a removal), then the objects removed since the last call
  /// (MovedObject::removed). The reference stays valid until the next call.
  ///
  /// Each internal step (Coutinho §1.3): kinematic colliders move to their end-of-step pose; per
  /// system, particles are integrated (gravity + drag, §3.3), collided as swept spheres against
  /// the colliders held at that pose (§3.4; against kinematic solids along the relative motion)
  /// with restitution and Coulomb friction (§3.6.1) or as resting contacts (§3.6.3), hit actions
  /// applied (Material::on_hit; split droplets join the system at age 0), the dead are removed
  /// (survivors keep their order), the step's births are released and colours updated. Then the
  /// systems that opted in (ParticleSystemDef::collide_particles / collision_group) collide with
  /// each other's particles (hashed grid §2.3.1, sequential impulses §3.6.2), their overlap
  /// corrections swept against the colliders. No particle ends a step with its centre closer than
  /// its radius to a plane on the solid side; one found inside a box leaves through the nearest
  /// face with the box's normal velocity; one inside a sphere, cylinder, capsule or closed mesh
  /// is removed and counted (§3.4.2, removed_inside_count()).
  /// @throws std::invalid_argument unless sampling_time is > 0 and finite.
  /// Cloths step after the particle systems (see add_cloth); a cloth whose state becomes
  /// non-finite is reported as NonFiniteState naming the cloth, step and time.
  /// @throws NonFiniteState if a particle's state becomes NaN/inf; the message names the system,
  ///         the particle id, the internal step number (1-based, as step_count() would count it)
  ///         and the time. The world is then left mid-advance and should be discarded.
  const std::vector<MovedObject>& advance(double sampling_time);

  // --- Joints (joint.hpp; Coutinho Ch. 5) ----------------------------------------------------
  /// Joins two bodies (or a body and the world) from the next step on. The anchor and axis are
  /// read in the world frame now and fixed in each body's frame: the bodies are not moved, so a
  /// joint whose anchor is not where the bodies meet holds them at that distance. The joints and
  /// the contacts of the dynamic bodies are solved together each step (§5.2–5.4); the joined
  /// bodies do not collide with each other unless JointDef::collide_connected.
  /// @throws std::out_of_range on a stale body handle; std::invalid_argument (naming the field,
  ///         "JointDef.axis") when both bodies are null or equal, neither is dynamic, the anchor or
  ///         axis is not finite or the axis is zero, a limit range does not contain 0 or is not
  ///         finite, cone_angle is not in (0, π) with limits on a spherical joint, damping,
  ///         max_motor_torque or break_force is negative or NaN.
  JointHandle add_joint(const JointDef& def);
  /// What the joint did over the last step and where its anchors are (joint.hpp).
  /// @throws std::out_of_range if stale.
  [[nodiscard]] JointReading joint_state(JointHandle h) const;
  [[nodiscard]] const JointDef& definition(JointHandle h) const;
  /// Every joint, in the engine's dense order (registration order until a removal).
  [[nodiscard]] std::vector<JointHandle> joints() const;

  /// Adds a damped spring between two bodies' points or a body's point and the world
  /// (body_spring.hpp; §4.3.3), acting from the next step. Removing a body removes its springs.
  /// @throws std::out_of_range on a stale body handle; std::invalid_argument (naming the field,
  ///         "BodySpringDef.stiffness") when both bodies are null or equal, neither is dynamic,
  ///         an anchor is not finite, or stiffness, damping or rest_length is NaN/inf or (for
  ///         stiffness and damping) negative.
  BodySpringHandle add_body_spring(const BodySpringDef& def);
  /// (N) The force the spring applies to body a now (towards body b when stretched), world frame.
  /// @throws std::out_of_range if stale.
  [[nodiscard]] Vec3 body_spring_force(BodySpringHandle h) const;

  // --- Removal -------------------------------------------------------------------------------
  /// Removes a registered object. Its handle (and every copy) is stale at once: every accessor
  /// and remove() reject it with std::out_of_range, also after its slot is reused by a later
  /// registration (the slot's generation is bumped). The next advance() reports the removal once
  /// in its list (MovedObject::removed), after the moved entries. The other objects keep their
  /// handles; the order of the lists (colliders(), particle_systems(), cloths(), the moved list)
  /// may change, since the engine's arrays are compacted by swap-remove.
  /// - a body/collider: all its shapes stop colliding at once (one removal is reported); warm-start
  ///   data of resting contacts against them are dropped;
  /// - a particle system: the attractor springs that pull it are removed with it (not reported
  ///   separately) and force fields forget it (a field left with no system acts on none);
  /// - a force field or attractor spring: it stops acting from the next step.
  /// Random streams are keyed by each kind's registration count, so removing an object does not
  /// change the draws of the others: a system independent of the removed object (no shared
  /// particle-particle group) goes on exactly as in a world that never held it.
  /// @throws std::out_of_range if the handle is null or stale.
  void remove(BodyHandle h);
  void remove(ParticleSystemHandle h);
  void remove(ClothHandle h);
  void remove(ForceFieldHandle h);
  void remove(AttractorSpringHandle h);
  /// A joint stops acting from the next step (removing a body removes its joints with it, their
  /// handles going stale; joints are never in the moved list).
  void remove(JointHandle h);
  void remove(BodySpringHandle h);

  /// FNV-1a 64 hash of the complete simulation state, in a fixed order: time and step count;
  /// for every particle system (in the order of particle_systems()) its live particle count, all
  /// SoA attributes of its live particles (positions, velocities, start-of-step positions when
  /// kept, colours, radii, masses, ages, lifetimes, ids, charges when kept, base radii, tints,
  /// split generations and countdowns), next id, emitter schedule and the states of its four
  /// random generators (emitter, split, charge, splash); for every cloth its vertex positions
  /// and velocities; for every body its pose (centre, rotation quaternion). Equal on the same
  /// build for the same scene, seed and number of advance() calls at any thread count; any
  /// change of one bit of that state changes it with overwhelming probability. Cost: linear in
  /// the state size. Definitions (model) are not hashed.
  [[nodiscard]] std::uint64_t state_hash() const;

  /// The complete state that carries from one advance() to the next, as bytes (a private binary
  /// format with a version and one checked section per subsystem; docs/cache.md): time and step
  /// count, body and shape poses and velocities, rigid state, contact manifolds with their
  /// warm-start impulses, sleep state, every live particle, emitter schedules and random
  /// generators, particle warm starts, cloth state. Replaces `out`'s contents (its capacity is
  /// reused). Deterministic: equal states give equal bytes. Definitions are not included.
  void save_state(std::string& out) const;
  /// Restores a state written by save_state() of a world registered with the same definitions in
  /// the same order (the same scene): this world then continues bit-identically to the one it was
  /// saved from (same state_hash() now and after any further advance()). The next advance()
  /// reports only what moves from here on; poses() gives every moving body's current pose.
  /// @throws StateError (state_error.hpp) naming what differs when the bytes are truncated, of
  ///         another format, or for other objects (counts, particle capacity, body types), and
  ///         naming the quantity when a value is one no step writes: NaN or infinite, a particle
  ///         beyond the divergence bounds, a non-unit orientation, rigid arrays that break their
  ///         relations (I_b⁻¹ I_b = E, I_w⁻¹ = R I_b⁻¹ Rᵀ, ω = I_w⁻¹ L; Coutinho §4.2), a negative
  ///         normal impulse (docs/cache.md lists them); the world is then left partly loaded and
  ///         should be discarded.
  void load_state(std::string_view bytes);
  /// The pose of every kinematic and dynamic body (the engine's dense order) as the moved list
  /// reports it: what a renderer needs after load_state() to show the restored state.
  [[nodiscard]] std::vector<MovedObject> poses() const;
  /// Version of save_state()'s layout (bumped whenever a section changes).
  [[nodiscard]] static std::uint32_t state_format();

  /// Current pose of a body (for the initial render list): its frame's origin and rotation (a
  /// one-shape body with an identity offset: that shape's centre and rotation), except a body
  /// whose only shape is a plane at an identity offset: the plane's reference point and a
  /// rotation taking local +z to its normal.
  /// @throws std::out_of_range if stale.
  [[nodiscard]] MovedObject pose(BodyHandle h) const;

  /// Whether a dynamic body is awake (false: asleep, frozen at rest with its island until
  /// something moving touches it; see WorldDef::allow_sleeping). Static and kinematic bodies
  /// are always awake. @throws std::out_of_range if stale.
  [[nodiscard]] bool is_awake(BodyHandle h) const;

  /// Wakes a sleeping dynamic body and every body asleep in its island (nothing for an awake,
  /// static or kinematic body). Call it after changing what acts on a body from outside the
  /// engine. @throws std::out_of_range if stale.
  void wake(BodyHandle h);

  /// (m/s, rad/s) Linear velocity of a body's frame origin and angular velocity, world frame
  /// (zero for a static body, the path's for a kinematic one). @throws std::out_of_range if stale.
  [[nodiscard]] std::pair<Vec3, Vec3> velocity(BodyHandle h) const;

  /// Mass, centre of mass, velocities and momenta of a dynamic body (world frame).
  /// @throws std::out_of_range if stale; std::invalid_argument if the body is not dynamic.
  [[nodiscard]] BodyMotion motion(BodyHandle h) const;
  /// Live particles of a system. @throws std::out_of_range if the handle is stale.
  [[nodiscard]] ParticleView particles(ParticleSystemHandle h) const;
  [[nodiscard]] const ParticleSystemDef& definition(ParticleSystemHandle h) const;

  [[nodiscard]] double time() const;                ///< (s) simulated time
  [[nodiscard]] std::uint64_t step_count() const;   ///< internal steps taken
  /// Particles ever emitted by the system (for rate tests and statistics): ids handed out so far,
  /// by the emitter or spawn_particle(); births dropped at max_particles are not counted.
  [[nodiscard]] std::uint64_t emitted_count(ParticleSystemHandle h) const;
  /// Particles of the system removed because their centre was found inside a solid collider
  /// (sphere, cylinder, capsule, closed mesh) after their step (Coutinho §3.4.2), since registration.
  /// @throws std::out_of_range if the handle is stale.
  [[nodiscard]] std::uint64_t removed_inside_count(ParticleSystemHandle h) const;
  [[nodiscard]] std::vector<ParticleSystemHandle> particle_systems() const;
  /// Every body (the colliders of the scene format included), in the engine's dense order.
  [[nodiscard]] std::vector<BodyHandle> colliders() const;

  // --- Cloth (Coutinho §3.9.2; see cloth.hpp) ------------------------------------------------
  /// Registers a cloth. Each internal step of advance() steps every cloth after the particle
  /// systems, with one cloth step per internal step (WorldDef::max_step; one implicit step per
  /// 1/60 s frame is stable), colliding its vertices with the colliders at their end-of-step
  /// pose. Gust noise is seeded from (WorldDef::seed, cloth index).
  /// @throws std::invalid_argument naming the ClothDef field on a bad definition.
  ClothHandle add_cloth(const ClothDef& def);
  /// Current vertices, normals, UVs and triangles. Valid until the next advance().
  /// @throws std::out_of_range if the handle is stale.
  [[nodiscard]] ClothView cloth(ClothHandle h) const;
  [[nodiscard]] ClothStats cloth_stats(ClothHandle h) const;
  [[nodiscard]] const ClothDef& definition(ClothHandle h) const;
  [[nodiscard]] std::vector<ClothHandle> cloths() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace simreel::sim
