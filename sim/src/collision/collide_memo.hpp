#pragma once
// Exact reuse of a particle's collision response from one step to the next (private to
// collision/). The response of the collision pass to one particle (resolve() in
// particle_response.cpp: Coutinho §3.4 swept sphere, §3.6.1 impulse, §3.6.3 resting contact) is a
// pure function of the particle's integrated end state (position, velocity, as the floats
// stored), its radius and mass, its step dt, and of the pass's environment: the colliders (shape,
// pose at both ends of the step, velocities, material), the system's gravity and drag, the step
// h, the contact-speed threshold and the system's hit action. A particle lying still on a static
// surface is at a fixed point of the step: it is integrated to the same floats every step and
// put back to the same floats (in the rain benchmark, 92 % of 100k drops after 1.5 s on a
// 100k-triangle terrain, each otherwise re-swept against the mesh every step). The pass keeps
// the (input -> output) of each particle it leaves at rest and, when the particle's next input and
// the environment are the same bits as then, writes the output instead of sweeping again: the
// same floats by construction, at any thread count (each particle's entry is its own).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "collision/collider_impl.hpp"

namespace simreel::sim::detail {

/// The pass environment a ParticleStore's memo entries (ParticleStore::memo) were recorded in,
/// and the epoch that names it. One per particle system.
class CollideMemo {
 public:
  /// Floats per particle in ParticleStore::memo: the key (position xyz, velocity xyz, radius,
  /// mass as integrated) then the value (position xyz, velocity xyz after the pass).
  static constexpr std::size_t kKey = 8, kValue = 6, kStride = kKey + kValue;
  static_assert(kStride == kMemoStride);

  /// Starts a pass over `s` (turning its memo columns on at the first call): compares the
  /// environment with the one the entries were recorded in, bit for bit, and when anything
  /// differs records the new one under a new epoch (which makes every entry stale). Returns the
  /// epoch a valid entry carries (never 0, the mark of an entry never recorded). The copies of
  /// the colliders hold their meshes and hulls, so no other shape can take their addresses.
  std::uint32_t begin_pass(ParticleStore& s, const std::vector<Collider>& colliders,
                           const ForceParams& f, double h, double contact_speed,
                           const HitAction* on_hit, const SplitOnHit* on_hit_split);

  /// Responses reused in the last pass (for tests and benchmarks; 0 when the pass had none).
  std::size_t reused = 0;

 private:
  bool have_env_ = false;
  std::uint32_t epoch_ = 0;
  std::vector<Collider> colliders_;
  ForceParams forces_{};
  double h_ = 0.0, contact_speed_ = 0.0;
  bool has_on_hit_ = false;
  HitAction on_hit_ = HitAction::bounce;
  SplitOnHit on_hit_split_;
};

}  // namespace simreel::sim::detail
