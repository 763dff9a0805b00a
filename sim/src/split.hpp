#pragma once
// Particle split (Coutinho §3.9.1) (private). The rules are documented on SplitDef.

#include <cstddef>
#include <cstdint>

#include "particle_store.hpp"
#include "simreel/sim/particle_system.hpp"
#include "simreel/sim/random.hpp"

namespace simreel::sim::detail {

/// Splits the live particles among [0, end) whose split condition is met at the end of this
/// internal step: each appends `children` children at the end of the store (ids from next_id, in
/// parent order) and dies (its lifetime is set to 0; the caller's compaction removes it).
/// Children of a parent are skipped, and the parent waits, while they would not fit under
/// max_particles. Returns the number of children created.
std::size_t split_particles(const EmitterDef& def, Rng& rng, ParticleStore& s, std::size_t end,
                            std::uint64_t& next_id);

}  // namespace simreel::sim::detail
