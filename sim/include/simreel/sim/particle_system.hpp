#pragma once
/// @file particle_system.hpp
/// Particle systems (Coutinho §3.1–3.3, §3.8): definitions and the read-only view the program
/// hands to the renderer and the exporter.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "simreel/sim/forces.hpp"
#include "simreel/sim/handle.hpp"
#include "simreel/sim/keyframes.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim {

/// ODE integrators (Coutinho Appendix B). All of them advance the whole system at once through
/// one shared force evaluation (springs, fields and pair forces work with every one of them).
enum class Integrator {
  semi_implicit_euler,  ///< v += a h; x += v h - h²/2 (g - k_d v / m) d², d = 1 / (1 + h k_d / m)
                        ///< Drag is taken at the new velocity, v = (v + a' h) / (1 + h k_d / m)
                        ///< with a' every other acceleration, so it is stable for any drag and
                        ///< mass (the default); the position term makes ballistic arcs exact (x += h v0 +
                        ///< h² g / 2) and vanishes at the terminal velocity
  rk4,                  ///< classical fourth-order Runge–Kutta on (x, v); with gravity + drag
                        ///< only, a particle with h k_d / m > 0.5 takes ceil(2 h k_d / m)
                        ///< sub-steps (explicit RK4 diverges past 2.78)
  explicit_euler,       ///< x += v h; v += a h (first order; gains energy on oscillators)
  rk2,                  ///< explicit midpoint method (second order)
  implicit_euler,       ///< linearised backward Euler (first order, loses energy; for stiff
                        ///< springs): (M - h ∂f/∂v - h² ∂f/∂x) Δv = h (f + h ∂f/∂x v), solved
                        ///< by conjugate gradients (per particle in closed form without springs)
  adaptive,             ///< RK4 with step doubling: one step of h vs two of h/2, error =
                        ///< max |Δx| (m); rejected and redone above `tolerance`; next step
                        ///< h · 0.8 (tolerance / error)^(1/5), never beyond the internal step
};

/// Emitting shapes, all in the emitter's local frame (its +z axis is "the" emission axis).
/// A particle leaves along the shape's normal at its start point, turned by its spread draw.
enum class EmitterShape {
  disk,    ///< disk of `disk_radius` around the emitter origin, normal = emitter +z axis;
           ///< start points uniform over the area
  quad,    ///< rectangle `quad_size` (x by y, local axes), laid out as a grid (§3.8, eq. 3.100)
  point,   ///< the emitter origin, normal = +z
  sphere,  ///< surface of the sphere of `sphere_radius` around the origin, start points uniform
           ///< over the area, normal = outward radial direction (§3.9: fireworks, explosions).
           ///< The book decomposes the sphere into a grid of cells, one particle per cell; here
           ///< points are random (no overlap guarantee within a release)
  box,     ///< volume of the box `box_size` (x, y, z) centred on the origin, start points
           ///< uniform over the volume, normal = +z
  mesh,    ///< surface of the triangle mesh `mesh_positions`/`mesh_triangles`: a triangle is
           ///< chosen with probability proportional to its area, then a uniform point on it;
           ///< normal = the triangle's face normal (counter-clockwise winding seen from outside)
  cube,    ///< the book's default emitter (§3.8, Fig. 3.43b): a cube of edge `cube_size` centred
           ///< on the origin whose top face (local z = +cube_size / 2) is the emitting quad,
           ///< cube_size x cube_size, laid out as the quad grid, normal = +z. Only the face
           ///< emits; the cube body is not a collider (add a box collider to make it solid)
};

/// One key of a color-over-lifetime gradient; `t` is normalised age (age / lifetime) in [0, 1].
struct ColorKey {
  double t = 0.0;
  std::array<float, 4> rgba{1.f, 1.f, 1.f, 1.f};  ///< linear RGBA in [0, 1]
};

/// One key of a size-over-lifetime curve: at normalised age `t` in [0, 1] a particle's radius is
/// `size` times the radius it was drawn with (piecewise linear between keys, the end keys held
/// outside them).
struct SizeKey {
  double t = 0.0;
  double size = 1.0;  ///< factor on the drawn radius, >= 0
};

/// A burst (Unity's "bursts"): `count` particles born together at `time`, then again every
/// `repeat_interval` for `cycles` bursts in all (0 = forever; a repeat_interval of 0 means a
/// single burst). Counts are exact and do not depend on the frame rate or step: burst k is
/// released in the step whose end is the first >= time + k repeat_interval.
struct Burst {
  double time = 0.0;             ///< (s) first burst
  std::size_t count = 10;        ///< particles per burst
  double repeat_interval = 0.0;  ///< (s) between bursts, >= 0
  std::size_t cycles = 1;        ///< bursts in all; 0 = forever (needs repeat_interval > 0)
};

/// Particle split (Coutinho §3.9.1, its nine parameters in the book's order, with its meanings):
///  1. `enabled`: "whether particles can generate new child particles".
///  2. `children`: "the total number of child particles that will be created by their parent
///     after each split". The parent lives on (the book's parent keeps creating children; see 4).
///  3. `age` (s): "the age of the particle at which it will start to create its children": the
///     first split happens at the end of the first internal step at which age >= `age`.
///  4. `delay_steps`: "the time interval between two consecutive splits, as a multiple of the
///     simulation time step ... a split delay of two indicates that, after the particle-split
///     age has been reached, the particle will create new child particles every other simulation
///     time step": after a split at the end of step s a particle splits again at step
///     s + delay_steps. Children count their own delay from the step they were created in.
///  5. `depth`: "the maximum number of splits a particle may have". A child inherits the count
///     of splits of its parent (after that split), so the count is along the lineage and an
///     emitted particle's family is bounded: after all its splits it holds (children + 1)^depth
///     particles (e.g. 2 children, depth 3: 27).
///  6. `velocity_fraction`: "the percentage value of the parent's velocity inherited by its
///     children": a child's speed is this fraction of the parent's speed at the split.
///  7. `direction_deviation_deg`: "a maximum deviation from the parent's direction ... to spread
///     the children round their parents, along the direction of movement": a child's direction
///     is uniform over the spherical cap of this half-angle around the parent's direction of
///     movement (+z of the emitter if the parent is at rest).
///  8. `size_fraction`: "the percentage value of the parent's size inherited by its children":
///     a child's radius (and drawn base radius) is this fraction of the parent's. Its mass is
///     the parent's times size_fraction³ (the same density; the book does not say).
///  9. `lifetime_deviation` (s): "a maximum deviation from the parent's age inherited by its
///     children": a child's age is the parent's plus a uniform draw in [-dev, +dev] (clamped to
///     [0, lifetime]); its lifetime is the parent's. Children of one split thus die over a
///     spread of times, and their colour and size curves are staggered.
/// A child starts at the parent's position with the parent's colour, and draws in a fixed order
/// (direction, then age per child, parents in store order) from the system's own split Rng. A
/// parent waits (splits at a later step) while the live particles plus its children would exceed
/// max_particles.
struct SplitDef {
  bool enabled = false;
  std::size_t children = 2;              ///< in [1, 10^6]
  double age = 0.5;                      ///< (s) >= 0
  std::size_t delay_steps = 1;           ///< >= 1 internal steps
  std::size_t depth = 1;                 ///< in [1, 32]
  double velocity_fraction = 1.0;        ///< >= 0
  double direction_deviation_deg = 0.0;  ///< in [0, 180]
  double size_fraction = 1.0;            ///< > 0
  double lifetime_deviation = 0.0;       ///< (s) >= 0
};

/// When a sub-emitter fires (Unity's sub-emitter triggers; Houdini's "source from particles").
enum class SubEmitterTrigger {
  death,  ///< a particle of the parent system dies: its age reached its lifetime, or a collider
          ///< killed it (HitAction::kill/split, or it was found inside a solid, §3.4.2)
};

/// A sub-emitter (Unity "Sub Emitters" module): when a particle of the parent system triggers,
/// `count` particles are born in another system, `system`, at the parent's position at that
/// instant. They are drawn from that system's own EmitterDef (lifetime, speed, spread, mass,
/// radius, colour, brightness; its shape and rotation are placed on the parent's position, so a
/// small sphere gives a cloud around it) and its own random stream, and they add
/// `inherit_velocity` times the parent's velocity. The target's rate and bursts still run on their
/// own (give it rate 0 and no bursts to emit only from the parent).
///
/// Timing (death): a particle whose age passed its lifetime by o (s) during the step died at
/// t1 - o, at x1 - v1 o; its sub-particles are born there and then, age o, and move for the rest of
/// the step like any newborn (so they do not lag the step). Sub-particles are born in the births
/// stage of the step the parent died in, after the target's own newborns, parents taken in system
/// order and store order; births beyond the target's max_particles are dropped.
struct SubEmitterDef {
  ParticleSystemHandle system;  ///< the system the particles are born in (may be the parent)
  SubEmitterTrigger trigger = SubEmitterTrigger::death;
  std::size_t count = 10;        ///< particles born per triggering parent, in [1, 10^6]
  /// In [0, 1]: chance that a triggering parent emits at all (Unity's "emit probability"); one
  /// uniform draw per triggering parent from the target's random stream when < 1.
  double probability = 1.0;
  double inherit_velocity = 1.0;  ///< in [0, 1]: fraction of the parent's velocity added
  /// Whether particles created by a split (§3.9.1) trigger too; false: only particles from the
  /// emitter (or spawn_particle), so a star's trail sparks do not fire the star's sub-emitter.
  bool split_children = true;
};

/// Emitter definition (Coutinho §3.8): where and how particles are released. Every per-particle
/// parameter is a Distribution drawn from N(mean, deviation²) (or uniform on [min, max]) per
/// released particle, in a fixed order from the emitter's own Rng(WorldDef::seed, system index),
/// then clamped to [min, max].
///
/// Schedule: particle j (from 0) is born at start_time + (j + 1) / rate while that is <= stop_time,
/// so floor(rate * (t - start_time)) have been born by time t whatever the fps and step; bursts
/// add their counts at their own times (not limited by start/stop_time). Births are taken in time
/// order. A particle born inside an internal step moves only for the rest of that step and starts
/// with that age (a fast jet shows no bands at the step rate); its start point and direction come
/// from the emitter's pose at its own birth time, so a moving emitter leaves no gaps, and it gets
/// `inherit_velocity` times the path's velocity at that time. Births while max_particles are
/// alive are dropped.
/// Quad and cube releases (the particles born in one internal step) are laid out on a grid of
/// cells of side 2 d_max (eq. 3.100; d_max the largest diameter in the release), or d_max if that
/// is too coarse, one random cell per particle and a random offset inside it, so a release does
/// not overlap while the quad has room.
struct EmitterDef {
  EmitterShape shape = EmitterShape::disk;
  double disk_radius = 0.05;               ///< (m), shape == disk
  std::array<double, 2> quad_size{0.2, 0.2};  ///< (m) along local x and y, shape == quad
  double sphere_radius = 0.1;              ///< (m) > 0, shape == sphere
  std::array<double, 3> box_size{0.2, 0.2, 0.2};  ///< (m) full extents, each > 0, shape == box
  double cube_size = 1.0;                  ///< (m) edge of the default cube, shape == cube
  /// (n x 3) vertex positions (m), emitter frame, shape == mesh.
  std::vector<float> mesh_positions;
  /// (m x 3) vertex indices of counter-clockwise triangles, shape == mesh; total area > 0.
  std::vector<std::uint32_t> mesh_triangles;
  Transform transform;                     ///< emitter frame; particles leave along its +z axis
  KeyframePath path;                       ///< if not empty, overrides `transform` over time
  double rate = 100.0;                     ///< particles per second (>= 0, fractional rates
                                           ///< accumulate across steps)
  double start_time = 0.0;                 ///< (s) emission starts
  double stop_time = 1e300;                ///< (s) emission stops
  std::vector<Burst> bursts;               ///< in addition to `rate`
  Distribution lifetime{2.0, 0.0, 0.0};    ///< (s), clamped >= 0
  Distribution start_speed{1.0, 0.0, 0.0}; ///< (m/s) along the emission direction
  Distribution spread_deg{0.0, 0.0, 0.0, 180.0};  ///< polar angle from the shape's normal
                                           ///< (degrees); azimuth uniform in [0, 360). A
                                           ///< negative normal draw is folded (-a at azimuth p
                                           ///< is a at p + 180), then clamped to [min, max] and
                                           ///< [0, 180]
  Distribution mass{1e-3, 0.0, 1e-12};     ///< (kg), clamped > 0 (at least 1e-12); mean > 0
  Distribution radius{0.01, 0.0, 1e-6};    ///< (m), clamped > 0 (at least 1e-6); mean > 0
  /// Standard deviation of a per-particle brightness factor k ~ N(1, color_deviation²) clamped
  /// to [0, 2], multiplying the gradient's RGB (not alpha) all its life. >= 0; 0 = off.
  double color_deviation = 0.0;
  double inherit_velocity = 0.0;           ///< in [0, 1]: fraction of the emitter's velocity
                                           ///< (the path's, at the birth time) added to a newborn
  /// Gradient over normalised age (keys sorted by t; one key = constant colour). Default: one
  /// white key. (Sized, not brace-initialised: GCC 12 warns -Wmaybe-uninitialized on an
  /// initializer_list in a default member initialiser.)
  std::vector<ColorKey> color_over_lifetime = std::vector<ColorKey>(1);
  /// Radius factor over normalised age (keys sorted by t); empty = constant radius.
  std::vector<SizeKey> size_over_lifetime;
  std::size_t max_particles = 100000;      ///< emission pauses while this many are alive
  SplitDef split;                          ///< particle split (§3.9.1)
};

/// A particle system: its emitter, forces and integrator.
struct ParticleSystemDef {
  std::string name = "particles";  ///< used in exports (column `system`)
  EmitterDef emitter;
  Vec3 gravity{0.0, 0.0, -9.81};   ///< (m/s²) gravitational acceleration, world frame
  double drag = 0.0;               ///< viscous drag coefficient k_d (kg/s): F = -k_d v (§3.3.2)
  /// Quadratic (air) drag coefficient c_2 (kg/m): F = -c_2 |v| v, beside `drag`; c_2 = ½ ρ C_d A
  /// for a body of frontal area A in a fluid of density ρ; terminal speed √(m g / c_2).
  double drag_quadratic = 0.0;
  Integrator integrator = Integrator::semi_implicit_euler;
  double tolerance = 1e-4;         ///< (m) adaptive integrator: largest position error per step
  bool collide = true;             ///< collide with the world's colliders
  /// Particles present from the start, ids 0..k-1 (counted in emitter.max_particles).
  std::vector<InitialParticle> initial_particles;
  /// Damped springs (§3.3.3); a and b index initial_particles.
  std::vector<SpringDef> springs;
  /// Electric charge q (C) of each emitted particle: drawn per particle at birth from the
  /// system's own generator Rng(seed, 0x5eed0000 + system index) (a deviation of 0 draws
  /// nothing). Initial particles carry their own InitialParticle::charge.
  Distribution charge{0.0, 0.0};
  PairForceDef pair_forces;
  // Particle–particle collisions (Coutinho §2.3.1 grid, §3.6.1–3.6.2 impulses).
  bool collide_particles = false;  ///< particles of this system collide with each other
  /// Systems sharing a non-empty group collide with each other's particles (and internally).
  std::string collision_group;
  double particle_restitution = 0.5;  ///< e in [0, 1] between particles (pair: the mean)
  double particle_friction = 0.1;     ///< Coulomb mu >= 0 between particles (pair: the mean)
  /// What this system's particles do when they hit any collider, overriding each collider's
  /// Material::on_hit (and its SplitOnHit with `on_hit_split`) when set: rain that splashes on
  /// whatever it falls on. Unset: each collider decides.
  std::optional<HitAction> on_hit;
  SplitOnHit on_hit_split;
};

/// Read-only view of a particle system's live particles, valid until the next World::advance(),
/// spawn_particle() or load_state().
/// Arrays are structure-of-arrays of length `count`; xyz arrays are (count x 3) interleaved.
struct ParticleView {
  std::size_t count = 0;
  const float* position = nullptr;     ///< (count x 3) centre, world frame (m)
  const float* velocity = nullptr;     ///< (count x 3) world frame (m/s)
  const float* color = nullptr;        ///< (count x 4) linear RGBA in [0, 1], from color over lifetime
  const float* radius = nullptr;       ///< (count) (m)
  const float* mass = nullptr;         ///< (count) (kg)
  const float* age = nullptr;          ///< (count) (s)
  const float* lifetime = nullptr;     ///< (count) (s)
  const float* charge = nullptr;       ///< (count) (C), or nullptr when the system has none
  const std::uint64_t* id = nullptr;   ///< (count) stable id, unique within the system, in
                                       ///< emission order; survivors keep their relative order
};

}  // namespace simreel::sim
