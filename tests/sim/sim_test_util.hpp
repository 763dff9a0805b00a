#pragma once
// Helpers shared by the sim tests: single-particle worlds and view accessors.

#include <cstddef>

#include "simreel/sim/world.hpp"

namespace simreel::sim::test {

/// A system that never emits on its own (rate 0): particles come from World::spawn_particle.
inline ParticleSystemDef spawn_only_system(const char* name = "probe") {
  ParticleSystemDef def;
  def.name = name;
  def.emitter.rate = 0.0;
  def.emitter.max_particles = 1000;
  return def;
}

inline Vec3 position_of(const ParticleView& v, std::size_t i) {
  return {v.position[3 * i], v.position[3 * i + 1], v.position[3 * i + 2]};
}
inline Vec3 velocity_of(const ParticleView& v, std::size_t i) {
  return {v.velocity[3 * i], v.velocity[3 * i + 1], v.velocity[3 * i + 2]};
}

}  // namespace simreel::sim::test
