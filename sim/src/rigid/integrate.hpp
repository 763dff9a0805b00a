#pragma once
// Time integration of rigid bodies: semi-implicit (symplectic) Euler (Coutinho App. B applied
// to the state of §4.2; quaternion kinematics of App. C). Private.
//
// One step of length h (s) is split in two so that the contact solver runs between them:
//   integrate_velocities:  v ← (v + h F/m) / (1 + h k_v/m)
//                          L ← (E + h k_ω I_w⁻¹)⁻¹ (L + h τ),   ω ← I_w⁻¹ L
//   (contact solve: changes v and ω, writes L = I_w ω back)
//   integrate_positions:   x ← x + h (v + v_bias)
//                          q ← exp(h (ω_½ + ω_bias)) ⊗ q,  ω_½ = I_w(q_½)⁻¹ L with q_½
//                          the half-step orientation (fixed point, 3 rounds),
//                          I_w⁻¹ ← R I_b⁻¹ Rᵀ,   ω ← I_w⁻¹ L
// Positions use the new velocities (symplectic Euler).
//
// Gyroscopic term: the angular state integrated is the world angular momentum L, for which
// dL/dt = τ holds with no ω × I ω term; the precession comes from recomputing ω = I_w⁻¹ L with
// the new orientation. Torque-free, L is therefore conserved to rounding, exactly, for any h
// (Catto's implicit gyroscopic step would conserve it only approximately, trading that for
// energy dissipation). The kinetic energy ½ ω·L is not conserved exactly, but the orientation
// turns by the midpoint ω (implicit midpoint in q with L held): a symmetric rule, so the energy
// error stays bounded and second order in h. The explicit ω(q_n) of Coutinho App. C's
// q + ½ h ω ⊗ q drifts instead: a thin plank tumbling about its intermediate axis gained 100
// times its energy in 2 s (test_rigid_body.cpp).
//
// Needles: the midpoint's fixed point contracts only while h |ω| (κ - 1) < 1 (κ the inertia
// ratio). Where its last round still moves ω by more than 1e-3 |ω|, the step turns the body by
// a symmetric splitting of the free rigid body instead (Dullweber, Leimkuhler & McLachlan 1997;
// Fassò 2003): exact for an axisymmetric body, bounded energy for the others at any step. A 2 m
// rod of 1 mm radius tumbling at 5 rad/s had gained 130 times its energy in 10 s at 1/240 s.
// Bodies whose rounds converge (every scene of the project) keep the midpoint's bits.
//
// Drag (Coutinho §4.3.2) is applied implicitly (backward Euler on the linear drag term) so that
// a large k h / m damps instead of overshooting: v decays by 1/(1 + h k/m) per step, which
// tends to e^{-k t/m} with an error first order in h.
//
// The quaternion is renormalised every step (App. C: drift off the unit sphere would scale and
// shear the rotation matrix).

#include "rigid/body_state.hpp"

namespace simreel::sim::detail {

/// Velocity half of the step for every dynamic body (static ones are skipped): forces, torques
/// and drag over h (s, > 0). Accumulators are left as they are (see clear_forces()).
void integrate_velocities(RigidBodies& bodies, double h);

/// Position half of the step for every dynamic body: moves x and q with the current velocities
/// plus the split-impulse pseudo-velocities (then zeroed), renormalises q, refreshes I_w⁻¹ and
/// ω = I_w⁻¹ L.
/// `motion` picks what moves them: both (the default), only the real velocities (the split
/// pseudo-velocities kept for a later call), or only the pseudo-velocities — so that the joint
/// projection can tell the motion it must turn into velocity from the contacts' position
/// correction it must not (core/stage_bodies.cpp).
enum class Motion { both, velocity, bias };
void integrate_positions(RigidBodies& bodies, double h, Motion motion = Motion::both);

/// A step with no contacts: integrate_velocities, integrate_positions, clear_forces.
void step_free(RigidBodies& bodies, double h);

/// L ← I_w ω for body i (after a solver changed ω directly).
void sync_angular_momentum(RigidBodies& bodies, std::size_t i);

}  // namespace simreel::sim::detail
