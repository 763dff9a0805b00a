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
  semi_implicit_euler,  ///< v += a h; x += v h (symplectic, first order; the default)
  rk4,                  ///< classical fourth-order Runge–Kutta on (x, v)
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
/// parameter is a Distribution drawn from N(mean, deviation²) per released particle.
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
                                           ///< (degrees); azimuth uniform in [0, 360)
  Distribution mass{1e-3, 0.0, 1e-12};     ///< (kg), clamped > 0
  Distribution radius{0.01, 0.0, 1e-6};    ///< (m), clamped > 0
  std::vector<ColorKey> color_over_lifetime{ColorKey{0.0, {1.f, 1.f, 1.f, 1.f}}};
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
