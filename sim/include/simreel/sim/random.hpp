#pragma once
/// @file random.hpp
/// The project's own random generator and normal distribution, so the same seed gives the same
/// particles with any standard library (std::normal_distribution differs between them).

#include <cstdint>

namespace simreel::sim {

/// xoshiro256** (Blackman & Vigna 2018), seeded through splitmix64. Not thread-safe: one
/// generator per emitter, derived from the scene seed and the emitter's index.
class Rng {
 public:
  /// @param seed any 64-bit value; @param stream distinguishes generators sharing a seed
  ///        (e.g. the emitter index), so emitters do not draw correlated sequences.
  explicit Rng(std::uint64_t seed = 0, std::uint64_t stream = 0);

  std::uint64_t next_u64();
  /// Uniform in [0, 1) with 53 random bits.
  double uniform();
  /// Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Standard normal N(0, 1) by the Box–Muller transform (both values used: the second is
  /// cached), computed with std::log/std::sqrt/std::cos/std::sin only.
  double normal();
  /// N(mean, deviation²). A deviation of 0 returns mean exactly without drawing.
  double normal(double mean, double deviation) {
    return deviation == 0.0 ? mean : mean + deviation * normal();
  }

 /// The generator's complete state, for World::state_hash() and snapshots.
  struct State {
    std::uint64_t s[4];
    double cached;
    bool has_cached;
  };
  [[nodiscard]] State state() const { return {{s_[0], s_[1], s_[2], s_[3]}, cached_, has_cached_}; }
  /// Restores a state taken by state() (a cache resumed, World::load_state): the generator then
  /// draws exactly what the one it was taken from would have drawn next.
  void set_state(const State& st) {
    for (int k = 0; k < 4; ++k) s_[k] = st.s[k];
    cached_ = st.cached;
    has_cached_ = st.has_cached;
  }

 private:
  std::uint64_t s_[4];
  double cached_ = 0.0;
  bool has_cached_ = false;
};

}  // namespace simreel::sim
