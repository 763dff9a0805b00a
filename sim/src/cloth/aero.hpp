#pragma once
// The cloth's aerodynamic forces as loops over structures of arrays (private to cloth/).

#include <cstddef>
#include <cstdint>

namespace simreel::sim::detail {

/// Air density and coefficients of the aerodynamic model (ClothDef::aero).
struct AeroCoefficients {
  double rho = 0.0;  ///< air density (kg/m³)
  double cd = 0.0;   ///< drag coefficient C_d
  double cl = 0.0;   ///< lift coefficient C_l
};

/// Aerodynamic drag and lift on triangles [0, nt), after Coutinho §3.9.2's wind force: with u
/// the wind relative to the triangle (the wind minus the mean of its vertices' velocities), A its
/// area, n its unit normal turned to face the wind and cos θ = n · û,
///
///   F = ½ ρ |u|² A cos θ (C_d n + C_l (n - cos θ û)),
///
/// the lift term only where |n - cos θ û| > 1e-12; a third of F goes to each vertex. Also each
/// triangle's damping block c |u| (1 + cos θ) nnᵀ / 3 (c = ½ ρ C_d A; lumped on each vertex for
/// the implicit step: the symmetric bound of the pressure term's ∂/∂u, which keeps light cloth in
/// a gale stable at the frame step). A triangle of zero area or in still air gets zeros.
///
/// tri: 3 vertex indices per triangle; x (m), v (m/s): 3 arrays `st` apart indexed by vertex;
/// wind (m/s): 3 arrays of nt. Writes F / 3 into out[0 .. 3 nt) (3 arrays) and the damping block
/// into out[3 nt .. 9 nt) (6 arrays: xx xy xz yy yz zz).
void aero_triangles(std::size_t nt, const std::uint32_t* tri, const double* x, const double* v,
                    std::ptrdiff_t st, const double* wind, const AeroCoefficients& k, double* out);

/// The same for a rows × columns grid cloth (ClothTopology's generator: cell (r, c) with corner
/// a = r columns + c split into (a, a + columns, a + columns + 1) and (a, a + columns + 1, a + 1)),
/// with every array indexed by the cell's corner a, so the loops read contiguous runs and
/// vectorise (the index lists of the general loop need gathers). Then each vertex's sum of its
/// up to six triangles' F / 3 and damping blocks, in a fixed order, added to f (3 arrays) and
/// written to D (6 arrays).
///
/// x, v, f, D: arrays `st` apart indexed by vertex, valid for indices [-columns - 1, n +
/// columns + 1) (x, v zero outside [0, n)); wind: 2 triangles x 3 arrays `st` apart, indexed
/// by the cell's corner; cells: n numbers, 1 where a cell has its corner at a (not in the last
/// row or column), else 0; work: 2 x 9 arrays `st` apart, valid from index -columns - 1 (zero
/// there; written here). `threads` > 1 splits the vertices in fixed chunks (the same bits at
/// any count).
void aero_grid(std::size_t rows, std::size_t columns, const double* x, const double* v,
               std::ptrdiff_t st, const double* wind, const double* cells,
               const AeroCoefficients& k, double* work, double* f, double* D, int threads);

}  // namespace simreel::sim::detail
