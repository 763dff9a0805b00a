#pragma once
// The step as a table of named stages (Coutinho §1.3: move -> check collisions -> respond ->
// report). World::advance() runs every stage in this order for each internal step [t0, t1]; the
// report of moved (and removed) objects is built once per advance(), after its steps.
//
// Order. The order is kinematic poses -> particle forces and integration -> particle
// collisions -> particle-particle -> cloth -> bodies -> births and deaths -> report. Byte
// identity with the engine before the stage table wins over it: births (split children, emitter
// newborns with their partial step and collisions, splash droplets) come right after the
// particle collisions, so newborns take part in particle-particle collisions and in the cloth's
// particle contacts of the same step, as they always have. Until particle-particle, systems are
// independent of each other, so running each stage over all systems before the next stage gives
// the same result as the old per-system sequence.

#include "core/world_state.hpp"

namespace simreel::sim::detail {

using StageFn = void (*)(WorldState& w, double t0, double t1);

struct Stage {
  const char* name;
  StageFn run;
};

/// Kinematic colliders move to their end-of-step pose (particles collide with them there, §3.4).
void stage_kinematic_poses(WorldState& w, double t0, double t1);
/// Every system's particles alive at t0 are integrated over [t0, t1] (forces §3.3, App. B).
void stage_particle_integration(WorldState& w, double t0, double t1);
/// Those particles are collided as swept spheres with the colliders (§3.4–3.6); sleeping ones
/// (ParticleStore::rest) are put back where they sleep instead.
void stage_particle_collisions(WorldState& w, double t0, double t1);
/// Splits (§3.9.1), removal of the dead, emission of the step's newborns (each moved and
/// collided for its own age), colours and sizes over lifetime.
void stage_births_and_deaths(WorldState& w, double t0, double t1);
/// Particle-particle collisions of the opted-in systems (hashed grid §2.3.1, §3.6.2).
void stage_particle_particle(WorldState& w, double t0, double t1);
/// Cloth step (§3.9.2), then particles against cloth.
void stage_cloth(WorldState& w, double t0, double t1);
/// Dynamic bodies (the rigid-body issue): empty until dynamic bodies exist.
void stage_bodies(WorldState& w, double t0, double t1);

inline constexpr Stage kStages[] = {
    {"kinematic poses", &stage_kinematic_poses},
    {"particle forces and integration", &stage_particle_integration},
    {"particle collisions", &stage_particle_collisions},
    {"births and deaths", &stage_births_and_deaths},  // before particle-particle: see above
    {"particle-particle", &stage_particle_particle},
    {"cloth", &stage_cloth},
    {"bodies", &stage_bodies},
};

}  // namespace simreel::sim::detail
