// Stage "particle collisions" (stages.hpp): the particles integrated this step, as swept spheres
// against the colliders (Coutinho Ch. 2–3; collision/particle_response.cpp), and the splash
// droplets of HitAction::split.
#include "core/stages.hpp"

namespace simreel::sim::detail {

void stage_particle_collisions(WorldState& w, double t0, double t1) {
  prepare_coupling(w);  // the step's impulse log on dynamic bodies (§3.7, body_coupling.cpp)
  for (std::size_t index = 0; index < w.systems.size(); ++index) {
    ParticleSystemState& ps = w.systems.at(index);
    const bool sleep = w.sleep_allowed(index);
    if (ps.def.collide && !w.shapes.empty()) w.collide_system(index, 0, ps.n_old, t1 - t0);
    if (!sleep) continue;
    // Sleeping particles (ParticleStore::rest) stay where they fell asleep, at rest: what the
    // integrator did to them this step is undone (the pass above did not sweep them).
    ParticleStore& st = ps.store;
    for (std::size_t i = 0; i < ps.n_old; ++i) {
      const float* r = &st.rest[4 * i];
      if (!(r[3] >= kSleepTime)) continue;
      for (std::size_t k = 0; k < 3; ++k) {
        st.position[3 * i + k] = r[k];
        st.velocity[3 * i + k] = 0.0f;
      }
    }
  }
}

void WorldState::collide_system(std::size_t index, std::size_t begin, std::size_t end, double h) {
  ParticleSystemState& ps = systems.at(index);
  ParticleStore& st = ps.store;
  CollisionContext ctx;
  ctx.contact_speed = def.contact_speed;
  ctx.rng = &ps.splash_rng;
  ctx.spawns = &ps.spawns;
  ctx.impulses = coupling_log(*this);
  ctx.threads = threads;
  if (ps.def.on_hit) {
    ctx.on_hit = &*ps.def.on_hit;
    ctx.on_hit_split = &ps.def.on_hit_split;
  }
  ctx.sleep = sleep_allowed(index);  // sleeping particles are not swept (put back after)
  ctx.memo = &ps.collide_memo;
  ps.spawns.clear();
  collide(st, begin, end, h, shapes, ctx, ps.forces);
  ps.removed_inside += ctx.removed_inside;
  // Splash droplets (HitAction::split) join the system now, at age 0: they move from the next
  // step on. Droplets past max_particles are dropped.
  for (const SpawnRequest& q : ps.spawns) {
    if (st.count >= ps.def.emitter.max_particles) break;
    const std::size_t i = st.append(1);
    for (int k = 0; k < 3; ++k) {
      st.position[3 * i + std::size_t(k)] = float(q.position[k]);
      if (st.track_prev) st.prev_position[3 * i + std::size_t(k)] = float(q.position[k]);
      st.velocity[3 * i + std::size_t(k)] = float(q.velocity[k]);
    }
    st.mass[i] = float(q.mass);
    st.radius[i] = float(q.radius);
    st.base_radius[i] = float(q.radius);
    st.lifetime[i] = float(q.lifetime);
    st.age[i] = 0.0f;
    st.id[i] = ps.next_id++;
    ps.gradient.apply(st, i, i + 1);
  }
}

}  // namespace simreel::sim::detail
