#pragma once
// Emitters (Coutinho §3.8): release schedule, per-particle draws and the quad grid layout
// (private).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "particle_store.hpp"
#include "simreel/sim/particle_system.hpp"
#include "simreel/sim/random.hpp"

namespace simreel::sim::detail {

struct EmitterState {
  Rng rng;
  std::uint64_t scheduled = 0;  ///< births scheduled so far, released or dropped at the cap
  std::vector<std::uint64_t> cells;    ///< quad: cells chosen for the current release (scratch)
  std::vector<std::uint64_t> scratch;  ///< quad: permutation or hash table (scratch)
  std::vector<double> local;           ///< quad: (n x 2) start points of the release (scratch)
};

/// Releases the particles born in (t0, t1] at the end of the system's arrays and returns the
/// index of the first. Particle j (from 0) of the emitter is born at start_time + (j + 1) / rate
/// (up to stop_time), so floor(rate * (t - start_time)) have been released by time t, however
/// that time was cut into frames and steps. Each
/// newborn gets age = t1 - birth time (it is advanced by the caller for that long only, so a jet
/// shows no banding), its start point as prev_position (if tracked), and the next id. Births beyond
/// max_particles live particles are dropped (emission pauses, it does not catch up later).
std::size_t emit(const EmitterDef& def, EmitterState& state, ParticleStore& store, double t0,
                 double t1, std::uint64_t& next_id);

}  // namespace simreel::sim::detail
