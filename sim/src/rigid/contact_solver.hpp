#pragma once
// Sequential-impulse contact solver (Catto 2005, "Iterative Dynamics with Temporal Coherence";
// Catto 2006, "Fast and Simple Physics using Sequential Impulses"): the impulses with friction
// of Coutinho §4.8 applied one contact at a time, iterated, with accumulated-impulse clamping,
// so that the iteration converges to the solution of the contact LCP of §4.8 / App. G (checked
// against rigid/lcp.hpp in the tests). Private; works on RigidBodies by index, no World.
//
// Conventions: the normal is unit, world, from body a to body b; the relative velocity is
// v_rel = v_b(p) - v_a(p), so v_n = v_rel·n < 0 means approaching. The impulse λ n (N s) acts
// on b and -λ n on a. Either body may be kStaticBody (infinite mass, not in RigidBodies).
//
// Choices (and why):
// - Friction (both solvers; the soft step bounds it differently, see solve_soft): the circular Coulomb
//   cone, both tangent rows of a contact solved together from the same velocities: the pair that stops the slip (the whole 2×2 tangent block inverted) when it
//   lies in the disc of radius μ λ_n (sticking), else a pair on the disc's rim along p - m̄ v_t
//   with one mass m̄ = 2 / trace K_t for both rows (sliding), which settles against the slip
//   itself whatever the tangent basis. Solving t1 then t2 with their own masses (the former
//   rule) made friction anisotropic: sliding along t1 off a box's corners met 6-7 % less of it.
// - Static and kinetic friction (Coulomb's two coefficients, Coutinho §3.6.3; PhysX's static and
//   dynamic friction): a contact whose slip (tangential relative speed) at the step's start is
//   at most stick_speed sticks for the step, its disc of radius μ_s λ_n; one slipping faster
//   slides on the disc of μ λ_n. The decision is per step, not per sweep: within the sweeps a
//   point's share of a sticking patch's friction can pass its own μ_s λ_n on the way to an
//   answer that sticks, so breaking loose there let boxes slide that hold. A body that can no
//   longer stick moves on at g (sin θ - μ_s cos θ) for the step or steps until its slip passes
//   stick_speed, then slides at g (sin θ - μ cos θ); one slowing down sticks once its slip is
//   below stick_speed. With μ_s = μ nothing changes.
// - Restitution: from the relative normal velocity recorded by prepare(), which runs before
//   the velocity integration, so a resting contact does not see the step's gravity as an impact;
//   only above `restitution_threshold` (resting contact, Coutinho §3.6.3).
// - Speculative contacts: a contact with depth < 0 (a gap g = -depth, from a contact margin)
//   only limits the approach speed to g/h, so it closes the gap by the end of the step at most;
//   an approach faster than g/h (and than restitution_threshold) is an impact within the step,
//   whose target, when e > 0, is the larger of -g/h and -e v_n (a swept body stopped short of a
//   wall bounces).
// - Position error: split impulses (Catto 2006; Box2D v2.x's "split impulse"): penetration
//   beyond the slop is removed by pseudo-velocities that move the positions for one step and are
//   then forgotten. Baumgarte stabilisation adds the correction to the real velocity, which
//   injects energy (a resting box hops, a bouncing sphere rises higher than e² h); split
//   impulses keep the velocity solve free of it, so restitution and resting contact stay exact.
// - Warm starting: prepare() keeps the cached impulses in ContactPoint; warm_start() applies
//   them. The tangent basis is a fixed function of the normal (tangent_basis()), so a persistent
//   contact whose normal does not change keeps its tangent impulses meaningful.
// - Determinism: contacts are solved in the order given; no hashing, no threads.
// - Memory: the solver's rows live in one vector that is only ever resized; after the first
//   steps (or reserve()) a step allocates nothing.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "rigid/body_state.hpp"

namespace simreel::sim::detail {

/// Body index meaning "the static world" (infinite mass, zero velocity).
inline constexpr std::uint32_t kStaticBody = std::numeric_limits<std::uint32_t>::max();

/// One contact point between bodies a and b, plain data. The caller (narrow phase or manifold)
/// fills the geometry and material; the solver reads the cached impulses to warm-start and
/// writes the accumulated ones back (copy them into next step's matching contact).
struct ContactPoint {
  std::uint32_t body_a = kStaticBody;  ///< index into RigidBodies, or kStaticBody
  std::uint32_t body_b = kStaticBody;  ///< index into RigidBodies, or kStaticBody
  Vec3 point = Vec3::Zero();           ///< (m) world; the contact (e.g. midway between surfaces)
  Vec3 normal = Vec3::UnitZ();         ///< unit, world, from a to b
  double depth = 0.0;                  ///< (m) penetration along the normal (> 0), or -gap
  double restitution = 0.0;            ///< e in [0, 1]
  double friction = 0.0;               ///< Coulomb μ >= 0 of sliding (kinetic)
  double static_friction = -1.0;       ///< μ_s of sticking; < 0 or below μ: = friction
  /// (m) Radius of a round side (sphere, capsule; 0 otherwise): its surface point under the
  /// contact stays below its centre (or segment) as it turns, so the soft step tracks that
  /// centre, not a point fixed in the body (a ball rolling down a slope sank otherwise).
  double round_a = 0.0, round_b = 0.0;
  /// A side of rotational symmetry that is not round (a cylinder; zero otherwise): its axis
  /// (unit, world) and the contact point's offset from that axis, perpendicular to it (m,
  /// world). Spin about the axis leaves the surface where it is, so the soft step tracks the
  /// offset turned only by the part of the body's turn that tilts the axis (a rolling wire's
  /// contact otherwise rode up with the body: 1000 rad/s about a 0.5 mm axis let it sink).
  Vec3 axis_a = Vec3::Zero(), axis_b = Vec3::Zero();
  Vec3 radial_a = Vec3::Zero(), radial_b = Vec3::Zero();
  double normal_impulse = 0.0;         ///< (N s) accumulated, >= 0: warm start in, result out
  double tangent_impulse[2] = {0.0, 0.0};  ///< (N s) along tangent_basis(normal): in and out
};

/// Two unit tangents t1, t2 with (t1, t2, n) right-handed, a fixed function of the unit n
/// (Coutinho App. A's tangent plane from a normal; Box2D/Catto's choice of the smaller component).
void tangent_basis(const Vec3& n, Vec3& t1, Vec3& t2);

struct ContactSolverSettings {
  int velocity_iterations = 10;  ///< sweeps over all contacts for the velocities
  int position_iterations = 4;   ///< sweeps for the split-impulse pseudo-velocities
  /// (m/s) restitution only for approach speeds above this (resting contact below it).
  double restitution_threshold = 0.5;
  double slop = 0.001;       ///< (m) penetration left alone (keeps contacts alive, no jitter)
  /// (m/s) slip at the step's start up to which a contact sticks (static friction μ_s).
  double stick_speed = 1e-3;
  double split_beta = 0.2;   ///< fraction of penetration beyond slop removed per step, (0, 1]
  bool warm_start = true;    ///< apply the cached impulses before iterating
  // Soft step (solve_soft and friends; Catto 2024, Box2D v3's solver):
  // Tuned on bench_bodies' 20-row pyramid at 1/60 s with 4 substeps: Box2D's 30 Hz and one
  // biased sweep let it sink 3 cm (a soft spring per layer) and lean; 60 Hz (there the cap),
  // two biased sweeps and no slop keep its top within 1 cm and it falls asleep in about a second.
  /// (Hz) stiffness f of the soft contact, capped at a quarter of the substep rate (Box2D v3's
  /// cap, for stability); the default is the cap itself. A stack's soft contacts sag by about
  /// g / (2π f)² per layer and box of load, whatever the boxes' size, so a fixed f (60 Hz until
  /// stop 99) left every 10-box stack ~7 mm low at any substep count: a stack of 2 cm boxes sank
  /// a third of a box and fell. At the cap the sag falls with the substep squared, and the soft
  /// step tends to rigid contact as the substeps get finer.
  double contact_hertz = std::numeric_limits<double>::infinity();
  double damping_ratio = 10.0;    ///< ζ of the soft contact (heavily over-damped: no bounce from the push)
  double max_push_speed = 3.0;    ///< (m/s) largest speed at which overlap is pushed out
  double soft_slop = 0.0;         ///< (m) overlap the soft step leaves alone
  /// (m/s) stick_speed of the soft step, decided once per step at its start: its three sweeps
  /// per substep leave a sticking contact slipping at up to a few mm/s. A body breaking loose
  /// slides with μ_s for at most that step (its last substeps' clamp was too noisy to go by).
  double soft_stick_speed = 0.01;
  int substep_iterations = 2;     ///< biased sweeps per substep
  int relax_iterations = 1;       ///< unbiased sweeps per substep
};

class ContactSolver {
 public:
  ContactSolver() = default;
  explicit ContactSolver(const ContactSolverSettings& settings) : settings_(settings) {}

  [[nodiscard]] const ContactSolverSettings& settings() const { return settings_; }
  ContactSolverSettings& settings() { return settings_; }

  /// Reserves room for n contacts (no allocation in later steps with at most n).
  void reserve(std::size_t n) { rows_.reserve(n); }

  /// Builds the solver rows: lever arms, tangents, effective masses, the restitution target
  /// from the current relative normal velocity, the split-impulse target from the depth. Call
  /// before integrate_velocities() (see restitution above). Asserts on a bad body index.
  /// `own_surface`: each side's lever arm runs to its own surface point (the contact point
  /// -/+ half the depth along the normal; prepare_soft) instead of the midpoint.
  void prepare(const RigidBodies& bodies, std::span<const ContactPoint> contacts, double h,
               bool own_surface = false);

  /// Applies the cached impulses of `contacts` (same span as prepare()) to the velocities, or
  /// zeroes them when settings().warm_start is false.
  void warm_start(RigidBodies& bodies, std::span<ContactPoint> contacts);

  /// One Gauss–Seidel sweep over the contacts (friction, then normal, per contact). Returns the
  /// largest change of an accumulated normal impulse in the sweep (N s): a convergence measure.
  double iterate_velocities(RigidBodies& bodies, std::span<ContactPoint> contacts);

  /// settings().position_iterations sweeps of split impulses on the pseudo-velocities
  /// (RigidBodies::bias_velocity, bias_angular_velocity).
  void solve_positions(RigidBodies& bodies);

  /// Writes L = I_w ω back for every dynamic body touched by a contact.
  void finish(RigidBodies& bodies) const;

  /// warm_start, settings().velocity_iterations sweeps, solve_positions, finish.
  void solve(RigidBodies& bodies, std::span<ContactPoint> contacts);

  // --- Soft step (Catto 2024, "Solver2D"; Box2D v3). Contacts are found once per step of
  // length h; the step is cut into n substeps of h/n, each: integrate velocities, warm start,
  // solve_soft(bias), integrate positions, solve_soft(relax); then restitution once. The
  // normal and tangents stay those of the step's start (prepare_soft); the separation is brought
  // up to date each substep from the bodies' displacement and turn since then (anchors fixed in
  // the bodies), which costs a few products per contact instead of a narrow phase. The lever
  // arms, the angular response I_w⁻¹ (r × d) and the effective masses turn with the bodies
  // (track_separations, refresh_soft): in 3D the world inertia turns with the body (Box2D's 2D
  // inertia is a scalar), and a response left at the step's start put a needle's axial spin
  // across its axis (a 1 mm wire gained 10⁸ times its energy at one landing); a body turned by
  // less than kRefreshTurn since its rows were computed keeps them. Overlap is removed by a soft
  // constraint (a damped spring of contact_hertz, damping_ratio, through mass and impulse
  // scales: Catto's "soft step") whose bias goes into the real velocity and is then relaxed
  // away, so no pseudo-velocities.

  /// Rows as prepare(), plus the start poses of all bodies and each contact's separation and
  /// lever arms; `h_sub` is the substep (s).
  void prepare_soft(const RigidBodies& bodies, std::span<const ContactPoint> contacts, double h_sub);
  /// Brings every contact's separation up to date with the bodies' positions (after each
  /// integrate_positions of a substep).
  void track_separations(const RigidBodies& bodies);
  /// Recomputes the angular response I_w⁻¹ (r × d) and effective masses of every row with a
  /// body that turned by more than kRefreshTurn (rad) or whose world inverse inertia moved by
  /// more than that fraction since its rows were last computed, from the current lever arms
  /// (track_separations) and world inertia (prepare_soft computed them all).
  void refresh_soft(const RigidBodies& bodies);
  /// Turn (rad) below which refresh_soft keeps a body's rows: the lever arms' error is then
  /// under 1e-4 of their length (a resting pile's jitter), and their refresh was 15 % of a
  /// 210-box pyramid's step.
  static constexpr double kRefreshTurn = 1e-4;
  /// Applies the accumulated impulses (of this step so far, or the cached ones at its start).
  void warm_start_soft(RigidBodies& bodies, std::span<ContactPoint> contacts) const;
  /// One sweep: per contact the normal row, then the tangent pair (friction_pair, isotropic)
  /// bounded by the normal impulse just found (Box2D v3's order; bounded by the impulse the warm
  /// start carried over from an impact, friction spun a 100 m/s box off a wall). With `use_bias`
  /// the overlap is pushed out softly, without it only the approach is stopped (relax). A
  /// contact still apart (speculative) lets the bodies close the gap within the substep but no
  /// more.
  void solve_soft(RigidBodies& bodies, std::span<ContactPoint> contacts, bool use_bias);
  /// Newton's impact law once after the substeps for contacts that approached faster than
  /// restitution_threshold at the step's start and took an impulse.
  void restitution_soft(RigidBodies& bodies, std::span<ContactPoint> contacts);

 // The solver's rows (public only so the solver's helper functions can take them).
  /// One direction d (normal or tangent) of a contact, with everything an iteration needs
  /// precomputed so a sweep does no matrix products: the lever-arm crosses r × d and the
  /// angular velocity change per unit impulse I_w⁻¹ (r × d) of each side (zero for a side that
  /// does not move).
  struct Axis {
    Vec3 d;
    Vec3 ra_d, rb_d;  ///< ra × d, rb × d
    Vec3 ia_d, ib_d;  ///< I_a⁻¹ (ra × d), I_b⁻¹ (rb × d); zero unless dynamic
    double mass;      ///< 1 / (J M⁻¹ Jᵀ) along d (kg)
  };
  struct Row {
    std::uint32_t a, b;
    bool move_a, move_b;     ///< dynamic sides (impulses change their velocities)
    double inv_mass_a, inv_mass_b;
    Axis n, t1, t2;
    double target_vn;        ///< (m/s) the normal velocity to reach: -e v_n⁻ or 0
    double target_bias;      ///< (m/s) pseudo-velocity to reach: β (depth - slop)/h or 0
    double sticking_mass[3]; ///< (kg) K_t⁻¹ of the 2×2 tangent block: [0] [1]; [1] [2]
    double sliding_mass;     ///< (kg) 2 / trace K_t
    double friction;         ///< μ (kinetic)
    double static_friction;  ///< μ_s >= μ
    bool sliding;            ///< slipping at the step's start: bounded by μ, not μ_s
    double bias_impulse;     ///< accumulated split impulse (N s), >= 0
  };
  /// A contact's soft-step data: lever arms at the step's start and the separation they give.
  struct SoftRow {
    Vec3 ra, rb;             ///< (m) contact point - centre of mass of a, b (zero for static)
    Vec3 turn_a, turn_b;     ///< (m) the point of a, b that turns with it: ra, rb, or a round side's centre or axis point
    Vec3 axis_a, axis_b;     ///< ContactPoint::axis_a, axis_b (zero: none)
    Vec3 radial_a, radial_b; ///< ContactPoint::radial_a, radial_b
    Vec3 arm_a, arm_b;       ///< (m) the tracked contact point - centre of mass, now (track_separations)
    double separation;       ///< (m) -depth at the step's start
    double current;          ///< (m) separation at the bodies' current poses (track_separations)
    double restitution;      ///< e
    double approach;         ///< (m/s) v_n at the step's start (before gravity), or at first push
    double max_normal;       ///< (N s) largest normal impulse of the step
  };

 private:
  ContactSolverSettings settings_;
  std::vector<Row> rows_;
  std::vector<SoftRow> soft_;
  std::vector<Vec3> start_x_;          ///< (m) bodies' centres at prepare_soft
  std::vector<Quat> start_q_;          ///< bodies' orientations at prepare_soft
  std::vector<Vec3> moved_x_;          ///< (m) scratch: displacement since then
  std::vector<Mat3> turned_;           ///< scratch: rotation since then minus E
  std::vector<Quat> refreshed_q_;      ///< bodies' orientations when their rows were computed
  std::vector<Mat3> refreshed_inertia_;  ///< and their world inverse inertia then
  std::vector<std::uint8_t> stale_;    ///< scratch: body's rows to recompute (refresh_soft)
  double h_sub_ = 0.0;
  double bias_rate_ = 0.0, mass_scale_ = 1.0, impulse_scale_ = 0.0;
};

/// Relative velocity v_b(p) - v_a(p) (m/s, world) at world point p.
[[nodiscard]] Vec3 relative_velocity(const RigidBodies& bodies, std::uint32_t a,
                                     std::uint32_t b, const Vec3& p);

/// One full step of the bodies with the given contacts (found at the current positions):
/// gravity g (m/s²) into the accumulators, prepare, integrate_velocities, solve,
/// integrate_positions, clear_forces. The order every caller (tests, the World's bodies stage)
/// should follow.
void step_with_contacts(RigidBodies& bodies, ContactSolver& solver,
                        std::span<ContactPoint> contacts, double h, const Vec3& g);

}  // namespace simreel::sim::detail
