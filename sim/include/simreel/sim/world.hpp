#pragma once
/// @file world.hpp
/// The World: registers objects, advances by a caller-given sampling time in internal steps,
/// and reports what moved (Coutinho §1.4.1, the interface with the rendering engine).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "simreel/sim/collider.hpp"
#include "simreel/sim/handle.hpp"
#include "simreel/sim/particle_system.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim {

struct WorldDef {
  double max_step = 1.0 / 240.0;  ///< (s) largest internal step; advance() splits each sampling
                                  ///< time into ceil(T / max_step) equal steps
  std::uint64_t seed = 0;         ///< scene seed; emitter i draws from Rng(seed, i)
  double contact_speed = 0.05;    ///< (m/s) normal speed under which a collision becomes a
                                  ///< resting contact (§3.6.3)
};

/// One entry of the moved list: the object's pose at the end of advance().
struct MovedObject {
  Handle handle;
  Vec3 translation = Vec3::Zero();      ///< (m), world frame
  Mat3 rotation = Mat3::Identity();     ///< local-to-world rotation
};

/// Thrown when the state stops being finite: names the object, step and time.
class NonFiniteState : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class World {
 public:
  /// @throws std::invalid_argument if max_step <= 0 or not finite.
  explicit World(const WorldDef& def = {});
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;

  /// Registers colliders and particle systems. @throws std::invalid_argument on an invalid
  /// definition (non-positive size, zero normal, restitution outside [0, 1], ...).
  ColliderHandle add_plane(const PlaneDef& def);
  ColliderHandle add_box(const BoxDef& def);
  ParticleSystemHandle add_particle_system(const ParticleSystemDef& def);

  /// Advances the simulation by `sampling_time` (s, > 0) in internal steps of at most
  /// WorldDef::max_step. Returns the objects whose pose changed since the last call (kinematic
  /// colliders), in registration order. The reference stays valid until the next call.
  /// @throws NonFiniteState if a particle's state becomes NaN/inf.
  const std::vector<MovedObject>& advance(double sampling_time);

  /// Current pose of a collider (for the initial render list). @throws std::out_of_range if stale.
  [[nodiscard]] MovedObject pose(ColliderHandle h) const;
  /// Live particles of a system. @throws std::out_of_range if the handle is stale.
  [[nodiscard]] ParticleView particles(ParticleSystemHandle h) const;
  [[nodiscard]] const ParticleSystemDef& definition(ParticleSystemHandle h) const;

  [[nodiscard]] double time() const;                ///< (s) simulated time
  [[nodiscard]] std::uint64_t step_count() const;   ///< internal steps taken
  /// Particles ever emitted by the system (for rate tests and statistics).
  [[nodiscard]] std::uint64_t emitted_count(ParticleSystemHandle h) const;
  [[nodiscard]] std::vector<ParticleSystemHandle> particle_systems() const;
  [[nodiscard]] std::vector<ColliderHandle> colliders() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace simreel::sim
