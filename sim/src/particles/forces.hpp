#pragma once
// Force evaluation shared by every integrator (private): one call computes the accelerations of
// a whole system from its state (Coutinho §3.2: connected particles are advanced together).

#include <cstddef>
#include <cstdint>
#include <cmath>
#include <vector>

#include "particles/noise.hpp"
#include "simreel/sim/forces.hpp"
#include "simreel/sim/particle_system.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim::detail {

/// A registered force field and its pose at the time of the current evaluation.
struct FieldState {
  ForceFieldDef def;
  GradientNoise noise;
  Vec3 centre = Vec3::Zero();
  Mat3 rotation = Mat3::Identity();  ///< field frame -> world
  void pose_at(double t);
  /// Drop-off weight (see Falloff) at world point x, for the current pose.
  [[nodiscard]] double weight(const Vec3& x) const;
  /// Acceleration (m/s²) on a particle of mass m at x with velocity v, current pose, time t.
  [[nodiscard]] Vec3 acceleration(const Vec3& x, const Vec3& v, double m, double t) const;
  /// (m/s) Air velocity at world point x, time t: a uniform field's wind, the curl noise's flow;
  /// zero for the other kinds (what the air drag of bodies is taken relative to).
  [[nodiscard]] Vec3 air_velocity(const Vec3& x, double t) const;
};

/// Everything that pushes the particles of one system, resolved to indices in the integrated
/// range [0, n). Built for each internal step (springs and attractors are stored by id).
struct Dynamics {
  struct Spring {
    std::uint32_t i, j;
    double ks, kd, rest;
  };
  struct Pull {  // attractor spring, zero rest length (§3.3.5)
    const AttractorSpringDef* def;
    std::vector<std::uint32_t> index;  // empty with all = true: every particle
    bool all = false;
  };

  std::size_t n = 0;
  const double* mass = nullptr;     // (n)
  const double* charge = nullptr;   // (n) or nullptr
  /// Every particle of mass mass0 (kg) and charge charge0 (C), bit for bit, and `mass` and
  /// `charge` not bound (null): set by the pair-block integrator for the pair forces alone, so
  /// that an emitter's particles (one mass, one charge) are not copied to double arrays each step.
  bool one_mass_charge = false;
  double mass0 = 0.0, charge0 = 0.0;
  Vec3 gravity = Vec3::Zero();
  double drag = 0.0;
  double drag_quadratic = 0.0;  ///< c_2 (kg/m): F = -c_2 |v| v
  double max_speed = 1e4;      ///< (m/s) divergence bound on each velocity component
  double max_distance = 1e6;   ///< (m) divergence bound on each coordinate
  PairForceDef pair;
  std::vector<FieldState*> fields;
  std::vector<Spring> springs;
  std::vector<Pull> pulls;
  int threads = 1;
  /// Dense pair-force grids: read each cell's neighbour runs in place with AVX-512 or AVX2 where
  /// the CPU runs it (false: copy them into one candidate list first, as other CPUs do). The
  /// same pairs in the same order either way, so the same bits; the tests compare the two.
  bool pair_runs_in_place = true;
  /// The most candidate pairs tested at once (8, 4 or 1): eight AVX-512VL lanes or four AVX2
  /// lanes where the CPU has them, the kept ones compressed to the front; else one by one. The
  /// same pairs in the same order at every width (the tests compare 8, 4 and 1).
  int pair_lanes = 8;
  /// Semi-implicit Euler with pair forces as the only forces between particles takes them block
  /// by block with the integration (false: the general path, with (n x 3) velocity and
  /// acceleration arrays). The same bits either way; the tests compare the two.
  bool pair_blocks = true;

  /// a (n x 3) = accelerations at time t for positions x and velocities v (n x 3 each). The drag
  /// -(k_d + c_2 |v|) v / m is included only when `with_drag` (semi-implicit Euler takes it
  /// implicitly).
  void eval(double t, const double* x, const double* v, double* a, bool with_drag);

  /// True when each particle's acceleration depends on that particle alone (no pair forces,
  /// springs or attractor springs): eval_block() then gives eval()'s values on any slice.
  [[nodiscard]] bool local() const {
    return !(pair.enabled() && n > 1) && springs.empty() && pulls.empty();
  }
  /// Poses every field at time t (what eval() does first; eval_block() leaves it to the caller).
  void pose_fields(double t);
  /// eval() for `len` <= kBlock particles whose rows x, v (len x 3), mass (len) and a (len x 3)
  /// point at, with the fields already posed at t; only when local(). Bit for bit eval()'s
  /// values for those particles (the same sums in the same order).
  void eval_block(double t, std::size_t len, const double* x, const double* v, const double* mass,
                  double* a, bool with_drag) const;
  static constexpr std::size_t kBlock = 64;  ///< particles per block (one batch of curl noise)

  /// (kg/s) The effective linear drag coefficient k_d + c_2 |v| at velocity v.
  [[nodiscard]] double drag_at(const double* v3) const {
    if (drag_quadratic == 0.0) return drag;
    return drag + drag_quadratic * std::sqrt(v3[0] * v3[0] + v3[1] * v3[1] + v3[2] * v3[2]);
  }

  /// Pair-force accelerations only, added to a (n x 3) for positions x (n x 3): a_i += F_i / m_i
  /// (Coutinho §3.3.4). compute_pair_forces() then pair_acceleration() for each row, one
  /// addition a row, so the same bits wherever the rows are added.
  void add_pair_forces(const double* x, double* a);
  /// The pair forces for positions x (n x 3) into the grid scratch, over the mass, not added
  /// anywhere: pair_acceleration(i) reads particle i's (3 values, m/s²) until the next call.
  void compute_pair_forces(const double* x);
  /// The same for float positions (the particle store's; each taken to double exactly, so the
  /// same bits as from their double copies).
  void compute_pair_forces(const float* x);
  [[nodiscard]] const double* pair_acceleration(std::size_t i) const {
    return accel_.data() + 3 * std::size_t(rank_[i]);
  }

  template <typename T>
  void pair_forces_over_grid(const T* x);  // (both compute_pair_forces)

  // grid scratch (reused; no allocation once grown)
  std::vector<std::uint64_t> cell_key_;     // (n) cell key of each particle (sparse grids)
  std::vector<std::uint32_t> order_;        // (n) particle indices sorted by (cell key, index)
  std::vector<std::uint32_t> rank_;         // (n) particle index -> sorted position
  std::vector<double> sorted_;              // (5 x n) x, then y, z, q, m, each in cell order
  std::vector<double> accel_;               // (n x 3) pair forces (N) in sorted order
  std::vector<std::uint64_t> cell_keys_;    // sparse grids: occupied cells' keys, increasing
  std::vector<std::uint32_t> cell_start_;   // sparse grids: first particle of each cell, + n
  std::vector<std::uint32_t> cell_count_;   // dense grids: run start of every bounding-box cell
  std::vector<std::int32_t> cell32_;        // (n x 3) integer cell coordinates (within +-2^20)
  std::vector<std::int64_t> cell_xyz_;      // (n x 3) the same, clamped to +-2^40 (when beyond)
  /// One thread's candidates of a cell (the particles of its 27 neighbour cells, in run order):
  /// positions, sorted index, squared distances to the current particle; then the ones kept
  /// (candidate index, squared distance, charge, mass) and their force coefficients.
  /// Dense grids (each pair once): the pairs found so far, in the order their forces are added
  /// (sorted indices i < j in visiting order, squared distance, numerator K q_i q_j - G m_i m_j)
  /// and their coefficients; `pairs` of them in use.
  struct PairGather {
    std::vector<double> x, y, z, r2, kr2, kq, km, coef;
    std::vector<std::uint32_t> s, keep;
    std::vector<double> pr2, pnum, pcoef;
    std::vector<std::uint32_t> pi, pj;
    std::size_t pairs = 0;  // (written per particle: the padding keeps the next thread's
    char pad_[64 - sizeof(std::size_t)];  // buffers off its cache line)
    void resize(std::size_t m) {
      if (x.size() >= m) return;
      for (auto* a : {&x, &y, &z, &r2, &kr2, &kq, &km, &coef}) a->resize(m);
      s.resize(m);
      keep.resize(m);
    }
    void reserve_pairs(std::size_t p) {
      if (pr2.size() >= p) return;
      for (auto* a : {&pr2, &pnum, &pcoef}) a->resize(p);
      pi.resize(p);
      pj.resize(p);
    }
  };
  std::vector<PairGather> gather_;  // one per thread
};

/// The velocity factor of a step with the drag taken at the new velocity v' = u d,
/// v' = u / (1 + h (k_d + c_2 |v'|) / m): with a = 1 + h k_d / m, b = h c_2 / m and s = |u|,
/// |v'| solves a |v'| + b |v'|² = s, so d = 2 / (a + √(a² + 4 b s)) (no cancellation; 1 / a when
/// c_2 = 0). Stable for any drag (0 < d <= 1) and the terminal speed √(m g / c_2) is its exact
/// fixed point.
inline double quadratic_drag_damp(double h, double m, double kd, double c2, double s) {
  const double a = 1.0 + h * kd / m, b = h * c2 / m;
  return 2.0 / (a + std::sqrt(a * a + 4.0 * b * s));
}

/// Validation of the force-related definitions: std::invalid_argument naming the field.
void validate_forces(const ParticleSystemDef& def);
void validate(const ForceFieldDef& def);
void validate(const AttractorSpringDef& def);

/// Minimum particle count before a loop is split over threads (below it the fork costs more).
inline constexpr std::size_t kParallelMin = 16384;

}  // namespace simreel::sim::detail
