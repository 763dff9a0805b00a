#pragma once
/// @file particle_system.hpp
/// Particle systems (Coutinho §3.1–3.3, §3.8): definitions and the read-only view the program
/// hands to the renderer and the exporter.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "simreel/sim/keyframes.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim {

/// ODE integrators (Coutinho Appendix B).
enum class Integrator {
  semi_implicit_euler,  ///< v += a h; x += v h (symplectic, first order; the default). Drag is
                        ///< taken at the new velocity, v = (v + g h) / (1 + h k_d / m), so it is
                        ///< stable for any drag and mass
  rk4,                  ///< classical fourth-order Runge–Kutta on (x, v); a particle with
                        ///< h k_d / m > 0.5 takes ceil(2 h k_d / m) sub-steps (explicit RK4
                        ///< diverges past 2.78)
};

enum class EmitterShape {
  disk,  ///< disk of `disk_radius` around the emitter origin, normal = emitter +z axis
  quad,  ///< rectangle `quad_size` (x by y, local axes), laid out as a grid (§3.8, eq. 3.100)
};

/// One key of a color-over-lifetime gradient; `t` is normalised age (age / lifetime) in [0, 1].
struct ColorKey {
  double t = 0.0;
  std::array<float, 4> rgba{1.f, 1.f, 1.f, 1.f};  ///< linear RGBA in [0, 1]
};

/// Emitter definition (Coutinho §3.8): where and how particles are released. Every per-particle
/// parameter is a Distribution drawn from N(mean, deviation²) per released particle, in a fixed
/// order from the emitter's own Rng(WorldDef::seed, system index), then clamped to [min, max].
///
/// Schedule: particle j (from 0) is born at start_time + (j + 1) / rate while that is <= stop_time,
/// so floor(rate * (t - start_time)) have been born by time t whatever the fps and step. A particle
/// born inside an internal step moves only for the rest of that step and starts with that age
/// (a fast jet shows no bands at the step rate). Births while max_particles are alive are dropped.
/// Disk start points are uniform over the disk's area. Quad releases (the particles born in one
/// internal step) are laid out on a grid of cells of side 2 d_max (eq. 3.100; d_max the largest
/// diameter in the release), or d_max if that is too coarse, one random cell per particle and a
/// random offset inside it, so a release does not overlap while the quad has room.
struct EmitterDef {
  EmitterShape shape = EmitterShape::disk;
  double disk_radius = 0.05;               ///< (m), shape == disk
  std::array<double, 2> quad_size{0.2, 0.2};  ///< (m) along local x and y, shape == quad
  Transform transform;                     ///< emitter frame; particles leave along its +z axis
  KeyframePath path;                       ///< if not empty, overrides `transform` over time
  double rate = 100.0;                     ///< particles per second (>= 0, fractional rates
                                           ///< accumulate across steps)
  double start_time = 0.0;                 ///< (s) emission starts
  double stop_time = 1e300;                ///< (s) emission stops
  Distribution lifetime{2.0, 0.0, 0.0};    ///< (s), clamped >= 0
  Distribution start_speed{1.0, 0.0, 0.0}; ///< (m/s) along the emission direction
  Distribution spread_deg{0.0, 0.0, 0.0, 180.0};  ///< polar angle from the emitter +z axis
                                           ///< (degrees); azimuth uniform in [0, 360). A
                                           ///< negative draw is folded (-a at azimuth p is a at
                                           ///< p + 180), then clamped to [min, max] and [0, 180]
  Distribution mass{1e-3, 0.0, 1e-12};     ///< (kg), clamped > 0 (at least 1e-12); mean > 0
  Distribution radius{0.01, 0.0, 1e-6};    ///< (m), clamped > 0 (at least 1e-6); mean > 0
  /// Gradient over normalised age (keys sorted by t; one key = constant colour). Default: one
  /// white key. (Sized, not brace-initialised: GCC 12 warns -Wmaybe-uninitialized on an
  /// initializer_list in a default member initialiser.)
  std::vector<ColorKey> color_over_lifetime = std::vector<ColorKey>(1);
  std::size_t max_particles = 100000;      ///< emission pauses while this many are alive
};

/// A particle system: its emitter, forces and integrator.
struct ParticleSystemDef {
  std::string name = "particles";  ///< used in exports (column `system`)
  EmitterDef emitter;
  Vec3 gravity{0.0, 0.0, -9.81};   ///< (m/s²) gravitational acceleration, world frame
  double drag = 0.0;               ///< viscous drag coefficient k_d (kg/s): F = -k_d v (§3.3.2)
  Integrator integrator = Integrator::semi_implicit_euler;
  bool collide = true;             ///< collide with the world's colliders
  // Particle–particle collisions (Coutinho §2.3.1 grid, §3.6.1–3.6.2 impulses).
  bool collide_particles = false;  ///< particles of this system collide with each other
  /// Systems sharing a non-empty group collide with each other's particles (and internally).
  std::string collision_group;
  double particle_restitution = 0.5;  ///< e in [0, 1] between particles (pair: the mean)
  double particle_friction = 0.1;     ///< Coulomb mu >= 0 between particles (pair: the mean)
};

/// Read-only view of a particle system's live particles, valid until the next World::advance().
/// Arrays are structure-of-arrays of length `count`; xyz arrays are (count x 3) interleaved.
struct ParticleView {
  std::size_t count = 0;
  const float* position = nullptr;     ///< (count x 3) centre, world frame (m)
  const float* velocity = nullptr;     ///< (count x 3) world frame (m/s)
  const float* color = nullptr;        ///< (count x 4) linear RGBA in [0, 1], from color over lifetime
  const float* radius = nullptr;       ///< (count) (m)
  const float* age = nullptr;          ///< (count) (s)
  const float* lifetime = nullptr;     ///< (count) (s)
  const std::uint64_t* id = nullptr;   ///< (count) stable id, unique within the system, in
                                       ///< emission order; survivors keep their relative order
};

}  // namespace simreel::sim
