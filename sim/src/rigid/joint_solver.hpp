#pragma once
// Joint solver for articulated rigid bodies (Coutinho Ch. 5). Private; works on RigidBodies by
// index like the contact solver, and is driven with it (core/stage_bodies.cpp).
//
// Formulation (and why):
// - Lagrangian multipliers (§5.1–5.3): every joint contributes equality rows J_i v = 0 on the
//   velocities of its two bodies (spherical: the anchor points' velocities agree, eq. 5.5;
//   hinge: also the relative angular velocity across its axis is zero; fixed: all of it). The
//   multipliers of all joints come from ONE linear system K λ = -J v with K = J M⁻¹ Jᵀ, the
//   impulse form (forces × h) of the book's eq. 5.12 system: its 3×3 blocks are the book's
//   (1/m E - r̃ I⁻¹ r̃) matrices of eq. 5.8, with the signs of Fig. 5.4 (+ for the joint's body b,
//   - for body a). K is sparse (a block couples two joints only through a shared body), so it is
//   factorised as a sparse LDLᵀ with a fill-reducing ordering (Eigen's SimplicialLDLT, AMD): on
//   a tree (a chain, a ragdoll) that ordering eliminates leaves first and gives no fill-in, the
//   O(n) solve of Baraff 1996 ("Linear-time dynamics using Lagrange multipliers"); closed loops
//   get a little fill. A tiny diagonal regularisation (1e-10 of K's mean diagonal) keeps
//   redundant loops (a planar four-bar of hinges) factorisable.
// - Solved with the contacts (§5.4): the contact solver's sequential impulses and the exact
//   joint solve alternate (block Gauss–Seidel); each sweep ends with the joint solve, so every
//   collision impulse on one link is passed through the joints to the whole articulation before
//   the next sweep, and the velocities leaving the solver satisfy the joints exactly. This is
//   the book's "all collision impulses (external and internal) computed together" (§5.4), with
//   the contacts' inequalities handled iteratively instead of by one LCP.
// - Limits, motors and joint damping are one-dimensional angular rows solved by sequential
//   impulses beside the contacts (a limit: impulse >= 0, speculative until it is reached; a
//   motor: |impulse| <= max torque × h; damping: an implicit soft row).
// - Drift (§5.4's fictitious zero-rest-length spring): instead of a spring, whose stiffness must
//   be tuned per mass and which makes the system stiff, the positions are projected back onto the
//   joints after the step by Newton iterations on the position errors C (K Δ = -C to 1e-7 m),
//   keeping the step's factorisation while each round cuts the error tenfold (ragdolls,
//   pendulums) and relinearising at the current positions when it does not (a whipping chain);
//   then limits are projected the same way.
// - Energy: the velocity solve makes the velocities tangent to the joints at the START of the
//   step, so the motion drifts off them at second order (a pendulum's bob flies out along the
//   tangent) and the next solve strips that normal part: an O(h ω²) loss — a double pendulum
//   loses a quarter of its energy in 10 s at 1/240 s. So the projection's displacement is
//   added to the velocities (Δx/h: RATTLE, Andersen 1983; the position multipliers act as
//   impulses over the step), which makes the scheme symplectic for a free articulation: a double
//   pendulum keeps its energy within 0.5% (tests/sim/test_joints.cpp). An articulation that
//   touches something takes the projection as a position correction only: the contacts
//   dissipate anyway, and their split-impulse push must not become joint velocity. (The
//   book's acceleration-level term ω × (ω × r) of eq. 5.8, as a velocity target of ½ h J̇ v,
//   keeps a free double pendulum's energy as well; RATTLE was kept because it needs no explicit
//   term quadratic in ω, which amplifies any spike of ω a contact gives a light link.)
// - Geometric stiffness (Andrews, Teichmann & Kry 2017): the solve takes each joint force's
//   moment with the step's lever arms, explicit in the links' rotation, which a light link under
//   a large force turns faster than the step resolves (a chain of a thousand 1 cm links came
//   apart in a second). Such links get that stiffness added to their inertia for the solve
//   (stiffen_inertia()); links the step resolves are left as they are.
// - Determinism: rows in joint order, bodies in index order; no threads, no hashing.
// - Memory: rows, triplets and vectors are resized, never shrunk; after the first steps of a
//   fixed set of joints a step allocates only inside Eigen's factorisation.

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "rigid/body_state.hpp"
#include "rigid/contact_solver.hpp"
#include "simreel/sim/joint.hpp"

namespace simreel::sim::detail {

/// A joint's constant geometry and parameters, in its bodies' frames. A side that is
/// kStaticBody has its anchor, axis and reference in world coordinates (a static body never
/// moves); a side with a rigid entry has them in that entry's frame (position = centre of mass for
/// dynamic bodies, the body origin for kinematic ones; the body's orientation).
struct JointModel {
  JointType type = JointType::spherical;
  Vec3 local_anchor_a = Vec3::Zero(), local_anchor_b = Vec3::Zero();  ///< (m)
  Vec3 local_axis_a = Vec3::UnitZ(), local_axis_b = Vec3::UnitZ();    ///< unit
  Vec3 local_ref_a = Vec3::UnitX(), local_ref_b = Vec3::UnitX();      ///< unit, ⊥ axis
  /// q_a⁻¹ q_b at registration (sides without a rigid entry count as the identity).
  Quat rel0 = Quat::Identity();
  bool limit_enabled = false;
  double lower_angle = 0.0, upper_angle = 0.0;  ///< (rad) hinge
  double cone_angle = 0.0;                      ///< (rad) spherical swing
  double twist_lower = -3.141592653589793, twist_upper = 3.141592653589793;  ///< (rad)
  double damping = 0.0;                         ///< (N m s/rad)
  bool motor_enabled = false;
  double motor_speed = 0.0, max_motor_torque = 0.0;
};

/// The two rigid entries a joint acts on this step (kStaticBody for the world or a static body).
struct JointBodies {
  std::uint32_t a = kStaticBody, b = kStaticBody;
};

/// World-frame geometry of a joint at the bodies' current poses.
struct JointFrame {
  Vec3 pa, pb;      ///< (m) anchor as carried by a, by b
  Vec3 ra, rb;      ///< (m) lever arms pa - x_a, pb - x_b (zero for a static side)
  Vec3 axis_a, axis_b, ref_a, ref_b;  ///< unit
  Quat qa, qb;      ///< orientations (identity for a static side)
};
[[nodiscard]] JointFrame joint_frame(const RigidBodies& r, const JointModel& m, JointBodies j);

/// Angles of a joint (rad): hinge angle of b relative to a about the axis, spherical swing
/// between the two axes and twist about the axis (Coutinho-style swing–twist of q_a⁻¹ q_b q_rel0⁻¹).
struct JointAngles {
  double hinge = 0.0, swing = 0.0, twist = 0.0;
};
[[nodiscard]] JointAngles joint_angles(const JointModel& m, const JointFrame& f);

/// What the solver applied to a joint over the step: impulses on body b (N s, N m s, world).
struct JointImpulse {
  Vec3 linear = Vec3::Zero();
  Vec3 angular = Vec3::Zero();
};

class JointSolver {
 public:
  /// Builds the rows of every joint with at least one moving side, assembles K = J M⁻¹ Jᵀ and
  /// factorises it. Call after the contact solver's prepare(), before the velocity integration
  /// (the rows depend on positions only).
  void prepare(const RigidBodies& r, std::span<const JointModel> models,
               std::span<const JointBodies> bodies, double h);

  [[nodiscard]] bool empty() const { return eq_.empty() && ang_.empty(); }

  /// Solves K Δλ = -J v for the current velocities and applies Δλ: afterwards J v = 0 to
  /// round-off. The impulses are summed per joint (impulses()).
  void solve_equality(RigidBodies& r);

  /// One sweep of sequential impulses over limits, motors and damping rows.
  void iterate_rows(RigidBodies& r);

  /// L = I_w ω for every dynamic body a row touched (like ContactSolver::finish).
  void finish(RigidBodies& r) const;

  /// After the positions moved: Newton iterations K Δ = -C(x) on the equality rows' position
  /// errors (with this step's K while each round cuts the error tenfold, else relinearised at
  /// the current positions), then
  /// limit violations removed one by one, then equality again; stops when every error is below
  /// `tolerance` (m, rad) or after `iterations` rounds. Unless `in_contact` is empty, the
  /// displacement of each body with in_contact[i] == 0 is then added to its velocities as
  /// Δx/h, Δθ/h (RATTLE: the position multipliers act as impulses), so a swinging articulation
  /// keeps its energy; an empty span (or a flagged body) takes it as a position correction only.
  void project_positions(RigidBodies& r, std::span<const JointModel> models,
                         std::span<const JointBodies> bodies, double h,
                         std::span<const std::uint8_t> in_contact, int iterations = 4,
                         double tolerance = 1e-7);

  /// Per joint (indices of prepare()'s spans): the impulses applied to body b this step.
  [[nodiscard]] std::span<const JointImpulse> impulses() const { return impulse_; }

  /// Geometric stiffness (Andrews, Teichmann & Kry 2017, "Geometric Stiffness for Real-time
  /// Constrained Multibody Dynamics", after Tournier et al. 2015, "Stable Constrained Dynamics"):
  /// a joint force f at a lever arm r turns with its body, a rotational stiffness of up to
  /// |f| |r| that the velocity solve, with the step's Jacobian, treats explicitly. A light link
  /// under a large tension (the top links of a long chain of small links) then has its rotation
  /// ω² = k / I far above (2 / h)² and the chain blows up within a second. Each moving body's
  /// k = Σ_j |f_j| |r_j| over its joints (forces `force_n` in N, per joint, from the last step's
  /// readings; r_j from its centre of mass) is added to its inertia for the solve as E k h² (the
  /// diagonal bound of Andrews et al.: the exact term is a 3×3 block per body whose eigenvalues
  /// are within ±|f| |r|; the form without its part about r, exact for a tension along r, let
  /// a whipping 1000-link chain come apart at 1.9 s, this one at its whip crack at 4.3 s, which
  /// only a smaller step resolves), scaled by (x - x0) / (1 + x)
  /// with x = k h² / I_min, I_min the smallest principal moment: nothing where the rotation is
  /// resolved (x <= x0 = 0.1, ω h < 0.3, so those articulations keep their bits), the whole
  /// term where it is not: the stiffened rotation's (ω h)² = x / (1 + added / I_min) stays near
  /// 1 or below, inside the step's limit of 4. inv_inertia_world of those bodies is replaced
  /// until restore_inertia(); call around the contact and joint solvers' prepare() (their rows
  /// carry the inverse inertia), not around integrate_velocities (ω = I_w⁻¹ L stays the body's
  /// own).
  void stiffen_inertia(RigidBodies& r, std::span<const JointModel> models,
                       std::span<const JointBodies> bodies, std::span<const double> force_n,
                       double h);
  /// Puts back the inverse inertias stiffen_inertia() replaced.
  void restore_inertia(RigidBodies& r);

 private:
  /// One row of the exact system: J = (ja_lin, ja_ang, jb_lin, jb_ang), M⁻¹Jᵀ per side.
  struct EqRow {
    std::uint32_t a, b, joint;
    std::uint8_t kind;  ///< 0..2 point along x, y, z; 3.. angular
    Vec3 ja_lin, ja_ang, jb_lin, jb_ang;
    Vec3 ma_lin, ma_ang, mb_lin, mb_ang;
  };
  /// One angular row solved by sequential impulses on (ω_b - ω_a)·d.
  struct AngRow {
    std::uint32_t a, b, joint;
    Vec3 d, ia_d, ib_d;
    double mass;     ///< 1 / (k + gamma), k = d·(I_a⁻¹ + I_b⁻¹) d
    double gamma;    ///< soft rows (damping): 1 / (c h); 0 otherwise
    double target;   ///< (rad/s) relative angular speed to reach
    double lo, hi;   ///< bounds of the accumulated impulse (N m s)
    double acc;
  };
  void assemble(const RigidBodies& r);
  void apply(RigidBodies& r, const Eigen::VectorXd& lambda, bool record);
  void rows_for(const RigidBodies& r, const JointModel& m, JointBodies j, std::uint32_t joint,
                double h, bool equality_only);

  std::vector<EqRow> eq_;
  std::vector<AngRow> ang_;
  std::vector<JointImpulse> impulse_;
  std::vector<Eigen::Triplet<double>> triplets_;
  std::vector<std::uint64_t> pattern_, last_pattern_;
  /// Where each triplet's value goes in K_'s value array, while the pattern holds: K is then
  /// refilled in place (the same sums in the same order as setFromTriplets) and re-factorised.
  std::vector<int> slot_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> touch_;  ///< (body, row*2+side) scratch
  Eigen::SparseMatrix<double> K_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt_;
  bool factor_ok_ = false;
  Eigen::VectorXd rhs_, lambda_;
  std::vector<Vec3> dx_, dtheta_;  ///< per-body position corrections (projection scratch)
  std::vector<Vec3> moved_x_;      ///< (m) sum of a body's displacements over the projection
  std::vector<Vec3> moved_theta_;  ///< (N m s · s) sum of the angular impulses × h that turned it
  std::vector<double> stiffness_;   ///< (N m) per body: Σ |f| |r| (stiffen_inertia scratch)
  std::vector<std::pair<std::uint32_t, Mat3>> saved_inertia_;  ///< (body, its own I_w⁻¹)
};

}  // namespace simreel::sim::detail
