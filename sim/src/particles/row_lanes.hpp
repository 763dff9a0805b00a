// Element-wise particle kernels over rows of three doubles (x, y, z of particle i at 3i..3i+2),
// in a form for each width: the vector clones the compiler writes, and hand-written AVX2 (and,
// for the semi-implicit lanes and the curl drag, AVX-512) that reads and writes the rows as
// they lie. Every form performs the same operations per particle in the same order
// (-ffp-contract=off), so they give the same bits; tests/sim/test_row_lanes.cpp compares them.
#pragma once

#include <cstddef>

namespace simreel::sim::detail {

/// Semi-implicit Euler with a linear viscous drag (Coutinho §2.2; Integrator::semi_implicit_euler)
/// for len particles: per particle i with c = k_d / m_i and d = 1 / (1 + h c),
/// v' = (v + h a) d and x' = x + h v' - (h² / 2) (g - c v') d², exact for a constant
/// acceleration. x, v, a: len rows of 3 (m, m/s, m/s² without the drag); m: len masses (kg);
/// h (s), drag k_d (kg/s), gravity g (m/s²). x and v are updated in place.
/// `lanes` picks the form: 0 the widest hand-written rows the CPU runs (8, else 4), 8 the
/// AVX-512 rows where the CPU has AVX-512F (else as 4), 4 the AVX2 rows wherever the CPU has AVX2,
/// 1 the compiler's clones.
void semi_implicit_linear_rows(std::size_t len, double h, double drag, double g0, double g1,
                               double g2, const double* m, double* x, double* v, const double* a,
                               int lanes = 0);

/// The curl-noise field's drag towards the air velocity (FieldState::acceleration, Coutinho
/// §2.3's viscous drag): a_i += (w_i k_d / m_i) (amplitude R u_i - v_i) for len particles, nothing
/// where w_i = 0 (outside the region). w: weights; ux, uy, uz: the curl per particle (unit-free,
/// one array per axis); q: R row-major (3 x 3); mass (kg); v, a: rows of 3 (m/s, m/s²).
/// `lanes` as above.
void add_noise_drag_rows(std::size_t len, const double* w, const double* ux, const double* uy,
                         const double* uz, const double* q, double amplitude, double drag,
                         const double* mass, const double* v, double* a, int lanes = 0);

/// Rows of three floats (len x 3, as the particle store keeps positions and velocities) to three
/// columns of doubles x, y, z (len each), exactly. `lanes`: 0 the AVX2 form where the CPU has
/// AVX2 but not AVX-512 (whose clone the compiler writes well), 4 the AVX2 form wherever the CPU
/// has AVX2, 1 the clones.
void rows_to_columns(const float* rows, std::size_t len, double* x, double* y, double* z,
                     int lanes = 0);

/// The same into three columns of floats.
void rows_to_columns(const float* rows, std::size_t len, float* x, float* y, float* z,
                     int lanes = 0);

/// Three columns of floats x, y, z (len each) to rows of three (len x 3). `lanes` as for
/// rows_to_columns().
void columns_to_rows(const float* x, const float* y, const float* z, std::size_t len, float* rows,
                     int lanes = 0);

/// True where the CPU runs the AVX2 forms above (lanes = 4).
bool row_lanes_avx2();

/// True where the CPU runs the AVX-512 forms of the semi-implicit lanes and the curl drag
/// (lanes = 8; elsewhere 8 runs the AVX2 form, or the clones without AVX2).
bool row_lanes_avx512();

}  // namespace simreel::sim::detail
