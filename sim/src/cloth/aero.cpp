#include "cloth/aero.hpp"

#include <algorithm>
#include <cmath>

#include "core/vector_clones.hpp"

namespace simreel::sim::detail {

namespace {

/// One triangle's F / 3 and damping block (aero.hpp) from its corners' positions p and
/// velocities w (x, y, z each) and the wind; the operations of the per-triangle formula in a
/// fixed order, so the general and the grid loop give the same bits for the same triangle.
/// keep_cell = 0 zeroes a cell that is not in the grid. Writes the 9 numbers `os` apart.
[[gnu::always_inline]] inline void aero_one(
    double p0x, double p0y, double p0z, double p1x, double p1y, double p1z, double p2x,
    double p2y, double p2z, double w0x, double w0y, double w0z, double w1x, double w1y,
    double w1z, double w2x, double w2y, double w2z, double windx, double windy, double windz,
    const AeroCoefficients& k, double keep_cell, double* __restrict out, std::ptrdiff_t os) {
  constexpr double kThird = 1.0 / 3.0;
  const double ux = windx - ((w0x + w1x) + w2x) * kThird;
  const double uy = windy - ((w0y + w1y) + w2y) * kThird;
  const double uz = windz - ((w0z + w1z) + w2z) * kThird;
  const double u2 = (ux * ux + uy * uy) + uz * uz;
  const double e1x = p1x - p0x, e1y = p1y - p0y, e1z = p1z - p0z;
  const double e2x = p2x - p0x, e2y = p2y - p0y, e2z = p2z - p0z;
  double nx = e1y * e2z - e1z * e2y, ny = e1z * e2x - e1x * e2z, nz = e1x * e2y - e1y * e2x;
  const double twice_area = std::sqrt((nx * nx + ny * ny) + nz * nz);
  // Bitwise &: no branches, so the loops calling this stay one basic block and vectorise.
  const bool live = (keep_cell > 0.0) & (u2 > 0.0) & (twice_area > 0.0);
  // Divisions by 1 where the triangle is left out: no infinities to mask.
  const double ia = 1.0 / (twice_area > 0.0 ? twice_area : 1.0);
  nx *= ia;
  ny *= ia;
  nz *= ia;
  const double speed = std::sqrt(u2);
  const double inv_speed = 1.0 / (u2 > 0.0 ? speed : 1.0);
  const double hx = ux * inv_speed, hy = uy * inv_speed, hz = uz * inv_speed;
  double cos_t = (nx * hx + ny * hy) + nz * hz;
  const double turn = cos_t < 0.0 ? -1.0 : 1.0;  // the normal facing the wind
  nx *= turn;
  ny *= turn;
  nz *= turn;
  cos_t *= turn;
  const double q = 0.5 * k.rho * u2 * 0.5 * twice_area;  // ½ ρ |u|² A
  const double drag = q * k.cd * cos_t;
  double fx = drag * nx, fy = drag * ny, fz = drag * nz;
  const double lx = nx - cos_t * hx, ly = ny - cos_t * hy, lz = nz - cos_t * hz;  // |l| = sin θ
  const double lift = (lx * lx + ly * ly) + lz * lz > 1e-24 ? q * k.cl * cos_t : 0.0;
  fx += lift * lx;
  fy += lift * ly;
  fz += lift * lz;
  const double third = live ? kThird : 0.0;
  out[0] = fx * third;
  out[os] = fy * third;
  out[2 * os] = fz * third;
  const double s = live ? q * k.cd * inv_speed * (1.0 + cos_t) * kThird : 0.0;
  out[3 * os] = s * nx * nx;
  out[4 * os] = s * nx * ny;
  out[5 * os] = s * nx * nz;
  out[6 * os] = s * ny * ny;
  out[7 * os] = s * ny * nz;
  out[8 * os] = s * nz * nz;
}

SIMREEL_VECTOR_CLONES
void triangles_kernel(std::size_t nt, const std::uint32_t* __restrict tri,
                      const double* __restrict x, const double* __restrict v, std::ptrdiff_t st,
                      const double* __restrict wind, const AeroCoefficients k,
                      double* __restrict out) {
  for (std::size_t t = 0; t < nt; ++t) {
    const std::ptrdiff_t a = tri[3 * t], b = tri[3 * t + 1], c = tri[3 * t + 2];
    aero_one(x[a], x[st + a], x[2 * st + a], x[b], x[st + b], x[2 * st + b], x[c], x[st + c],
             x[2 * st + c], v[a], v[st + a], v[2 * st + a], v[b], v[st + b], v[2 * st + b], v[c],
             v[st + c], v[2 * st + c], wind[t], wind[nt + t], wind[2 * nt + t], k, 1.0, out + t,
             std::ptrdiff_t(nt));
  }
}

/// Both triangles of the cells with corners a in [i0, i1) (aero.hpp: aero_grid).
SIMREEL_VECTOR_CLONES
void cells_kernel(std::ptrdiff_t i0, std::ptrdiff_t i1, std::ptrdiff_t cols,
                  const double* __restrict x, const double* __restrict v, std::ptrdiff_t st,
                  const double* __restrict wind, const double* __restrict cells,
                  const AeroCoefficients k, double* __restrict work) {
  const std::ptrdiff_t C = cols, C1 = cols + 1;
  const double* X = x;
  const double* Y = x + st;
  const double* Z = x + 2 * st;
  const double* U = v;
  const double* V = v + st;
  const double* W = v + 2 * st;
  // The 18 output arrays are `st` apart (disjoint); GCC cannot prove it for a runtime stride and
  // gives up on the 18 x 18 alias checks.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC ivdep
#endif
  for (std::ptrdiff_t a = i0; a < i1; ++a) {
    // (a, a + C, a + C + 1)
    aero_one(X[a], Y[a], Z[a], X[a + C], Y[a + C], Z[a + C], X[a + C1], Y[a + C1], Z[a + C1],
             U[a], V[a], W[a], U[a + C], V[a + C], W[a + C], U[a + C1], V[a + C1], W[a + C1],
             wind[a], wind[st + a], wind[2 * st + a], k, cells[a], work + a, st);
    // (a, a + C + 1, a + 1)
    aero_one(X[a], Y[a], Z[a], X[a + C1], Y[a + C1], Z[a + C1], X[a + 1], Y[a + 1], Z[a + 1],
             U[a], V[a], W[a], U[a + C1], V[a + C1], W[a + C1], U[a + 1], V[a + 1], W[a + 1],
             wind[3 * st + a], wind[4 * st + a], wind[5 * st + a], k, cells[a], work + 9 * st + a,
             st);
  }
}

/// Each vertex i in [i0, i1): its six triangles' terms (first triangles of the cells at i,
/// i - C, i - C - 1, then second triangles at i, i - C - 1, i - 1), added to f (components 0-2)
/// and written to D (components 3-8).
SIMREEL_VECTOR_CLONES
void vertices_kernel(std::ptrdiff_t i0, std::ptrdiff_t i1, std::ptrdiff_t cols, std::ptrdiff_t st,
                     const double* __restrict work, double* __restrict f, double* __restrict D) {
  const std::ptrdiff_t C = cols, C1 = cols + 1;
  for (std::ptrdiff_t e = 0; e < 9; ++e) {
    const double* t0 = work + e * st;
    const double* t1 = work + (9 + e) * st;
    if (e < 3) {
      double* out = f + e * st;
      for (std::ptrdiff_t i = i0; i < i1; ++i)
        out[i] += ((((t0[i] + t0[i - C]) + t0[i - C1]) + t1[i]) + t1[i - C1]) + t1[i - 1];
    } else {
      double* out = D + (e - 3) * st;
      for (std::ptrdiff_t i = i0; i < i1; ++i)
        out[i] = ((((t0[i] + t0[i - C]) + t0[i - C1]) + t1[i]) + t1[i - C1]) + t1[i - 1];
    }
  }
}

constexpr std::ptrdiff_t kChunk = 512;

}  // namespace

void aero_triangles(std::size_t nt, const std::uint32_t* tri, const double* x, const double* v,
                    std::ptrdiff_t st, const double* wind, const AeroCoefficients& k,
                    double* out) {
  triangles_kernel(nt, tri, x, v, st, wind, k, out);
}

void aero_grid(std::size_t rows, std::size_t columns, const double* x, const double* v,
               std::ptrdiff_t st, const double* wind, const double* cells,
               const AeroCoefficients& k, double* work, double* f, double* D, int threads) {
  const auto n = std::ptrdiff_t(rows * columns);
  const std::ptrdiff_t chunks = (n + kChunk - 1) / kChunk;
  const auto C = std::ptrdiff_t(columns);
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
#pragma omp for schedule(static)
    for (std::ptrdiff_t j = 0; j < chunks; ++j)
      cells_kernel(j * kChunk, std::min(n, (j + 1) * kChunk), C, x, v, st, wind, cells, k, work);
#pragma omp for schedule(static)
    for (std::ptrdiff_t j = 0; j < chunks; ++j)
      vertices_kernel(j * kChunk, std::min(n, (j + 1) * kChunk), C, st, work, f, D);
  }
}

}  // namespace simreel::sim::detail
