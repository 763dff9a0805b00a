#pragma once
/// @file forces.hpp
/// Forces beyond gravity and viscous drag (Coutinho §3.3): damped springs between particles,
/// force fields confined to a region with a drop-off, gravitational/Coulomb pair forces with a
/// cut-off, an animated zero-rest-length attractor spring, and (beyond the book) curl-noise
/// turbulence (Bridson, Hourihan & Nordenstam 2007, "Curl-noise for procedural fluid flow").

#include <cstddef>
#include <cstdint>
#include <vector>

#include "simreel/sim/handle.hpp"
#include "simreel/sim/keyframes.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim {

/// A particle given explicitly in ParticleSystemDef::initial_particles (ropes, chains, probes).
/// It lives forever (lifetime +inf) unless a collider removes it; ids 0..k-1 in list order.
struct InitialParticle {
  Vec3 position = Vec3::Zero();  ///< (m), world frame
  Vec3 velocity = Vec3::Zero();  ///< (m/s), world frame
  double mass = 1e-3;            ///< (kg), > 0
  double radius = 0.01;          ///< (m), > 0
  double charge = 0.0;           ///< (C) for pair forces (ParticleSystemDef::charge is for
                                 ///< emitted particles)
};

/// Damped spring between two particles (Coutinho §3.3.3, eq. 3.6):
///   f_a = -[k_s (|l| - r) + k_d (l̇ · l) / |l|] l / |l|,  l = x_a - x_b,  f_b = -f_a.
/// In ParticleSystemDef::springs, `a` and `b` index initial_particles; in World::add_spring they
/// are particle ids. A spring whose end dies is dropped.
struct SpringDef {
  std::uint64_t a = 0;
  std::uint64_t b = 1;
  double stiffness = 10.0;     ///< k_s (N/m), >= 0
  double damping = 0.0;        ///< k_d (kg/s), >= 0
  double rest_length = -1.0;   ///< r (m), >= 0; negative = the distance when the spring is made
};

/// Gravitational and Coulomb forces between the particles of one system (Coutinho §3.3.4):
///   f_ij = (K q_i q_j - G m_i m_j) (x_i - x_j) / |x_i - x_j|³  for |x_i - x_j| < cutoff,
/// zero beyond. Neighbours are found through a uniform grid of cells of side `cutoff`, so the
/// cost is near-linear in the particle count for a bounded density. Each particle gathers its own
/// force in a fixed order (thread-count independent).
struct PairForceDef {
  double gravitational_G = 0.0;  ///< G (N m²/kg²), >= 0; 0 = off (6.674e-11 is the real value)
  double coulomb_K = 0.0;        ///< K (N m²/C²), >= 0; 0 = off (8.988e9 in vacuum)
  double cutoff = 1.0;           ///< (m), > 0, required when either constant is > 0
  double softening = 1e-4;       ///< (m) ε in |d|² + ε² keeps coincident particles finite, >= 0
  [[nodiscard]] bool enabled() const { return gravitational_G > 0.0 || coulomb_K > 0.0; }
};

/// Where a force field acts.
enum class RegionShape { everywhere, sphere, box };

/// Drop-off of a field's strength with d, the normalised distance from the region centre to its
/// boundary (sphere: |x - c| / radius; box: max_k |local_k| / half_extent_k): weight 1 (none),
/// 1 - d (linear) or (1 - d)² (quadratic) inside (d <= 1), 0 outside. `everywhere` has weight 1.
enum class Falloff { none, linear, quadratic };

enum class FieldKind {
  uniform,     ///< a = acceleration + force / m (wind, updraft)
  attractor,   ///< a = strength (c - x) / |c - x|: toward the centre (strength < 0 repels)
  vortex,      ///< a = strength (axis × ρ̂) - inward_strength ρ̂, ρ = the part of x - c normal
               ///< to the axis: orbit around the axis, optionally pulled in
  curl_noise,  ///< F = drag (u(x, t) - v): dragged toward a divergence-free velocity field
  /// A pressure pulse at `time` from the region centre: the momentum `impulse` Π (N s) leaves
  /// the centre evenly in every direction, and whatever is at distance d takes the share its
  /// cross-section A intercepts, J = w Π A / (4π max(d, √(A/π))²) along the outward direction
  /// (w the drop-off weight), once, in the internal step holding `time`.
  ///  - A dynamic body: A its mean projected area, at its centre of mass (world.hpp, bodies and
  ///    fields).
  ///  - A particle of radius r and mass m alive before the pulse: A = π r², and the velocity
  ///    change is J / (m + ½ ρ_air (4/3)π r³): the added mass of a sphere in air (potential
  ///    flow), which keeps a light, large smoke puff from being thrown faster than the air that
  ///    carries it. Particles born at or after `time` (the explosion's own products, whose
  ///    velocities already are the blast) are not pushed. Cloth is not pushed.
  blast,
};

/// A force field (Coutinho §3.3, "force fields"), confined to a region that can follow a path.
/// All vectors and the region are in the field's frame: `transform` (or `path` sampled at the
/// time when not empty) maps it to the world.
struct ForceFieldDef {
  FieldKind kind = FieldKind::uniform;
  RegionShape shape = RegionShape::everywhere;
  double radius = 1.0;                 ///< (m) sphere radius, > 0
  Vec3 half_extents{1.0, 1.0, 1.0};    ///< (m) box half sizes, each > 0
  Falloff falloff = Falloff::none;
  Transform transform;                 ///< region centre and orientation
  KeyframePath path;                   ///< if not empty, overrides `transform` over time
  // uniform
  Vec3 acceleration = Vec3::Zero();    ///< (m/s²) field frame
  Vec3 force = Vec3::Zero();           ///< (N) field frame, divided by each particle's mass
  /// (m/s) field frame: air velocity of a uniform field (wind). Particles are dragged toward it
  /// with F = drag (u - v); dynamic bodies with F = ½ ρ_air C_d A |u - v| (u - v) (world.hpp).
  Vec3 wind = Vec3::Zero();
  // attractor and vortex
  double strength = 1.0;               ///< (m/s²) attractor pull / vortex tangential
  Vec3 axis = Vec3::UnitZ();           ///< vortex axis, field frame (normalised on add)
  double inward_strength = 0.0;        ///< (m/s²) vortex pull toward its axis
  // curl noise: u(x, t) = amplitude * curl ψ(frequency (x - scroll t)), ψ = three gradient
  // noises of unit amplitude (so |u| is of the order of the amplitude), divergence-free exactly.
  double amplitude = 1.0;              ///< (m/s)
  double frequency = 1.0;              ///< (1/m) spatial frequency of the noise, > 0
  Vec3 scroll = Vec3::Zero();          ///< (m/s) the field drifts with this velocity
  double drag = 1e-3;                  ///< k (kg/s) particle coupling F = k (u - v) to the
                                       ///< curl noise or the uniform field's wind, >= 0
  // blast
  double impulse = 0.0;                ///< Π (N s) >= 0: momentum of the pulse
  double time = 0.0;                   ///< (s) >= 0: when the pulse passes (one step takes it)
  /// Whether the field also pushes dynamic bodies (at their centre of mass; world.hpp).
  bool bodies = true;
  /// Whether the field acts on particles (those of `systems`); false: bodies only.
  bool particles = true;
  /// Systems the field acts on; empty = every system.
  std::vector<ParticleSystemHandle> systems;
};

/// An animated attractor spring of zero rest length (Coutinho §3.3.5, the user-interaction
/// spring, here driven by a path instead of a mouse): F = -k_s (x - p(t)) - k_d (v - ṗ(t)) on
/// each chosen particle of one system.
struct AttractorSpringDef {
  ParticleSystemHandle system;
  std::vector<std::uint64_t> ids;  ///< particle ids pulled; empty = every particle
  Vec3 anchor = Vec3::Zero();      ///< (m) anchor when `path` is empty
  KeyframePath path;               ///< anchor path (translation used)
  double stiffness = 1.0;          ///< k_s (N/m), >= 0
  double damping = 0.0;            ///< k_d (kg/s), >= 0
};

}  // namespace simreel::sim
