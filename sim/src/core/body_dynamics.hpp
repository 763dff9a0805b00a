#pragma once
// Dynamic bodies in the World (private to core/; Coutinho Ch. 4): the rigid state of every
// dynamic and kinematic body, the contact solver, and the contact manifolds of the current and
// previous step keyed by shape pair (warm starting). Static bodies have no rigid entry: they are
// the solver's kStaticBody. Kinematic bodies have one with zero inverse mass whose velocity is
// set from their path each step, so it enters the relative velocity of a contact (§3.7).
//
// Frames: a dynamic body's rigid entry is its centre of mass with the body frame's orientation
// (so the inertia is the full body-frame tensor about the centre of mass, not diagonalised); the
// body frame's origin is x - R c with c = Body::local_com.

#include <compare>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "collision/body_impulses.hpp"
#include "collision/manifold.hpp"
#include "collision/support.hpp"
#include "rigid/body_state.hpp"
#include "rigid/contact_solver.hpp"
#include "rigid/joint_solver.hpp"
#include "simreel/sim/handle.hpp"
#include "simreel/sim/body_spring.hpp"
#include "simreel/sim/joint.hpp"

namespace simreel::sim::detail {

struct WorldState;

inline constexpr std::uint32_t kNoRigid = std::numeric_limits<std::uint32_t>::max();

/// A shape pair by stable ids (the bodies' packed handles and the shapes' indices in their
/// bodies), plus a sub-index (a mesh triangle + 1; 0 otherwise): what keys a manifold from one
/// step to the next. Ordered, so the cache is a sorted vector (no hashing, deterministic).
struct PairKey {
  std::uint64_t body_a = 0;
  std::uint32_t shape_a = 0;
  std::uint64_t body_b = 0;
  std::uint32_t shape_b = 0;
  std::uint32_t sub = 0;
  auto operator<=>(const PairKey&) const = default;
  bool operator==(const PairKey&) const = default;
};

/// BodyManifold::first_point of a manifold carried over unchanged from the last step because
/// neither side can move (both asleep, or asleep and static): kept for the warm start when the
/// island wakes, with no points in BodyDynamics::points and no solver rows.
inline constexpr std::uint32_t kCarriedManifold = std::numeric_limits<std::uint32_t>::max();

/// One manifold of the step: its key, its points, the rigid indices of its two bodies and where
/// its points start in BodyDynamics::points (or kCarriedManifold).
struct BodyManifold {
  PairKey key;
  Manifold manifold;
  std::uint32_t rigid_a = kStaticBody, rigid_b = kStaticBody;
  std::uint32_t first_point = 0;
};

/// A shape's box for the broad phase (sort and sweep along x).
struct Proxy {
  Vec3 lo, hi;
  std::uint32_t shape;  ///< index into WorldState::shapes
  std::uint32_t body;   ///< index into bodies.dense()
  bool dynamic;
  bool active;  ///< an awake dynamic body, or a kinematic one that moves: it can start a contact
};

/// Sleeping (Box2D's b2_linearSleepTolerance / b2_angularSleepTolerance / b2_timeToSleep, the
/// same idea as Bullet's deactivation): a dynamic body that touches something and is slower
/// than both tolerances accumulates rest time (a free body never sleeps: it keeps its drift); an island of bodies in contact sleeps once every one of them has rested
/// kTimeToSleep. Sleeping bodies are frozen (rigid/body_state.hpp sleep()) and cost nothing: no
/// integration, no narrow phase among themselves, no solver rows. An island wakes whole when an
/// awake dynamic body or a moving kinematic body touches one of its bodies, when a body of it is
/// removed or pushed (World::wake), or when anything it rests on is removed.
inline constexpr double kSleepLinearSpeed = 0.05;                     ///< (m/s)
inline constexpr double kSleepAngularSpeed = 2.0 * 3.14159265358979 / 180.0;  ///< (rad/s)
inline constexpr double kTimeToSleep = 0.5;                           ///< (s)
/// A body speed (m/s) or spin (rad/s) at or above light's is an explosion of the solve, not
/// motion: a step stops the run there (stage_bodies.cpp) and a loaded state is refused
/// (state_snapshot.cpp), long before the values overflow.
inline constexpr double kDivergedSpeed = 299792458.0;

/// A registered joint (World::add_joint; Coutinho Ch. 5): its definition, its geometry in its
/// bodies' frames, the bodies by handle (resolved to rigid entries every step: removals move
/// rigid entries), and what it did over the last step.
struct JointEntry {
  JointDef def;
  JointModel model;
  Handle body_a, body_b;  ///< null: the world
  bool broken = false;
  JointReading reading;   ///< force, torque, broken (geometry is measured on demand)
};

/// A damped spring between bodies (World::add_body_spring; §4.3.3): its definition, anchors in
/// its bodies' rigid frames (world coordinates for the world or a static body) and rest length.
struct BodySpringEntry {
  BodySpringDef def;
  Handle body_a, body_b;  ///< null: the world
  Vec3 local_a = Vec3::Zero(), local_b = Vec3::Zero();
  double rest = 0.0;  ///< (m)
};

struct BodyDynamics {
  RigidBodies rigid;
  ContactSolver solver;
  std::size_t dynamic_count = 0;  ///< 0: the bodies stage does nothing (scenes before Ch. 4)
  std::vector<BodyManifold> manifolds, previous;  ///< this step's, last step's (sorted by key)
  std::vector<ContactPoint> points;
  std::vector<Proxy> proxies;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;  ///< proxy index pairs
  bool allow_sleeping = true;  ///< WorldDef::allow_sleeping
  bool continuous = true;      ///< WorldDef::continuous_collision
  /// Continuous collision (body_ccd.cpp), per rigid entry: the centre of mass and orientation at
  /// the start of the step, and whether the body is fast (its contacts then take the speculative
  /// margin kSpeculativeMargin). Reused from step to step.
  std::vector<Vec3> start_position;
  std::vector<Quat> start_orientation;
  std::vector<std::uint8_t> fast;
  /// Per rigid entry: rest time (s) of a dynamic body, and the island it fell asleep with (the
  /// bodies that wake together).
  std::vector<double> rest_time;
  std::vector<std::uint32_t> island;
  std::vector<std::uint32_t> parent;  ///< union–find scratch over rigid entries, reused
  /// Impulses from particles and cloth on the dynamic bodies over the current step (§3.7),
  /// applied and cleared by the bodies stage.
  BodyImpulses coupling;
  /// apply_coupling's per-body sums, reused from step to step (no allocation once grown).
  std::vector<Vec3> coupling_impulse, coupling_moment;
  std::vector<std::uint8_t> coupling_touched;
  /// Joints of this step (joints.cpp gather_joints): the unbroken joints' models and rigid
  /// entries, their dense indices in WorldState::joints, and the body pairs (dense body indices,
  /// sorted) that must not collide.
  JointSolver joint_solver;
  std::vector<JointModel> joint_models;
  std::vector<JointBodies> joint_bodies;
  std::vector<std::uint32_t> joint_entry;
  /// (N) each joint's force at the end of the last step (|reading.force|): the geometric
  /// stiffness of this step's solve (JointSolver::stiffen_inertia).
  std::vector<double> joint_force_n;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> no_collide;
  std::vector<std::uint8_t> in_contact;  ///< per rigid entry: touched something this step
  /// The rigid entries each body spring joins this step (sleep.cpp treats them as joints do).
  std::vector<JointBodies> spring_bodies;
};

/// Resolves this step's joints (joints.cpp): fills joint_models/joint_bodies/joint_entry from
/// the unbroken joints and no_collide from those that do not let their bodies collide, and
/// spring_bodies from the body springs.
void gather_joints(WorldState& w);

/// After the velocity solve of a step of length h: each joint's force and torque from the
/// solver's impulses; joints whose force exceeded their break_force break.
void finish_joints(WorldState& w, double h);

/// Removes every joint and body spring attached to the body `body` (a body being removed).
void remove_joints_of(WorldState& w, const Handle& body);

/// Adds the body springs' forces to the accumulators of their dynamic bodies (body_springs.cpp;
/// spring_bodies from gather_joints).
void apply_body_springs(WorldState& w);

/// Whether the bodies of dense indices i and j are joined by a joint that keeps them from
/// colliding.
[[nodiscard]] bool no_collide(const BodyDynamics& d, std::uint32_t i, std::uint32_t j);

/// Readies w.dyn.coupling for this step (body_coupling.cpp): which shapes belong to dynamic
/// bodies, an empty log. Called at the start of the particle collisions.
void prepare_coupling(WorldState& w);

/// The log the passes of this step append to, or nullptr when there is no dynamic body.
BodyImpulses* coupling_log(WorldState& w);

/// Adds to the dynamic bodies' force and torque accumulators, for the step [t0, t1]: the
/// impulses logged this step (as the constant force J/h over it: the same change of momentum
/// as an impulse at its start, Coutinho §3.7), and the force fields (body_coupling.cpp). Clears
/// the log.
void apply_coupling(WorldState& w, double t0, double t1);

/// Wakes the island of every sleeping body with an entry in this step's impulse log or a
/// non-zero force from a field over [t0, t1] (Box2D wakes a body a force is applied to).
void wake_coupled(WorldState& w, double t0, double t1);

/// (m) Contact margin of a new pair: pairs closer than this give (speculative) points. Kept
/// small so restitution sees the true impact speed (a speculative point would slow the body
/// first), but above zero: a body set on a surface by computing its pose lies on it only to
/// rounding (separations of +-1e-17 m), and at exactly zero some of its corners were dropped.
inline constexpr double kBodyContactMargin = 1e-6;
/// (m) Contact margin of a pair whose manifold carried load (a normal impulse) in the previous
/// step (a persistent contact; Bullet's contact breaking threshold plays this part). The solver leaves a resting body rocking
/// by a few um (~1e-6 m at 1/60 s from its unconverged first step), and a corner dropped for it
/// let the body fall freely for a step: it met the surface again slipping, and a slipping contact
/// is bounded by the kinetic mu, so a crate that static friction holds on a ramp slid off. A kept
/// point beyond contact is speculative (contact_solver.hpp): it only limits the approach to the
/// gap, so it neither holds the body back nor pulls it.
inline constexpr double kKeptContactMargin = 0.001;

/// (m) Contact margin of a pair with a fast body (BodyDynamics::fast): a body stopped at its
/// time of impact kTimeOfImpactGap short of a surface meets it in the next step's contacts as a
/// speculative point, which stops the approach, or bounces it when the gap would close within the
/// step (contact_solver.hpp).
inline constexpr double kSpeculativeMargin = 0.004;
/// (m) How far short of the surface a swept body is stopped (conservative advancement's target).
inline constexpr double kTimeOfImpactGap = 0.001;

struct Collider;     // collision/collider_impl.hpp
/// The convex of a solid collider (sphere, box, capsule, cylinder) in its shape frame, for GJK
/// (body_contacts.cpp); an empty sphere for planes and meshes.
[[nodiscard]] ConvexShape convex_of(const Collider& c);

struct Triangle;  // collision/bvh.hpp
/// A solid shape (sphere, box, capsule, cylinder, hull) seen from a mesh's frame, for skipping
/// the mesh's triangles that cannot touch it (body_contacts.cpp). A triangle's plane is a
/// candidate separating axis (Ericson 2005, §5.2.1): when the shape's support along the
/// triangle's normal stays farther than the gap from that plane, on either side, so does the
/// shape from the triangle. Both poses are those of the colliders when it is built.
class TrianglePlaneCull {
 public:
  TrianglePlaneCull(const Collider& mesh, const Collider& shape);
  /// True only when the plane of `tri` (mesh frame, unit normal) keeps the shape farther than
  /// gap (m) from the triangle, with a slack of 1e-9 m (plus 1e-9 of the shape's offset from
  /// the mesh origin) above rounding: GJK on the pair (collide()) then reports it apart. False
  /// for a NaN or zero normal.
  [[nodiscard]] bool apart(const Triangle& tri, double gap) const;

 private:
  ConvexShape shape_;  // support mapping, shape frame (a hull's vertices stay the collider's)
  Mat3 to_shape_;      // mesh frame -> shape frame (rotation)
  Vec3 origin_;        // (m) the shape frame's origin, mesh frame
  double slack_;
};

/// Marks BodyDynamics::fast from the velocities at the start of a step of length h and saves the
/// start poses (body_ccd.cpp). Call before find_body_contacts.
void begin_continuous(WorldState& w, double h);

/// Continuous collision after the positions are integrated (body_ccd.cpp): every awake dynamic
/// body not in a joint whose motion over the step (|Δx| + θ r_max, its bounding radius r_max)
/// exceeds half its thinnest shape's inner radius is swept from its start pose to its end pose
/// (centre of mass linear, orientation by slerp) against every shape of every body that is not
/// itself swept (static, kinematic and sleeping ones where they are; awake dynamic ones at their
/// end pose, only when its motion exceeds both bodies' inner radii together; planes; mesh
/// triangles through the mesh's AABB tree). Two swept bodies whose motions together exceed
/// their inner radii together are swept against each other, both moving (the approach bound
/// sums both centres' relative speed and both θ r_max), and each keeps the earlier of that time
/// and its own. The time of impact is found by
/// conservative advancement (Mirtich 1996, "Impulse-based Dynamic Simulation of Rigid Body
/// Systems", §2.3.2) on GJK distances (gjk.hpp): advance by (d - gap) / (approach bound), the
/// bound being the centre's speed towards the other shape plus θ r_max. A pair already
/// touching at the start, or one the body cannot penetrate by more than half its inner radius,
/// is left to the discrete contacts. The body is put back at its earliest time of
/// impact t (a fraction of the step h, s), keeping its velocity, less what the step's forces
/// added over the (1 - t) h it did not move when no contact point touched it in the step (a
/// free fall: speed and height then agree, and a bounce is as high as e² times the drop); the
/// next step's speculative contact stops or bounces it. The
/// book's end-of-step test with bisection (§4.4) cannot see a body that is past a thin wall at
/// the end of the step; this replaces it for fast bodies.
void continuous_collisions(WorldState& w, double h);

/// Broad and narrow phase (body_contacts.cpp): fills d.manifolds (in a fixed order: planes
/// first, then pairs by shape index) and d.points, each point warm-started from d.previous.
void find_body_contacts(WorldState& w);

/// Wakes sleeping islands touched this step by an awake dynamic body or a moving kinematic one
/// (d.manifolds of the last find_body_contacts). Returns whether any body woke: the caller then
/// finds the contacts again, since a sleeping island's own contacts were not computed.
bool wake_touched(WorldState& w);

/// Wakes every body of rigid entry i's island (i may be kStaticBody or awake: nothing happens).
void wake_island(WorldState& w, std::uint32_t i);

/// Wakes every sleeping body (a removal: whatever rested on the removed body must fall).
void wake_all(WorldState& w);

/// A collider added or about to be removed: wakes every particle of each system (and of the
/// systems in its collision group) that has a sleeper within reach of the collider's bounds
/// (1.5 radii + 1 mm; a plane: above it by less, or below), since what held a sleeper may be
/// gone or a new solid may overlap it. The whole system wakes, not just the sleepers near it:
/// the beads of a pile rest on one another, and sleep has no islands to follow.
void wake_particles_near(WorldState& w, const Collider& c);

/// Wakes every particle of the systems marked in `wake` (dense index) and of the systems in
/// their collision groups.
void wake_systems(WorldState& w, std::vector<bool> wake);

/// After the step's solve: rest times from the new velocities, islands from this step's
/// manifolds, and islands that have all rested kTimeToSleep put to sleep.
void update_sleep(WorldState& w, double h);

/// Removes rigid entry i by swap-remove, keeping every Body::rigid index right.
void remove_rigid(WorldState& w, std::uint32_t i);

}  // namespace simreel::sim::detail
