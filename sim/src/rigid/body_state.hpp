#pragma once
// Dynamic state of rigid bodies as structure-of-arrays (Coutinho §4.2: the state
// Y = (x, R, P, L) — the book writes (r, R, L, H) for position, rotation, linear and angular
// momentum; here x, q, v = P/m, L), the force and torque accumulators, and the force–torque
// pairs of §4.3 (a force at a point, gravity, damped springs). Private; no World dependency: the
// World's `bodies` stage owns one RigidBodies and indexes it by slot.
//
// Frames and units: positions, velocities, momenta, forces and torques are in the world frame,
// SI units; the orientation q maps body-frame vectors to world ones (x_world = R(q) x_body + x,
// with x the centre of mass, so the body frame is centred on the centre of mass). Inertia is given
// in the body frame about the centre of mass; the world inverse inertia I_w⁻¹ = R I_b⁻¹ Rᵀ is
// cached per body and refreshed whenever q changes.
//
// Angular state: L (world angular momentum about the centre of mass) is the integrated quantity,
// ω = I_w⁻¹ L is derived and cached (the contact solver works on ω and writes L back). Keeping L
// makes the torque-free motion conserve L exactly and carries the gyroscopic term ω × I ω
// implicitly (dL/dt = τ in the world frame; Coutinho eq. 4.15–4.20).
//
// A body with mass 0 at creation is static (infinite mass: inverse mass and inverse inertia
// zero); integration leaves it where it is.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "simreel/sim/types.hpp"

namespace simreel::sim::detail {

/// What one body starts with. Defaults: a static body at the origin.
struct RigidBodyDef {
  Vec3 position = Vec3::Zero();          ///< (m) centre of mass, world
  Quat orientation = Quat::Identity();   ///< body -> world; normalised on add
  Vec3 linear_velocity = Vec3::Zero();   ///< (m/s) of the centre of mass, world
  Vec3 angular_velocity = Vec3::Zero();  ///< (rad/s) world
  double mass = 0.0;                     ///< (kg) > 0 dynamic; 0 static (infinite mass)
  Mat3 inertia = Mat3::Zero();  ///< (kg m²) body frame, about the centre of mass; SPD if dynamic
  double linear_drag = 0.0;     ///< k_v (N s/m) >= 0: force -k_v v (Coutinho §4.3.2)
  double angular_drag = 0.0;    ///< k_ω (N m s) >= 0: torque -k_ω ω (Coutinho §4.3.2)
};

/// All bodies, one entry per array per body (n = size()). Append with add_body(); indices are
/// stable (removal is the owner's business: swap-remove every array alike).
struct RigidBodies {
  std::vector<Vec3> position;          ///< x (m), centre of mass, world (n)
  std::vector<Quat> orientation;       ///< q, unit, body -> world (n)
  std::vector<Vec3> linear_velocity;   ///< v (m/s), world (n)
  std::vector<Vec3> angular_momentum;  ///< L (kg m²/s) about the centre of mass, world (n)
  std::vector<Vec3> angular_velocity;  ///< ω = I_w⁻¹ L (rad/s), world (n)
  std::vector<double> mass;            ///< (kg); 0 for static (n)
  std::vector<double> inv_mass;        ///< (1/kg); 0 for static (n)
  std::vector<Mat3> inertia_body;      ///< I_b (kg m²), body frame (n)
  std::vector<Mat3> inv_inertia_body;  ///< I_b⁻¹, body frame; 0 for static (n)
  std::vector<Mat3> inv_inertia_world;  ///< I_w⁻¹ = R I_b⁻¹ Rᵀ, world; kept current with q (n)
  std::vector<Vec3> force;              ///< accumulated force (N), world; cleared per step (n)
  std::vector<Vec3> torque;  ///< accumulated torque (N m) about the centre of mass, world (n)
  std::vector<double> linear_drag;   ///< k_v (N s/m) (n)
  std::vector<double> angular_drag;  ///< k_ω (N m s) (n)
  /// Split-impulse pseudo-velocities (m/s, rad/s; world): written by the contact solver's
  /// position pass, added to the displacement of the next integrate_positions() and then zeroed,
  /// so pushing bodies apart never adds kinetic energy (Catto 2006, "Fast and Simple Physics
  /// using Sequential Impulses").
  std::vector<Vec3> bias_velocity;
  std::vector<Vec3> bias_angular_velocity;
  /// 1: a dynamic body put to sleep (sleep()): at rest, frozen with zero velocities and zero
  /// inverse mass, so the integrators skip it and contacts treat it as immovable until wake().
  std::vector<std::uint8_t> asleep;

  [[nodiscard]] std::size_t size() const { return position.size(); }
  /// Moves under forces and contacts: dynamic and awake (inverse mass > 0).
  [[nodiscard]] bool is_dynamic(std::size_t i) const { return inv_mass[i] > 0.0; }
  void reserve(std::size_t n);
};

/// Appends a body and returns its index. Throws std::invalid_argument on a negative or
/// non-finite mass, a dynamic body whose inertia is not symmetric positive definite, a zero or
/// non-finite orientation, or a negative drag coefficient.
std::size_t add_body(RigidBodies& bodies, const RigidBodyDef& def);

/// Removes body i: the last body moves into slot i in every array (swap-remove); the caller
/// re-points whatever named the last index. Asserts i < size().
void swap_remove(RigidBodies& bodies, std::size_t i);

/// Puts dynamic body i to sleep (Box2D's and Bullet's deactivation): v = L = ω = 0, accumulators
/// cleared, inverse mass and world inverse inertia 0, so every pass that moves bodies skips it
/// and a contact meets it as an immovable body. Its pose is kept exactly. Asserts it is dynamic.
void sleep(RigidBodies& bodies, std::size_t i);

/// Wakes body i if asleep: inverse mass 1/m and I_w⁻¹ from its orientation again, at rest.
void wake(RigidBodies& bodies, std::size_t i);

/// Recomputes I_w⁻¹ = R I_b⁻¹ Rᵀ and ω = I_w⁻¹ L of body i from its current q and L.
void update_derived(RigidBodies& bodies, std::size_t i);

/// World inertia I_w = R I_b Rᵀ (kg m²) of body i.
[[nodiscard]] Mat3 world_inertia(const RigidBodies& bodies, std::size_t i);

/// Velocity (m/s, world) of the body-fixed point now at world position p: v + ω × (p - x).
[[nodiscard]] Vec3 point_velocity(const RigidBodies& bodies, std::size_t i, const Vec3& p);

/// Adds force F (N, world) at the centre of mass.
void apply_force(RigidBodies& bodies, std::size_t i, const Vec3& F);

/// Adds torque τ (N m, world).
void apply_torque(RigidBodies& bodies, std::size_t i, const Vec3& tau);

/// Adds force F (N, world) acting at world point p: the force–torque pair F at the centre of
/// mass and τ = (p - x) × F (Coutinho §4.3, eq. 4.20).
void apply_force_at(RigidBodies& bodies, std::size_t i, const Vec3& F, const Vec3& p);

/// Adds m g (N) to every dynamic body; g (m/s²) world, e.g. (0, 0, -9.81).
void apply_gravity(RigidBodies& bodies, const Vec3& g);

/// Damped spring between body-fixed points (Coutinho §4.3.3, eqs. 4.21–4.22): pa_body on body
/// a and pb_body on body b (m, each in its body frame), rest length (m) >= 0, stiffness ks (N/m),
/// damping kd (N s/m). With d = p_b - p_a and u = d/|d|, the force on a is
/// F = (ks (|d| - rest) + kd (v_b(p_b) - v_a(p_a))·u) u and -F on b, each applied at its point.
/// rest = 0 is the mouse spring of §4.3.4 when b is a static body moved by the caller. A
/// coincident pair (|d| = 0) gives no force.
void apply_spring(RigidBodies& bodies, std::size_t a, const Vec3& pa_body, std::size_t b,
                  const Vec3& pb_body, double rest, double ks, double kd);

/// Applies impulse J (N s, world) at world point p: v += J/m, L += (p - x) × J, ω = I_w⁻¹ L.
void apply_impulse_at(RigidBodies& bodies, std::size_t i, const Vec3& J, const Vec3& p);

/// Zeroes the force and torque accumulators of every body.
void clear_forces(RigidBodies& bodies);

/// Kinetic energy (J) of body i: ½ m v² + ½ ω·L.
[[nodiscard]] double kinetic_energy(const RigidBodies& bodies, std::size_t i);

}  // namespace simreel::sim::detail
