// World::remove for every kind of object: swap-remove from the slot table (the handle and every
// copy of it go stale at once), drop what refers to the object, and queue the removal for the
// next advance()'s moved list.
#include <algorithm>

#include "core/world_impl.hpp"

namespace simreel::sim {

void World::remove(BodyHandle h) {
  detail::remove_body(*impl_, h.id);  // with all its shapes; reported once
  impl_->removed.push_back(h.id);
}

void World::remove(ParticleSystemHandle h) {
  detail::WorldState& w = *impl_;
  const std::size_t i = w.systems.index(h.id);
  const std::uint64_t serial = w.systems.serial(i);
  // Its attractor springs go with it (their handles go stale; they are not reported).
  for (std::size_t a = w.attractors.size(); a-- > 0;)
    if (w.attractors.at(a)->system == h) w.attractors.remove(w.attractors.handle(a));
  // Fields that named it forget it; a field left with no system acts on none (FieldEntry).
  for (detail::FieldEntry& f : w.fields.dense()) {
    auto& list = f.state->def.systems;
    list.erase(std::remove(list.begin(), list.end(), h), list.end());
  }
  w.particle_collider.forget_system(std::uint32_t(serial));
  w.systems.remove(h.id);
  w.removed.push_back(h.id);
}

void World::remove(ClothHandle h) {
  impl_->cloths.remove(h.id);
  impl_->removed.push_back(h.id);
}

void World::remove(ForceFieldHandle h) {
  detail::WorldState& w = *impl_;
  const detail::FieldState* f = w.fields[h.id].state.get();
  for (detail::ParticleSystemState& ps : w.systems.dense()) {
    auto& list = ps.dynamics.fields;
    list.erase(std::remove(list.begin(), list.end(), f), list.end());  // keeps the order
  }
  w.fields.remove(h.id);
  w.removed.push_back(h.id);
}

void World::remove(AttractorSpringHandle h) {
  detail::WorldState& w = *impl_;
  const AttractorSpringDef* a = w.attractors[h.id].get();
  auto& list = w.systems[a->system.id].attractors;
  list.erase(std::remove(list.begin(), list.end(), a), list.end());  // keeps the order
  w.attractors.remove(h.id);
  w.removed.push_back(h.id);
}

}  // namespace simreel::sim
