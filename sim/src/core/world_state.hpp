#pragma once
// The world's state (private to core/): the slot tables of every kind of object, time and step
// count, and the scratch of the passes that involve several objects. World::Impl is this struct;
// the stage functions (stages.hpp) take it by reference.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "cloth/cloth_particles.hpp"
#include "cloth/cloth_self.hpp"
#include "collision/collide_memo.hpp"
#include "collision/collider_impl.hpp"
#include "collision/particle_collisions.hpp"
#include "core/body_dynamics.hpp"
#include "core/body_state.hpp"
#include "core/slot_table.hpp"
#include "particles/emitter.hpp"
#include "particles/forces.hpp"
#include "particles/integrators.hpp"
#include "particles/particle_store.hpp"
#include "simreel/sim/cloth.hpp"
#include "simreel/sim/moved_object.hpp"
#include "simreel/sim/particle_system.hpp"
#include "simreel/sim/world_def.hpp"

namespace simreel::sim::detail {

/// One particle system's model (definition) and state (particles, emitter).
struct ParticleSystemState {
  ParticleSystemDef def;
  ParticleStore store;
  EmitterState emitter;
  ColorGradient gradient;
  SizeCurve size_curve;  ///< size over lifetime (emitter.hpp)
  Rng split_rng;         ///< particle split draws (split.hpp), a stream apart from the emitter's
  ForceParams forces{};
  std::uint64_t next_id = 0;
  // Forces beyond gravity + drag and the general integrators (forces.hpp, integrators.hpp).
  std::vector<SpringDef> springs;  ///< by particle id, rest lengths resolved
  /// Attractor springs pulling this system, in registration order (the order their forces are
  /// summed in; owned by WorldState::attractors).
  std::vector<const AttractorSpringDef*> attractors;
  Rng charge_rng;
  IntegratorState integrator_state;
  IntegratorWorkspace workspace;
  Dynamics dynamics;
  // Collisions (issue 5): splash droplets, §3.4.2 removals.
  Rng splash_rng;
  std::vector<SpawnRequest> spawns;
  CollideMemo collide_memo;  ///< the pass's reuse of unchanged responses (a cache, not state)
  // Sub-emitters (SubEmitterDef): this system's, and the births other systems' (or its own)
  // deaths handed to it in the current step (stage_births.cpp).
  std::vector<SubEmitterDef> sub_emitters;
  std::vector<SubBirth> sub_births;
  std::uint64_t removed_inside = 0;
  // Handed from one stage of the current step to the next (stages.hpp).
  std::size_t n_old = 0;  ///< particles alive at t0 (integrated by the integration stage)
  bool general = false;   ///< integrated by the general path (forces.hpp Dynamics)
};

/// A force field and whether it acts on every system (an empty system list at registration; it
/// stays so for systems registered later). A field whose listed systems were all removed acts on
/// none.
struct FieldEntry {
  std::unique_ptr<FieldState> state;
  bool all_systems = false;
};

struct WorldState {
  WorldDef def;
  double time = 0.0;        ///< (s)
  std::uint64_t steps = 0;  ///< internal steps taken
  int threads = 1;
  SlotTable<Body> bodies{ObjectKind::body, "body/collider"};
  /// Every body's shapes, posed in the world, grouped per body in the order of bodies.dense()
  /// (Body::first_shape): what the collision passes loop over.
  std::vector<Collider> shapes;
  SlotTable<ParticleSystemState> systems{ObjectKind::particle_system, "particle-system"};
  SlotTable<FieldEntry> fields{ObjectKind::force_field, "force-field"};
  SlotTable<std::unique_ptr<AttractorSpringDef>> attractors{ObjectKind::attractor_spring,
                                                             "attractor-spring"};
  SlotTable<Cloth> cloths{ObjectKind::cloth, "cloth"};
  SlotTable<JointEntry> joints{ObjectKind::joint, "joint"};
  SlotTable<BodySpringEntry> body_springs{ObjectKind::body_spring, "body spring"};
  std::vector<MovedObject> moved;
  std::vector<Handle> removed;  ///< removals since the last advance(), reported by the next
  ParticleCollider particle_collider;
  ClothParticleScratch cloth_scratch;  ///< particles against cloth (issue 6)
  ContactScratch cloth_contact_scratch;  ///< self and cloth–cloth contacts (issue 16)
  BodyDynamics dyn;  ///< dynamic bodies (Ch. 4): rigid state, solver, manifolds

  /// Is system i integrated by the general path (integrators.hpp) rather than the fast one?
  [[nodiscard]] bool general(std::size_t i) const;
  /// May system i's particles sleep (ParticleStore::rest)? Only under gravity and drag alone
  /// (the fast path), among colliders that never move, without cloth or dynamic bodies, which
  /// could push a sleeping particle without waking it.
  [[nodiscard]] bool sleep_allowed(std::size_t i) const;
  /// Resolves system i's springs and attractor springs to indices for this step.
  void build_dynamics(std::size_t i, bool interactions);
  /// Colliders of system i over particles [begin, end), then its splash droplets; h (s).
  void collide_system(std::size_t i, std::size_t begin, std::size_t end, double h);
  /// Throws NonFiniteState naming system i, the first bad particle in [begin, end), step, time.
  [[noreturn]] void non_finite(std::size_t i, std::size_t begin, std::size_t end,
                               double t1) const;
};

/// Removes a body and its shapes (bodies.cpp); the shapes keep the bodies' dense order and the
/// warm-start data follows them. @throws std::out_of_range on a null or stale handle.
void remove_body(WorldState& w, const Handle& h);

}  // namespace simreel::sim::detail
