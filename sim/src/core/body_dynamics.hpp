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
#include "rigid/body_state.hpp"
#include "rigid/contact_solver.hpp"

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

/// One manifold of the step: its key, its points, the rigid indices of its two bodies and where
/// its points start in BodyDynamics::points.
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
};

struct BodyDynamics {
  RigidBodies rigid;
  ContactSolver solver;
  std::size_t dynamic_count = 0;  ///< 0: the bodies stage does nothing (scenes before Ch. 4)
  std::vector<BodyManifold> manifolds, previous;  ///< this step's, last step's (sorted by key)
  std::vector<ContactPoint> points;
  std::vector<Proxy> proxies;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;  ///< proxy index pairs
  /// Impulses from particles and cloth on the dynamic bodies over the current step (§3.7),
  /// applied and cleared by the bodies stage.
  BodyImpulses coupling;
};

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

/// (m) Contact margin: pairs closer than this give (speculative) points. Kept at zero-ish so
/// restitution sees the true impact speed (a speculative point would slow the body first).
inline constexpr double kBodyContactMargin = 0.0;

/// Broad and narrow phase (body_contacts.cpp): fills d.manifolds (in a fixed order: planes
/// first, then pairs by shape index) and d.points, each point warm-started from d.previous.
void find_body_contacts(WorldState& w);

/// Removes rigid entry i by swap-remove, keeping every Body::rigid index right.
void remove_rigid(WorldState& w, std::uint32_t i);

}  // namespace simreel::sim::detail
