// Stage "particle-particle" (stages.hpp): systems that opted in (collide_particles,
// collision_group) collide with each other's particles (hashed grid §2.3.1, sequential impulses
// §3.6.2); the overlap corrections are swept against the colliders (§3.4).
#include "core/stages.hpp"

namespace simreel::sim::detail {

void stage_particle_particle(WorldState& w, double t0, double t1) {
  const double h = t1 - t0;
  std::vector<ParticleSystemState>& systems = w.systems.dense();
  const std::vector<Collider>& colliders = w.shapes;
  ParticleCollider& pc = w.particle_collider;
  // Groups in order of their first member; a system without a group is its own group.
  std::vector<bool> done(systems.size(), false);
  std::vector<ParticleGroupMember> members;
  for (std::size_t s = 0; s < systems.size(); ++s) {
    if (done[s]) continue;
    const ParticleSystemDef& d = systems[s].def;
    if (!d.collide_particles && d.collision_group.empty()) continue;
    members.clear();
    for (std::size_t u = s; u < systems.size(); ++u) {
      const ParticleSystemDef& du = systems[u].def;
      const bool same = u == s || (!d.collision_group.empty() && du.collision_group == d.collision_group);
      if (!same || done[u]) continue;
      done[u] = true;
      // The warm-start key is the registration serial: it survives other systems' removal.
      members.push_back({&systems[u].store, du.particle_restitution, du.particle_friction,
                         du.collide, std::uint32_t(w.systems.serial(u)), w.sleep_allowed(u),
                         du.gravity.norm()});
    }
    // A lone system without collide_particles has nobody to collide with.
    if (members.size() == 1 && !d.collide_particles) continue;
    pc.threads = w.threads;
    pc.run(members, w.def.contact_speed, h, &colliders);
    // §3.7: the collider contacts' impulses (pn n + pt on the particle) push dynamic bodies back,
    // at the surface point under the particle's centre before the overlap correction. (The
    // contacts, radii, x and x_before are all in the collider's working order.)
    if (BodyImpulses* log = coupling_log(w); log != nullptr && !pc.x_before.empty())
      for (const ParticleCollider::Contact& c : pc.contacts) {
        if (c.i != ParticleCollider::kCollider) continue;
        const Vec3 p = pc.x_before[c.j] - (pc.radius[c.j] - c.depth) * c.n;
        log->add(colliders[c.collider], -(c.pn * c.n + c.pt), p);
      }
    if (colliders.empty() || pc.x_before.empty()) continue;
    // The overlap correction moved particles: sweep those moves against the colliders (§3.4).
    // Each sweep changes its own particle alone, so the working order changes no result.
    for (std::size_t q = 0; q < pc.x.size(); ++q) {
      const Vec3& from = pc.x_before[q];
      if (from == pc.x[q]) continue;
      const auto [mi, i] = pc.member_particle(std::uint32_t(q));
      if (members[mi].collide) constrain_displacement(*members[mi].store, i, from, colliders);
    }
  }
}

}  // namespace simreel::sim::detail
