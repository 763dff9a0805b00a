#pragma once
/// @file world_def.hpp
/// WorldDef: the settings a World is created with (step size, seed, contact speed, threads).
/// Its own header so the engine's lower layers can read it without including world.hpp.

#include <cstdint>

namespace simreel::sim {

struct WorldDef {
  double max_step = 1.0 / 240.0;  ///< (s) largest internal step; advance() splits each sampling
                                  ///< time into ceil(T / max_step) equal steps
  std::uint64_t seed = 0;         ///< scene seed; the i-th system ever added draws from Rng(seed, i)
  double contact_speed = 0.05;    ///< (m/s) normal speed under which a collision becomes a
                                  ///< resting contact (§3.6.3), beyond the g h one step of
                                  ///< gravity adds (not counted as impact speed)
  int threads = 0;                ///< OpenMP threads for large systems (>= 16384 particles);
                                  ///< 0 = the hardware's count. Results are bit-identical at any
                                  ///< count: work is cut into items fixed by the scene, not by
                                  ///< the count, and no item's result depends on the thread
                                  ///< that takes it (fixed reduction order, per-particle gathers)
  double max_speed = 1e4;         ///< (m/s) > 0: a particle's or cloth vertex's velocity
                                  ///< component beyond it is a blow-up (divergence), reported
                                  ///< as NonFiniteState
  double max_distance = 1e6;      ///< (m) > 0: a particle or cloth vertex coordinate beyond it
                                  ///< (from the world origin) is a blow-up, reported as
                                  ///< NonFiniteState
  /// Dynamic bodies at rest fall asleep (an island of bodies in contact, all slower than
  /// 0.05 m/s and 2°/s for 0.5 s: Box2D's tolerances) and cost nothing until something moving
  /// touches them or World::wake is called; false keeps every body simulated every step.
  bool allow_sleeping = true;
  /// Dynamic bodies that move more than a quarter of their thickness in a step are swept from
  /// their start to their end pose against static, kinematic and sleeping bodies (and against a
  /// moving body they could pass through in one step) and stopped at the time of impact
  /// (conservative advancement: Mirtich 1996; Box2D v3's continuous step), and their contacts are
  /// found with a speculative margin, so a 5 cm box at 100 m/s stops at a 1 cm wall instead of
  /// passing it. The part of the step after the impact is dropped for that body (Box2D and Jolt
  /// do the same). false: discrete contacts only (Coutinho §4.4's end-of-step check), which lets
  /// fast thin bodies tunnel. Jointed bodies are never swept (their joint projection runs after).
  bool continuous_collision = true;
  /// Substeps of the bodies' solver per internal step, in [1, 16]. 1 (the default): each internal
  /// step finds the contacts and solves them by sequential impulses (10 sweeps) with split-impulse
  /// position correction. N >= 2: the soft step (Catto 2024; Box2D v3): contacts are found once
  /// per internal step, then N substeps of max_step / N each integrate, solve soft contacts and
  /// joints once with a push-out bias and once without (relax), with the contacts' separations
  /// followed from the bodies' motion; restitution once at the end. Stable stacks at a
  /// quarter of the collision work: max_step 1/60 with 4 substeps solves like 1/240 and finds
  /// contacts like 1/60. Particles and cloth still step at max_step.
  int body_substeps = 1;
};

}  // namespace simreel::sim
