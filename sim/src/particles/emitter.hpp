#pragma once
// Emitters (Coutinho §3.8): release schedule, per-particle draws, the emitting shapes, and the
// per-particle curves over lifetime (size, brightness) (private).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "particles/particle_store.hpp"
#include "simreel/sim/particle_system.hpp"
#include "simreel/sim/random.hpp"

namespace simreel::sim::detail {

struct EmitterState {
  Rng rng;
  std::uint64_t scheduled = 0;  ///< rate births scheduled so far, released or dropped at the cap
  std::vector<std::uint64_t> bursts_fired;  ///< per EmitterDef::bursts entry: bursts released
  std::vector<double> births;               ///< birth times of the current step (scratch)
  std::vector<std::uint64_t> cells;    ///< quad: cells chosen for the current release (scratch)
  std::vector<std::uint64_t> scratch;  ///< quad: permutation or hash table (scratch)
  std::vector<double> local;           ///< quad: (n x 2) start points of the release (scratch)
  std::vector<double> mesh_cdf;        ///< mesh: cumulative triangle areas (m²), built once
};

/// Releases the particles born in (t0, t1] at the end of the system's arrays and returns the
/// index of the first. Rate birth j (from 0) is at start_time + (j + 1) / rate (up to
/// stop_time), so floor(rate * (t - start_time)) have been released by time t, however that time
/// was cut into frames and steps; burst k of a Burst is released in the first step whose end is
/// >= time + k repeat_interval. Births are taken in time order. Each newborn gets
/// age = t1 - birth time (it is advanced by the caller for that long only, so a jet shows no
/// banding), start point and direction from the emitter pose at its birth time, its start point
/// as prev_position (if tracked), and the next id. Births beyond max_particles live particles are
/// dropped (emission pauses, it does not catch up later).
std::size_t emit(const EmitterDef& def, EmitterState& state, ParticleStore& store, double t0,
                 double t1, std::uint64_t& next_id);

/// One triggering parent of a sub-emitter (SubEmitterDef): `count` particles to be born at
/// `position` (m, world) with `velocity` (m/s, the inherited part) added, aged `age` (s) at the
/// end of the step.
struct SubBirth {
  Vec3 position = Vec3::Zero();
  Vec3 velocity = Vec3::Zero();
  double age = 0.0;
  std::size_t count = 0;
};

/// Releases the particles of sub-emitter `births`, in order, at the end of the system's arrays
/// and returns the index of the first: each drawn from `def` like emit()'s newborns, its start
/// point from def's shape in def's rotation placed on the parent's position. Births beyond
/// max_particles live particles are dropped.
std::size_t emit_sub(const EmitterDef& def, EmitterState& state, ParticleStore& store,
                     const std::vector<SubBirth>& births, std::uint64_t& next_id);

/// Size over lifetime: radius = base_radius * f(age / lifetime), f piecewise linear through the
/// keys (end keys held outside them).
class SizeCurve {
 public:
  SizeCurve() = default;
  explicit SizeCurve(const std::vector<SizeKey>& keys);
  [[nodiscard]] bool empty() const { return t_.empty(); }
  [[nodiscard]] float eval(float u) const;
  /// Writes the radius of particles [begin, end) from their base radius, age and lifetime.
  void apply(ParticleStore& s, std::size_t begin, std::size_t end) const;

 private:
  std::vector<float> t_;
  std::vector<float> size_;
};

/// Multiplies the RGB of particles [begin, end) by their brightness factor (colour variation).
void apply_tint(ParticleStore& s, std::size_t begin, std::size_t end);

}  // namespace simreel::sim::detail
