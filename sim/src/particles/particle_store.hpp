#pragma once
// Structure-of-arrays particle storage and the per-step kernels over it (private).
// Coutinho §3.1–3.3: point masses under gravity and viscous drag; Appendix B: integrators.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "simreel/sim/particle_system.hpp"

namespace simreel::sim::detail {

/// Live particles of one system. Every array holds exactly `count` particles (xyz arrays
/// 3 * count floats, color 4 * count); capacity for `max_particles` is reserved at creation so
/// neither emission nor compaction allocates, and the view's pointers move only on reserve().
struct ParticleStore {
  std::size_t count = 0;
  std::vector<float> position;       ///< (count x 3) world frame (m)
  std::vector<float> velocity;       ///< (count x 3) world frame (m/s)
  std::vector<float> prev_position;  ///< (count x 3) position at the start of the current step,
                                     ///< kept only when `track_prev` (see there)
  std::vector<float> color;          ///< (count x 4) linear RGBA
  std::vector<float> radius;         ///< (count) (m)
  std::vector<float> mass;           ///< (count) (kg)
  std::vector<float> age;            ///< (count) (s)
  std::vector<float> lifetime;       ///< (count) (s)
  std::vector<std::uint64_t> id;     ///< (count) emission order
  std::vector<float> charge;         ///< (count) (C), kept only when `has_charge`
  /// The swept collision test needs each particle's start-of-step position. Semi-implicit Euler
  /// moves in a straight line at the new velocity (x1 = x0 + dt v1), so x0 is recovered from the
  /// end state for free; RK4's chord is not dt v1, so RK4 systems that collide store it.
  bool track_prev = false;
  bool has_charge = false;  ///< the system has a charge distribution other than 0
  // Emitter and split state (emitter.cpp, split.cpp).
  std::vector<float> base_radius;             ///< (count) radius as drawn (m), before size over
                                              ///< lifetime
  std::vector<float> tint;                    ///< (count) brightness factor on the gradient RGB
  std::vector<std::uint8_t> split_generation; ///< (count) splits in the lineage (0 = emitted)
  std::vector<std::uint32_t> split_countdown; ///< (count) steps left before a child splits
  std::vector<std::uint8_t> from_split;       ///< (count) 1: created by a split (§3.9.1), 0:
                                              ///< emitted or spawned (sub-emitter filter)

  void reserve(std::size_t capacity);
  /// Appends n zero-initialised particles; returns the index of the first.
  std::size_t append(std::size_t n);
  /// Removes particles with age >= lifetime from index `first` on, keeping the survivors' order
  /// (so exports sorted by id stay sorted). Moves contiguous runs with memmove.
  void compact(std::size_t first = 0);
  [[nodiscard]] ParticleView view() const;
};

/// Gravity + viscous and quadratic drag parameters of a system (§3.3.1–3.3.2):
/// a = g - (k_d + c_2 |v|) v / m.
struct ForceParams {
  float gravity[3];
  float drag;  ///< k_d (kg/s)
  float drag_quadratic = 0.0f;  ///< c_2 (kg/m): F = -c_2 |v| v
  /// Divergence bounds (WorldDef): a velocity component beyond max_speed (m/s) or a coordinate
  /// beyond max_distance (m), like NaN and inf, makes the integrators report a bad state.
  float max_speed = 1e4f;
  float max_distance = 1e6f;
};

/// The fast path for gravity + drag only (semi_implicit_euler or rk4): advances particles
/// [begin, end) by h, adds h to their ages, and (when s.track_prev) saves the start-of-step
/// positions for the swept collision test, split statically over `threads` when the range is
/// large. Returns true if any resulting position or velocity is not finite.
bool integrate(ParticleStore& s, std::size_t begin, std::size_t end, double h,
               const ForceParams& f, Integrator integrator, int threads = 1);

/// Advances one particle by its own dt (a newborn released part-way through a step).
/// The age is not changed. Returns true if the result is not finite.
bool integrate_one(ParticleStore& s, std::size_t i, double dt, const ForceParams& f,
                   Integrator integrator);

/// Colour-over-lifetime gradient, piecewise linear in normalised age (one key = constant).
class ColorGradient {
 public:
  ColorGradient() = default;
  explicit ColorGradient(const std::vector<ColorKey>& keys);
  [[nodiscard]] bool constant() const { return t_.size() <= 1; }
  /// rgba at normalised age u (clamped to the first/last key outside their range).
  void eval(float u, float* rgba) const;
  /// Writes the colour of particles [begin, end) from their age / lifetime.
  void apply(ParticleStore& s, std::size_t begin, std::size_t end) const;

 private:
  std::vector<float> t_;     ///< key positions, non-decreasing
  std::vector<float> rgba_;  ///< (keys x 4)
};

}  // namespace simreel::sim::detail
