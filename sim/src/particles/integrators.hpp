#pragma once
// General integrators over a whole system (private): Coutinho Appendix B. Each works on a
// double copy of the system's state and calls the one shared force evaluation (Dynamics::eval).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "particles/forces.hpp"
#include "particles/particle_store.hpp"
#include "simreel/sim/particle_system.hpp"

namespace simreel::sim::detail {

/// Scratch for the general integrators (grown once, reused every step).
struct IntegratorWorkspace {
  std::vector<double> x, v, m, q;                  // state (n x 3, n x 3, n, n)
  std::vector<double> a1, a2, a3, a4, xt, vt, v2, v3;  // stages (n x 3)
  std::vector<double> x_full, v_full, x_half, v_half;  // adaptive: one h vs two h/2
};

/// Per-system integrator bookkeeping kept across steps.
struct IntegratorState {
  double next_h = 0.0;          ///< adaptive: suggested step (s); 0 = start at the full step
  std::uint64_t substeps = 0;   ///< accepted (sub)steps taken, all integrators
  std::uint64_t rejected = 0;   ///< adaptive: rejected trial steps
};

/// Advances particles [begin, end) of `s` from t0 by h with `integrator`, forces from `dyn`
/// (whose spring and pull indices are relative to `begin`; its mass/charge/n are set here), adds
/// h to their ages (unless !age_particles: a newborn's age is already its step) and saves start positions when s.track_prev. Returns true if any result is
/// not finite.
bool integrate_system(ParticleStore& s, std::size_t begin, std::size_t end, double t0, double h,
                      Dynamics& dyn, Integrator integrator, double tolerance,
                      IntegratorState& state, IntegratorWorkspace& w,
                      bool age_particles = true);

}  // namespace simreel::sim::detail
