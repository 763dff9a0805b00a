#pragma once
// Particle split (Coutinho §3.9.1) (private). The rules are documented on SplitDef.

#include <cstddef>
#include <cstdint>

#include "particles/particle_store.hpp"
#include "simreel/sim/particle_system.hpp"
#include "simreel/sim/random.hpp"

namespace simreel::sim::detail {

/// Splits the live particles among [0, end) whose split condition is met at the end of this
/// internal step: each appends `children` children at the end of the store (ids from next_id, in
/// parent order) and lives on. Children are not considered in the step that creates them. A
/// parent waits while its children would not fit under max_particles. Returns the number of
/// children created.
std::size_t split_particles(const EmitterDef& def, Rng& rng, ParticleStore& s, std::size_t end,
                            std::uint64_t& next_id);

}  // namespace simreel::sim::detail
