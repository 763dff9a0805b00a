// Gravitational and Coulomb pair forces between the particles of one system (Coutinho §3.3.4)
// over a grid of cut-off cells; each particle gathers its own force in a fixed order.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/vector_clones.hpp"
#include "particles/forces.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace simreel::sim::detail {

// ---------------------------------------------------------------------------------------------
// Pair forces over a grid of cut-off cells (§3.3.4)

namespace {

constexpr std::int64_t kCellBias = 1 << 20;  // 21 bits per axis: +-1M cells

std::uint64_t cell_key(std::int64_t cx, std::int64_t cy, std::int64_t cz) {
  auto c = [](std::int64_t v) {
    return std::uint64_t(std::clamp<std::int64_t>(v + kCellBias, 0, 2 * kCellBias - 1));
  };
  return (c(cx) << 42) | (c(cy) << 21) | c(cz);
}

/// r2[k] = |(xi, yi, zi) - (cx, cy, cz)[k]|² for k < m: element-wise, so every lane does the
/// scalar arithmetic (ddx² + ddy² + ddz², left to right) and the AVX2 clone gives the same bits.
SIMREEL_VECTOR_CLONES
void squared_distances(double xi, double yi, double zi, const double* __restrict cx,
                       const double* __restrict cy, const double* __restrict cz, std::size_t m,
                       double* __restrict r2) {
  for (std::size_t k = 0; k < m; ++k) {
    const double dx = xi - cx[k], dy = yi - cy[k], dz = zi - cz[k];
    r2[k] = dx * dx + dy * dy + dz * dz;
  }
}

}  // namespace

void Dynamics::add_pair_forces(const double* x, double* a) {
  const double cut = pair.cutoff, cut2 = cut * cut, eps2 = pair.softening * pair.softening;
  const double inv = 1.0 / cut;
  // Build: each particle's cell key, sorted with its index (a total order, so the layout is
  // independent of the thread count), then a hash of occupied cells -> run in the sorted array.
  cell_key_.resize(n);
  cell_xyz_.resize(3 * n);
  std::int64_t lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] = std::numeric_limits<std::int64_t>::max();
    hi[d] = std::numeric_limits<std::int64_t>::min();
  }
  bool finite = true;
  for (std::size_t i = 0; i < n; ++i) {
    std::int64_t c[3];
    for (int d = 0; d < 3; ++d) {
      const double f = std::floor(x[3 * i + std::size_t(d)] * inv);
      finite = finite && std::abs(f) < double(kCellBias);
      // (a cast of a value beyond +-2^40 would gain nothing: cell_key() clamps it anyway)
      constexpr double kFar = double(std::int64_t{1} << 40);
      c[d] = f >= kFar ? std::int64_t{1} << 40 : f <= -kFar ? -(std::int64_t{1} << 40)
             : f == f ? std::int64_t(f) : 0;
      cell_xyz_[3 * i + std::size_t(d)] = c[d];
      lo[d] = std::min(lo[d], c[d]);
      hi[d] = std::max(hi[d], c[d]);
    }
    cell_key_[i] = cell_key(c[0], c[1], c[2]);
  }
  std::vector<std::uint64_t>& keys = cell_key_;
  std::vector<std::uint32_t>& order = order_;
  order.resize(n);
  rank_.resize(n);
  // (key, index) order. Within +-kCellBias cells (no clamping) the key orders cells as the
  // linear index over the particles' bounding box does, so when that box has few cells per
  // particle a counting sort (stable: indices ascending within a cell) gives the same order in
  // O(n) instead of a comparison sort's O(n log n) random reads.
  const std::uint64_t ny = finite ? std::uint64_t(hi[1] - lo[1] + 1) : 0,
                      nz = finite ? std::uint64_t(hi[2] - lo[2] + 1) : 0,
                      nx = finite ? std::uint64_t(hi[0] - lo[0] + 1) : 0;
  if (finite && nx * ny * nz <= 4 * std::uint64_t(n) + 4096) {
    const std::size_t cells = std::size_t(nx * ny * nz);
    cell_count_.assign(cells + 1, 0);
    const auto lin = [&](std::size_t i) {
      const std::int64_t* c = &cell_xyz_[3 * i];
      return std::size_t((std::uint64_t(c[0] - lo[0]) * ny + std::uint64_t(c[1] - lo[1])) * nz +
                         std::uint64_t(c[2] - lo[2]));
    };
    for (std::size_t i = 0; i < n; ++i) ++cell_count_[lin(i) + 1];
    for (std::size_t c = 0; c < cells; ++c) cell_count_[c + 1] += cell_count_[c];
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t s = cell_count_[lin(i)]++;
      order[s] = std::uint32_t(i);
      rank_[i] = s;
    }
  } else {
    for (std::size_t i = 0; i < n; ++i) order[i] = std::uint32_t(i);
    std::sort(order.begin(), order.end(), [&](std::uint32_t p, std::uint32_t q) {
      return keys[p] != keys[q] ? keys[p] < keys[q] : p < q;
    });
    for (std::size_t s = 0; s < n; ++s) rank_[order[s]] = std::uint32_t(s);
  }
  // Copy key, x, y, z, q, m into cell order, one array each: a neighbour cell's particles are
  // then contiguous, and the distance pass over a cell's candidates reads them as vectors. The
  // particles are read in their own order and written to their ranks (a scatter: the random
  // accesses are independent stores, not loads the copy waits for).
  sorted_.resize(5 * n);
  double *sx = sorted_.data(), *sy = sx + n, *sz = sy + n, *sq = sz + n, *sm = sq + n;
  sorted_key_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t s = rank_[i];
    sorted_key_[s] = keys[i];
    sx[s] = x[3 * i];
    sy[s] = x[3 * i + 1];
    sz[s] = x[3 * i + 2];
    sq[s] = charge ? charge[i] : 0.0;
    sm[s] = mass[i];
  }
  // Occupied cells in key order: key and first particle of each run.
  cell_keys_.clear();
  cell_start_.clear();
  for (std::size_t s = 0; s < n; ++s)
    if (s == 0 || sorted_key_[s] != sorted_key_[s - 1]) {
      cell_keys_.push_back(sorted_key_[s]);
      cell_start_.push_back(std::uint32_t(s));
    }
  cell_start_.push_back(std::uint32_t(n));
  const double G = pair.gravitational_G, K = pair.coulomb_K;
  accel_.resize(3 * n);
  double* sacc = accel_.data();  // (n x 3) each particle's pair acceleration, in cell order
  const std::size_t cells = cell_keys_.size();
  const std::uint64_t* ck = cell_keys_.data();
  const std::uint32_t* cs = cell_start_.data();
  // Gather, one occupied cell at a time. Keys order cells by (x, y, z), so the three cells of a
  // neighbour column (dx, dy, dz = -1..1) are one contiguous run of particles, and as the cells
  // are visited in key order each column's start only moves forward: nine cursors replace 27
  // lookups. The nine runs are copied once per cell into a candidate list shared by the cell's
  // particles; each particle then takes the squared distances to all candidates in one
  // vectorised pass, keeps those within the cut-off (branch-free), and sums their forces in
  // candidate order: the same neighbours in the same order as a scalar loop over the runs, so
  // the same bits, whichever thread computes it.
  const int parts = n >= kParallelMin / 8 && threads > 1 ? threads : 1;
  if (gather_.size() < std::size_t(parts)) gather_.resize(std::size_t(parts));
#pragma omp parallel num_threads(parts) if (parts > 1)
  {
#ifdef _OPENMP
    const std::size_t t = std::size_t(omp_get_thread_num()), nt = std::size_t(omp_get_num_threads());
#else
    const std::size_t t = 0, nt = 1;
#endif
    PairGather& g = gather_[t];
    const std::size_t c_begin = cells * t / nt, c_end = cells * (t + 1) / nt;
    std::size_t cursor[9];
    for (std::size_t c = c_begin; c < c_end; ++c) {
      const std::size_t s0 = cs[c];
      const std::int64_t cx = std::int64_t(std::floor(sx[s0] * inv)),
                         cy = std::int64_t(std::floor(sy[s0] * inv)),
                         cz = std::int64_t(std::floor(sz[s0] * inv));
      std::uint32_t run_b[9], run_e[9];
      std::size_t m = 0;
      for (int col = 0; col < 9; ++col) {
        const std::int64_t dx = col / 3 - 1, dy = col % 3 - 1;
        const std::uint64_t lo = cell_key(cx + dx, cy + dy, cz - 1);
        const std::uint64_t hi = cell_key(cx + dx, cy + dy, cz + 1);
        std::size_t& cur = cursor[col];
        if (c == c_begin)
          cur = std::size_t(std::lower_bound(ck, ck + cells, lo) - ck);
        else
          while (cur < cells && ck[cur] < lo) ++cur;
        std::size_t end = cur;
        while (end < cells && ck[end] <= hi) ++end;
        run_b[col] = cs[cur];
        run_e[col] = cs[end];
        m += run_e[col] - run_b[col];
      }
      g.resize(m);
      std::size_t k = 0;
      for (int r = 0; r < 9; ++r)
        for (std::uint32_t s = run_b[r]; s < run_e[r]; ++s, ++k) {
          g.x[k] = sx[s];
          g.y[k] = sy[s];
          g.z[k] = sz[s];
          g.s[k] = s;
        }
      for (std::uint32_t si = cs[c]; si < cs[c + 1]; ++si) {
        const double xi = sx[si], yi = sy[si], zi = sz[si];
        const double qi = sq[si], mi = sm[si];
        squared_distances(xi, yi, zi, g.x.data(), g.y.data(), g.z.data(), m, g.r2.data());
        std::size_t kept = 0;
        for (std::size_t q = 0; q < m; ++q) {
          g.keep[kept] = std::uint32_t(q);
          kept += std::size_t((g.r2[q] < cut2) & (g.s[q] != si));
        }
        double ax = 0, ay = 0, az = 0;
        for (std::size_t u = 0; u < kept; ++u) {
          const std::size_t q = g.keep[u];
          const std::uint32_t s = g.s[q];
          const double ddx = xi - g.x[q], ddy = yi - g.y[q], ddz = zi - g.z[q];
          const double s2 = g.r2[q] + eps2;
          const double coef = (K * qi * sq[s] - G * mi * sm[s]) / (s2 * std::sqrt(s2));
          ax += coef * ddx;
          ay += coef * ddy;
          az += coef * ddz;
        }
        sacc[3 * si] = ax / mi;
        sacc[3 * si + 1] = ay / mi;
        sacc[3 * si + 2] = az / mi;
      }
    }
  }
  // Back to the particles' order, reading each one's rank (independent loads).
  for (std::size_t i = 0; i < n; ++i) {
    const double* o = sacc + 3 * std::size_t(rank_[i]);
    a[3 * i] += o[0];
    a[3 * i + 1] += o[1];
    a[3 * i + 2] += o[2];
  }
}

}  // namespace simreel::sim::detail
