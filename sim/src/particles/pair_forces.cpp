// Gravitational and Coulomb pair forces between the particles of one system (Coutinho §3.3.4)
// over a grid of cut-off cells; each particle gathers its own force in a fixed order.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/vector_clones.hpp"
#include "particles/forces.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif
#if defined(__SSE2__)
#include <emmintrin.h>
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

/// coef[u] = (kq q[u] - gm m[u]) / s³, s = √(r2[u] + ε²), for u < len: the pair force over the
/// distance, F / r = (K q_i q_j - G m_i m_j) / s³ (kq = K q_i, gm = G m_i; Coutinho §3.3.4, with
/// Plummer softening ε). Element-wise and in the scalar form's order ((K q_i) q_j, the square
/// root taken once), so every lane gives the scalar bits; the divide and square root are what
/// a neighbour costs, four at a time here instead of one.
SIMREEL_VECTOR_CLONES
void pair_coefficients(double kq, double gm, double eps2, const double* __restrict r2,
                       const double* __restrict q, const double* __restrict m, std::size_t len,
                       double* __restrict coef) {
  for (std::size_t u = 0; u < len; ++u) {
    const double s2 = r2[u] + eps2;
    coef[u] = (kq * q[u] - gm * m[u]) / (s2 * std::sqrt(s2));
  }
}

/// Bit k set when r2[k] < cut2 (false for NaN, as the scalar test), k < len <= 64. Two lanes a
/// compare on SSE2 (every x86-64): the kept neighbours (~15% of a 27-cell stencil's candidates)
/// are then visited by their set bits instead of testing each candidate in a scalar loop.
std::uint64_t inside_mask(const double* r2, std::size_t len, double cut2) {
  std::uint64_t bits = 0;
  std::size_t k = 0;
#if defined(__SSE2__)
  const __m128d c = _mm_set1_pd(cut2);
  for (; k + 2 <= len; k += 2)
    bits |= std::uint64_t(_mm_movemask_pd(_mm_cmplt_pd(_mm_loadu_pd(r2 + k), c))) << k;
#endif
  for (; k < len; ++k) bits |= std::uint64_t(r2[k] < cut2) << k;
  return bits;
}

}  // namespace

void Dynamics::add_pair_forces(const double* x, double* a) {
  const double cut = pair.cutoff, cut2 = cut * cut, eps2 = pair.softening * pair.softening;
  const double inv = 1.0 / cut;
  // Build: each particle's cell, the particles sorted by (cell key, index) (a total order, so the
  // layout is independent of the thread count), then where each cell's run starts.
  cell_xyz_.resize(3 * n);
  std::int64_t lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] = std::numeric_limits<std::int64_t>::max();
    hi[d] = std::numeric_limits<std::int64_t>::min();
  }
  bool finite = true;
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) {
      const double f = std::floor(x[3 * i + std::size_t(d)] * inv);
      finite = finite && std::abs(f) < double(kCellBias);
      // (a cast of a value beyond +-2^40 would gain nothing: cell_key() clamps it anyway)
      constexpr double kFar = double(std::int64_t{1} << 40);
      const std::int64_t c = f >= kFar ? std::int64_t{1} << 40 : f <= -kFar ? -(std::int64_t{1} << 40)
                             : f == f ? std::int64_t(f) : 0;
      cell_xyz_[3 * i + std::size_t(d)] = c;
      lo[d] = std::min(lo[d], c);
      hi[d] = std::max(hi[d], c);
    }
  }
  std::vector<std::uint32_t>& order = order_;
  order.resize(n);
  rank_.resize(n);
  // (key, index) order. Within +-kCellBias cells (no clamping) the key orders cells as the
  // linear index over the particles' bounding box does, so when that box has few cells per
  // particle a counting sort (stable: indices ascending within a cell) gives the same order in
  // O(n) instead of a comparison sort's O(n log n) random reads, and its prefix sums are a
  // dense table of where every cell's run starts: a neighbour column is then two reads.
  const std::uint64_t ny = finite ? std::uint64_t(hi[1] - lo[1] + 1) : 0,
                      nz = finite ? std::uint64_t(hi[2] - lo[2] + 1) : 0,
                      nx = finite ? std::uint64_t(hi[0] - lo[0] + 1) : 0;
  const bool dense = finite && nx * ny * nz <= 4 * std::uint64_t(n) + 4096;
  std::size_t cells = 0;  // dense: cells of the bounding box; else occupied cells
  if (dense) {
    cells = std::size_t(nx * ny * nz);
    // cnt[c + 2] counts cell c; after the prefix sums cnt[c + 1] is its start, and the scatter
    // advances that to its end, leaving start(c) = cnt[c] and end(c) = cnt[c + 1].
    cell_count_.assign(cells + 2, 0);
    std::uint32_t* cnt = cell_count_.data();
    const auto lin = [&](std::size_t i) {
      const std::int64_t* c = &cell_xyz_[3 * i];
      return std::size_t((std::uint64_t(c[0] - lo[0]) * ny + std::uint64_t(c[1] - lo[1])) * nz +
                         std::uint64_t(c[2] - lo[2]));
    };
    for (std::size_t i = 0; i < n; ++i) ++cnt[lin(i) + 2];
    for (std::size_t c = 1; c < cells + 2; ++c) cnt[c] += cnt[c - 1];
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t s = cnt[lin(i) + 1]++;
      order[s] = std::uint32_t(i);
      rank_[i] = s;
    }
  } else {
    std::vector<std::uint64_t>& keys = cell_key_;
    keys.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      keys[i] = cell_key(cell_xyz_[3 * i], cell_xyz_[3 * i + 1], cell_xyz_[3 * i + 2]);
    for (std::size_t i = 0; i < n; ++i) order[i] = std::uint32_t(i);
    std::sort(order.begin(), order.end(), [&](std::uint32_t p, std::uint32_t q) {
      return keys[p] != keys[q] ? keys[p] < keys[q] : p < q;
    });
    for (std::size_t s = 0; s < n; ++s) rank_[order[s]] = std::uint32_t(s);
    // Occupied cells in key order: key and first particle of each run.
    cell_keys_.clear();
    cell_start_.clear();
    for (std::size_t s = 0; s < n; ++s)
      if (s == 0 || keys[order[s]] != keys[order[s - 1]]) {
        cell_keys_.push_back(keys[order[s]]);
        cell_start_.push_back(std::uint32_t(s));
      }
    cell_start_.push_back(std::uint32_t(n));
    cells = cell_keys_.size();
  }
  // Copy x, y, z, q, m into cell order, one array each: a neighbour cell's particles are then
  // contiguous, and the distance pass over a cell's candidates reads them as vectors. The
  // particles are read in their own order and written to their ranks (a scatter: the random
  // accesses are independent stores, not loads the copy waits for).
  sorted_.resize(5 * n);
  double *sx = sorted_.data(), *sy = sx + n, *sz = sy + n, *sq = sz + n, *sm = sq + n;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t s = rank_[i];
    sx[s] = x[3 * i];
    sy[s] = x[3 * i + 1];
    sz[s] = x[3 * i + 2];
    sq[s] = charge ? charge[i] : 0.0;
    sm[s] = mass[i];
  }
  const double G = pair.gravitational_G, K = pair.coulomb_K;
  accel_.resize(3 * n);
  double* sacc = accel_.data();  // (n x 3) each particle's pair acceleration, in cell order
  // One occupied cell: particles [first, last) in cell order, its nine neighbour columns
  // (dx, dy = -1..1, x-major; each column's three cells dz = -1..1 one contiguous run, in key
  // order). The runs are copied once into a candidate list shared by the cell's particles;
  // each particle takes the squared distances to all candidates in one vectorised pass, visits
  // those within the cut-off by the set bits of a mask (itself excluded by its place in the
  // list), computes their coefficients in one vectorised pass, and sums their forces in
  // candidate order: ascending (cell, index), the same neighbours in the same order as a scalar
  // loop over the runs, so the same bits, whichever thread computes it.
  const auto cell_forces = [&](PairGather& g, std::uint32_t first, std::uint32_t last,
                               const std::uint32_t* run_b, const std::uint32_t* run_e) {
    std::size_t m = 0, self0 = 0;
    for (int r = 0; r < 9; ++r) {
      if (r == 4) self0 = m + (first - run_b[4]);  // the centre column holds the cell itself
      m += run_e[r] - run_b[r];
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
    for (std::uint32_t si = first; si < last; ++si) {
      const double xi = sx[si], yi = sy[si], zi = sz[si];
      const double qi = sq[si], mi = sm[si];
      squared_distances(xi, yi, zi, g.x.data(), g.y.data(), g.z.data(), m, g.r2.data());
      const std::size_t self = self0 + (si - first);
      std::size_t kept = 0;
      for (std::size_t w = 0; w < m; w += 64) {
        std::uint64_t bits = inside_mask(g.r2.data() + w, std::min<std::size_t>(64, m - w), cut2);
        if (self >= w && self - w < 64) bits &= ~(std::uint64_t{1} << (self - w));
        for (; bits != 0; bits &= bits - 1, ++kept) {
          const std::size_t q = w + std::size_t(std::countr_zero(bits));
          const std::uint32_t s = g.s[q];
          g.keep[kept] = std::uint32_t(q);
          g.kr2[kept] = g.r2[q];
          g.kq[kept] = sq[s];
          g.km[kept] = sm[s];
        }
      }
      pair_coefficients(K * qi, G * mi, eps2, g.kr2.data(), g.kq.data(), g.km.data(), kept,
                        g.coef.data());
      double ax = 0, ay = 0, az = 0;
      for (std::size_t u = 0; u < kept; ++u) {
        const std::size_t q = g.keep[u];
        const double c = g.coef[u];
        ax += c * (xi - g.x[q]);
        ay += c * (yi - g.y[q]);
        az += c * (zi - g.z[q]);
      }
      sacc[3 * si] = ax / mi;
      sacc[3 * si + 1] = ay / mi;
      sacc[3 * si + 2] = az / mi;
    }
  };
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
    std::uint32_t run_b[9], run_e[9];
    if (dense) {
      // Cells split where the particles do (a part = the cells whose run starts in its share of
      // [0, n)), so the parts hold about equal particle counts however the cells are filled.
      const std::uint32_t* cnt = cell_count_.data();
      const auto part_begin = [&](std::size_t p) {
        return p == 0    ? std::size_t(0)
               : p == nt ? cells
                         : std::size_t(std::lower_bound(cnt, cnt + cells, std::uint32_t(n * p / nt)) - cnt);
      };
      const std::size_t c_end = part_begin(t + 1), nyz = std::size_t(ny * nz);
      for (std::size_t c = part_begin(t); c < c_end; ++c) {
        if (cnt[c] == cnt[c + 1]) continue;
        const std::size_t ix = c / nyz, iy = c % nyz / std::size_t(nz), iz = c % std::size_t(nz);
        const std::size_t z0 = iz > 0 ? iz - 1 : iz, z1 = iz + 1 < nz ? iz + 1 : iz;
        for (int col = 0; col < 9; ++col) {
          const std::size_t cx = ix + std::size_t(col / 3) - 1, cy = iy + std::size_t(col % 3) - 1;
          if (cx >= nx || cy >= ny) {  // (below 0 wraps to a huge value)
            run_b[col] = run_e[col] = 0;
            continue;
          }
          const std::size_t base = (cx * std::size_t(ny) + cy) * std::size_t(nz);
          run_b[col] = cnt[base + z0];
          run_e[col] = cnt[base + z1 + 1];
        }
        cell_forces(g, cnt[c], cnt[c + 1], run_b, run_e);
      }
    } else {
      // Keys order cells by (x, y, z), and as the cells are visited in key order each column's
      // start only moves forward: nine cursors replace 27 lookups.
      const std::uint64_t* ck = cell_keys_.data();
      const std::uint32_t* cs = cell_start_.data();
      const std::size_t c_begin = cells * t / nt, c_end = cells * (t + 1) / nt;
      std::size_t cursor[9];
      for (std::size_t c = c_begin; c < c_end; ++c) {
        const std::size_t s0 = cs[c];
        const std::int64_t cx = std::int64_t(std::floor(sx[s0] * inv)),
                           cy = std::int64_t(std::floor(sy[s0] * inv)),
                           cz = std::int64_t(std::floor(sz[s0] * inv));
        for (int col = 0; col < 9; ++col) {
          const std::int64_t dx = col / 3 - 1, dy = col % 3 - 1;
          const std::uint64_t lo_key = cell_key(cx + dx, cy + dy, cz - 1);
          const std::uint64_t hi_key = cell_key(cx + dx, cy + dy, cz + 1);
          std::size_t& cur = cursor[col];
          if (c == c_begin)
            cur = std::size_t(std::lower_bound(ck, ck + cells, lo_key) - ck);
          else
            while (cur < cells && ck[cur] < lo_key) ++cur;
          std::size_t end = cur;
          while (end < cells && ck[end] <= hi_key) ++end;
          run_b[col] = cs[cur];
          run_e[col] = cs[end];
        }
        cell_forces(g, cs[c], cs[c + 1], run_b, run_e);
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
