// Gravitational and Coulomb pair forces between the particles of one system (Coutinho §3.3.4)
// over a grid of cut-off cells: each pair once on dense grids (Newton's third law, in a fixed
// order), else each particle gathering its own force in a fixed order.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "core/compress_avx2.hpp"  // compress_width()
#include "core/key_runs.hpp"
#include "core/same_bits.hpp"
#include "core/vector_clones.hpp"
#include "particles/forces.hpp"
#include "particles/pair_lists.hpp"

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
constexpr std::size_t kCopyBlock = 8;         // particles per block copy of a candidate run
static_assert(kCopyBlock >= 3, "the distance pass rounds its length up to 4 into this slack");

constexpr std::int64_t kKeyMax = 2 * kCellBias - 1;

/// The key of the cell (vx, vy, vz), coordinates relative to a base below the particles' cells:
/// 21 bits each, clamped to [0, kKeyMax], x-major. Clamping merges cells (a cloud more than 2^21
/// cells across), which costs candidates, never a neighbour: the lookups clamp alike.
std::uint64_t cell_key(std::int64_t vx, std::int64_t vy, std::int64_t vz) {
  auto c = [](std::int64_t v) { return std::uint64_t(std::clamp<std::int64_t>(v, 0, kKeyMax)); };
  return (c(vx) << 42) | (c(vy) << 21) | c(vz);
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

/// coef[u] = num[u] / s³, s = √(r2[u] + ε²), for u < len: the same coefficient for a pair whose
/// numerator K q_i q_j - G m_i m_j was taken when the pair was found (dense grids, each pair
/// once). Element-wise, as pair_coefficients().
SIMREEL_VECTOR_CLONES
void pair_coefficients_once(double eps2, const double* __restrict r2, const double* __restrict num,
                            std::size_t len, double* __restrict coef) {
  for (std::size_t u = 0; u < len; ++u) {
    const double s2 = r2[u] + eps2;
    coef[u] = num[u] / (s2 * std::sqrt(s2));
  }
}

/// pair_coefficients_once() for pairs that all share one numerator (every particle of one mass
/// and one charge): coef[u] = num / s³, the same operation on the same operands, so the same bits.
SIMREEL_VECTOR_CLONES
void pair_coefficients_shared(double eps2, const double* __restrict r2, double num, std::size_t len,
                              double* __restrict coef) {
  for (std::size_t u = 0; u < len; ++u) {
    const double s2 = r2[u] + eps2;
    coef[u] = num / (s2 * std::sqrt(s2));
  }
}

/// The cells of particles [0, len): c[3i + d] = ⌊x[3i + d] inv⌋ (the cell's integer coordinate
/// along d), with lo[d] and hi[d] lowered and raised to take them in; returns false when some
/// |⌊x inv⌋| >= kCellBias or is NaN (the caller then takes the 64-bit form, whose clamping a
/// key needs; what is written here then goes unused). Element-wise, and min, max and "and" are
/// exact in any order, so every clone gives the same values (the baseline cannot vectorise
/// floor: SSE4.1's roundpd is the first to round a vector). T: double, or float (the store's
/// positions, each taken to double exactly in the loop, where a widening copy first was a third
/// of this pass).
template <class T>
[[gnu::always_inline]] inline bool floor_cells_body(const T* __restrict x, std::size_t len,
                                                    double inv, std::int32_t* __restrict c,
                                                    std::int32_t* __restrict lo,
                                                    std::int32_t* __restrict hi) {
  constexpr double kClamp = double(2 * kCellBias);  // (so the conversion is defined)
  // One flat loop over the 3 len coordinates (no taking rows apart), the bounds kept per place
  // in a period of twelve (four rows: axes x y z x, y z x y, z x y z), folded by axis at the end.
  constexpr std::size_t kPeriod = 12;
  std::int32_t mn[kPeriod], mx[kPeriod];
  for (std::size_t j = 0; j < kPeriod; ++j) {
    mn[j] = lo[j % 3];
    mx[j] = hi[j % 3];
  }
  unsigned ok = 1;
  const auto cell = [&](std::size_t k) {
    const double f = std::floor(double(x[k]) * inv);
    ok &= unsigned(std::abs(f) < double(kCellBias));  // (false for NaN)
    const double g = f < -kClamp ? -kClamp : f > kClamp ? kClamp : f == f ? f : 0.0;
    return std::int32_t(g);
  };
  const std::size_t m = 3 * len, whole = m - m % kPeriod;
  for (std::size_t k0 = 0; k0 < whole; k0 += kPeriod)
    for (std::size_t j = 0; j < kPeriod; ++j) {
      const std::int32_t ck = cell(k0 + j);
      c[k0 + j] = ck;
      mn[j] = std::min(mn[j], ck);
      mx[j] = std::max(mx[j], ck);
    }
  for (std::size_t k = whole; k < m; ++k) {
    const std::int32_t ck = cell(k);
    c[k] = ck;
    mn[k - whole] = std::min(mn[k - whole], ck);
    mx[k - whole] = std::max(mx[k - whole], ck);
  }
  for (std::size_t j = 0; j < kPeriod; ++j) {
    lo[j % 3] = std::min(lo[j % 3], mn[j]);
    hi[j % 3] = std::max(hi[j % 3], mx[j]);
  }
  return ok != 0;
}

/// floor_cells_body() of double positions and of float ones (the grid's two callers' forms).
SIMREEL_VECTOR_CLONES
bool floor_cells(const double* __restrict x, std::size_t len, double inv,
                 std::int32_t* __restrict c, std::int32_t* __restrict lo,
                 std::int32_t* __restrict hi) {
  return floor_cells_body(x, len, inv, c, lo, hi);
}
SIMREEL_VECTOR_CLONES
bool floor_cells(const float* __restrict x, std::size_t len, double inv,
                 std::int32_t* __restrict c, std::int32_t* __restrict lo,
                 std::int32_t* __restrict hi) {
  return floor_cells_body(x, len, inv, c, lo, hi);
}

/// divide_rows() for particles of one mass m (the same operation on the same operands as
/// dividing by a row of m, so the same bits).
SIMREEL_VECTOR_CLONES
void divide_rows(double* __restrict f, double m, std::size_t len) {
  for (std::size_t k = 0; k < 3 * len; ++k) f[k] /= m;
}

/// f[3u + k] /= m[u] for u < len, k < 3: each particle's pair force over its mass, in place.
/// Element-wise (one IEEE divide each, as the scalar form), so every clone gives the same bits;
/// the divides, one a component, were most of the write-back's time when taken one by one.
SIMREEL_VECTOR_CLONES
void divide_rows(double* __restrict f, const double* __restrict m, std::size_t len) {
  for (std::size_t u = 0; u < len; ++u) {
    f[3 * u] /= m[u];
    f[3 * u + 1] /= m[u];
    f[3 * u + 2] /= m[u];
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
  compute_pair_forces(x);
  // Back to the particles' order, each row reading its rank's: independent loads, where a
  // scatter to the rows in cell order was a read-modify-write of a random line (~7 % of a step).
  // One addition per row, so any split over threads gives the same bits.
  const int parts = n >= kParallelMin / 8 && threads > 1 ? threads : 1;
#pragma omp parallel for schedule(static) num_threads(parts) if (parts > 1)
  for (std::size_t i = 0; i < n; ++i) {
    const double* o = pair_acceleration(i);
    a[3 * i] += o[0];
    a[3 * i + 1] += o[1];
    a[3 * i + 2] += o[2];
  }
}

void Dynamics::compute_pair_forces(const double* x) { pair_forces_over_grid(x); }
void Dynamics::compute_pair_forces(const float* x) { pair_forces_over_grid(x); }

template <typename T>
void Dynamics::pair_forces_over_grid(const T* x) {
  const double cut = pair.cutoff, cut2 = cut * cut, eps2 = pair.softening * pair.softening;
  const double inv = 1.0 / cut;
  // Build: each particle's cell, the particles sorted by (cell key, index) (a total order, so the
  // layout is independent of the thread count), then where each cell's run starts.
  // Each particle's cell in 32 bits, in chunks (any split gives the same values: per particle,
  // and min, max and "and" are exact). Beyond +-kCellBias cells (or NaN) the 64-bit form below,
  // clamped as the keys need; the grid is then sparse.
  const int parts = n >= kParallelMin / 8 && threads > 1 ? threads : 1;
  cell32_.resize(3 * n);
  std::int32_t lo32[3], hi32[3];
  for (int d = 0; d < 3; ++d) {
    lo32[d] = std::numeric_limits<std::int32_t>::max();
    hi32[d] = std::numeric_limits<std::int32_t>::min();
  }
  bool finite = true;
  constexpr std::size_t kChunk = 4096;
  const std::size_t chunks = (n + kChunk - 1) / kChunk;
#pragma omp parallel for schedule(static) num_threads(parts) if (parts > 1) \
    reduction(min : lo32[:3]) reduction(max : hi32[:3]) reduction(&& : finite)
  for (std::size_t ch = 0; ch < chunks; ++ch) {
    const std::size_t b = ch * kChunk, len = std::min(n, b + kChunk) - b;
    std::int32_t l[3], u[3];
    for (int d = 0; d < 3; ++d) {
      l[d] = std::numeric_limits<std::int32_t>::max();
      u[d] = std::numeric_limits<std::int32_t>::min();
    }
    finite = floor_cells(x + 3 * b, len, inv, cell32_.data() + 3 * b, l, u) && finite;
    for (int d = 0; d < 3; ++d) {
      lo32[d] = std::min(lo32[d], l[d]);
      hi32[d] = std::max(hi32[d], u[d]);
    }
  }
  std::int64_t lo[3] = {lo32[0], lo32[1], lo32[2]}, hi[3] = {hi32[0], hi32[1], hi32[2]};
  if (!finite) {
    cell_xyz_.resize(3 * n);
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::numeric_limits<std::int64_t>::max();
      hi[d] = std::numeric_limits<std::int64_t>::min();
    }
    for (std::size_t k = 0; k < 3 * n; ++k) {
      const double f = std::floor(double(x[k]) * inv);
      // (a cast of a value beyond +-2^40 would gain nothing: cell_key() clamps it anyway)
      constexpr double kFar = double(std::int64_t{1} << 40);
      cell_xyz_[k] = f >= kFar ? std::int64_t{1} << 40 : f <= -kFar ? -(std::int64_t{1} << 40)
                     : f == f ? std::int64_t(f) : 0;
      lo[k % 3] = std::min(lo[k % 3], cell_xyz_[k]);
      hi[k % 3] = std::max(hi[k % 3], cell_xyz_[k]);
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
      const std::int32_t* c = &cell32_[3 * i];
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
    // Relative to one below the lowest cell, so where the cloud lies does not matter, only how
    // far it spreads (a cloud 10,000 km from the origin at a 0.5 m cut-off once shared keys
    // with its neighbour cells, and met each neighbour up to three times).
    const std::int64_t bx = lo[0] - 1, by = lo[1] - 1, bz = lo[2] - 1;
    for (std::size_t i = 0; i < n; ++i)
      keys[i] = finite ? cell_key(cell32_[3 * i] - bx, cell32_[3 * i + 1] - by,
                                  cell32_[3 * i + 2] - bz)
                       : cell_key(cell_xyz_[3 * i] - bx, cell_xyz_[3 * i + 1] - by,
                                  cell_xyz_[3 * i + 2] - bz);
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
  // contiguous, and the distance pass over a cell's candidates reads them as vectors. Each
  // sorted place reads its particle (a gather: independent loads, each written once in order;
  // the scatter to the ranks was 9-16 % slower on the whole step, on Intel Xeon).
  //
  // Every particle of one mass and one charge (an emitter's, where neither is drawn from a
  // range): q and m are written, not gathered, so a sorted place reads one particle's line at
  // random instead of three (the copy was ~15 % of the 100k-particle step, waiting on those
  // reads), and every pair of the dense path has one numerator K q q - G m m.
  //
  // Where the caller said so (Dynamics::one_mass_charge: no arrays bound), the dense path reads
  // neither q nor m by particle, so neither is written; the sparse path's are filled.
  const bool one_mass_charge =
      this->one_mass_charge || (one_value(mass, n) && one_value(charge, n));
  const double q0 = this->one_mass_charge ? charge0 : charge != nullptr && n > 0 ? charge[0] : 0.0;
  const double m0 = this->one_mass_charge ? mass0 : n > 0 ? mass[0] : 0.0;
  sorted_.resize(5 * n + kCopyBlock, 0.0);  // (+ a block: the dense path's copies overshoot)
  double *sx = sorted_.data(), *sy = sx + n, *sz = sy + n, *sq = sz + n, *sm = sq + n;
#pragma omp parallel for schedule(static) num_threads(parts) if (parts > 1)
  for (std::size_t s = 0; s < n; ++s) {
    const std::size_t i = order[s];
    sx[s] = double(x[3 * i]);
    sy[s] = double(x[3 * i + 1]);
    sz[s] = double(x[3 * i + 2]);
  }
  if (one_mass_charge) {
    if (!dense) {
      std::fill(sq, sq + n, q0);
      std::fill(sm, sm + n, m0);
    }
  } else {
#pragma omp parallel for schedule(static) num_threads(parts) if (parts > 1)
    for (std::size_t s = 0; s < n; ++s) {
      const std::size_t i = order[s];
      sq[s] = charge ? charge[i] : 0.0;
      sm[s] = mass[i];
    }
  }
  const double G = pair.gravitational_G, K = pair.coulomb_K;
  accel_.resize(3 * n);
  double* sacc = accel_.data();  // (n x 3) each particle's pair force, in cell order
  // Sparse grids. One occupied cell: particles [first, last) in cell order, its nine neighbour
  // columns (dx, dy = -1..1, x-major; each column's three cells dz = -1..1 one contiguous run, in key
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
      sacc[3 * si] = ax;  // (divided by the mass on the way back: the same bits)
      sacc[3 * si + 1] = ay;
      sacc[3 * si + 2] = az;
    }
  };
  // Dense grids take each pair once (Newton's third law): a cell meets the later particles of
  // its own cell and 13 of its 26 neighbours, the ones after it in the x-major linear order:
  // (x, y, z + 1), the column (x, y + 1, z - 1..z + 1) and the columns (x + 1, y - 1..y + 1,
  // z - 1..z + 1). Five runs: the cell and (x, y, z + 1) are one (adjacent in the order). Each
  // pair within the cut-off is recorded (i < j in cell order) and its force F = coef (x_i - x_j)
  // added to i and subtracted from j when the pair buffer is flushed, in the order found.
  //
  // Determinism: a cell of the x-plane X writes to particles of the planes X and X + 1 only. The
  // planes are done in two passes, those with X even (absolute cell coordinate) then those with
  // X odd, with a barrier between; in a pass no two planes touch the same particle, so a pass
  // splits over threads by whole planes, and each plane is done by one thread from its first
  // cell to its last. A particle of plane X thus receives, whatever the thread count, first the
  // contributions of the plane done in the first pass (X if even, X - 1 if X is odd), then those
  // of the other, each in that plane's own visiting order: a fixed sequence of additions.
  const int lanes = std::min(compress_width(), pair_lanes);
  const AppendWithin append = append_within(lanes);
  const CellPairs in_place = pair_runs_in_place ? cell_pairs(lanes) : nullptr;
  const auto half_cell = [&](PairGather& g, std::size_t c, std::size_t ix, std::size_t iy,
                             std::size_t iz) {
    const std::uint32_t* cnt = cell_count_.data();
    const std::uint32_t first = cnt[c], last = cnt[c + 1];
    std::uint32_t rb[5], re[5];
    rb[0] = first;
    re[0] = iz + 1 < nz ? cnt[c + 2] : last;
    const std::size_t z0 = iz > 0 ? iz - 1 : iz, z1 = iz + 1 < nz ? iz + 1 : iz;
    // The candidates are counted from the runs' ends as each is found, in registers: a sum
    // over rb and re afterwards was vectorised into 128-bit loads of the four-byte stores just
    // made, which the store buffer cannot forward (a stall of ~5 % of the 100k-particle step).
    std::size_t m = re[0] - rb[0];
    const auto column = [&](int r, std::size_t cx, std::size_t cy) {
      if (cx >= nx || cy >= ny) {  // (below 0 wraps to a huge value)
        rb[r] = re[r] = 0;
        return;
      }
      const std::size_t base = (cx * std::size_t(ny) + cy) * std::size_t(nz);
      const std::uint32_t b = cnt[base + z0], e = cnt[base + z1 + 1];
      rb[r] = b;
      re[r] = e;
      m += e - b;
    };
    column(1, ix, iy + 1);
    column(2, ix + 1, iy - 1);
    column(3, ix + 1, iy);
    column(4, ix + 1, iy + 1);
    if (in_place != nullptr) {
      g.reserve_pairs(g.pairs + std::size_t(last - first) * m + 8);
      g.pairs = in_place(sx, sy, sz, first, last, rb, re, cut2, g.pi.data(), g.pj.data(), g.pr2.data(), g.pairs);
      return;
    }
    g.resize(m + kCopyBlock);
    // A run holds a few particles (~6 here), and an element loop over it costs a mispredicted
    // exit per run: copy whole blocks of kCopyBlock instead, the last one overshooting into
    // room the next run (or the slack) overwrites; it reads at most a block past the end of a
    // sorted array (into the next one, or sorted_'s slack).
    for (std::size_t r = 0, k = 0; r < 5; k += re[r] - rb[r], ++r)
      for (std::size_t u = 0; u < re[r] - rb[r]; u += kCopyBlock) {
        const std::size_t src = rb[r] + u, dst = k + u;
        std::memcpy(g.x.data() + dst, sx + src, kCopyBlock * sizeof(double));
        std::memcpy(g.y.data() + dst, sy + src, kCopyBlock * sizeof(double));
        std::memcpy(g.z.data() + dst, sz + src, kCopyBlock * sizeof(double));
        for (std::size_t v = 0; v < kCopyBlock; ++v) g.s[dst + v] = std::uint32_t(src + v);
      }
    for (std::uint32_t si = first; si < last; ++si) {
      const std::size_t k0 = si - first + 1, len = m - k0;  // the candidates after si
      const double xi = sx[si], yi = sy[si], zi = sz[si];
      // (over a multiple of 4 candidates, into the copies' slack: no remainder loop to mispredict)
      squared_distances(xi, yi, zi, g.x.data() + k0, g.y.data() + k0, g.z.data() + k0,
                        (len + 3) & ~std::size_t{3}, g.r2.data());
      g.reserve_pairs(g.pairs + len + 8);  // (+ 8: append_within's overshoot)
      g.pairs = append(std::uint32_t(si), g.s.data() + k0, g.r2.data(), len, cut2,
                              g.pi.data(), g.pj.data(), g.pr2.data(), g.pairs);
    }
  };
  // The recorded pairs' coefficients in one vectorised pass, then their forces in record order.
  const auto flush = [&](PairGather& g) {
    const std::size_t np = g.pairs;
    if (one_mass_charge) {
      pair_coefficients_shared(eps2, g.pr2.data(), K * q0 * q0 - G * m0 * m0, np, g.pcoef.data());
    } else {
      for (std::size_t u = 0; u < np; ++u) {
        const std::size_t i = g.pi[u], j = g.pj[u];
        g.pnum[u] = K * sq[i] * sq[j] - G * sm[i] * sm[j];
      }
      pair_coefficients_once(eps2, g.pr2.data(), g.pnum.data(), np, g.pcoef.data());
    }
    const std::uint32_t *pi = g.pi.data(), *pj = g.pj.data();
    const double* pc = g.pcoef.data();
    for (std::size_t u = 0; u < np; ++u) {
      const std::size_t i = pi[u], j = pj[u];
      const double c = pc[u];
      const double fx = c * (sx[i] - sx[j]), fy = c * (sy[i] - sy[j]), fz = c * (sz[i] - sz[j]);
      sacc[3 * i] += fx;
      sacc[3 * i + 1] += fy;
      sacc[3 * i + 2] += fz;
      sacc[3 * j] -= fx;
      sacc[3 * j + 1] -= fy;
      sacc[3 * j + 2] -= fz;
    }
    g.pairs = 0;
  };
  constexpr std::size_t kFlushPairs = 512;  // (any flush points give the same bits)
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
      const std::uint32_t* cnt = cell_count_.data();
      const std::size_t nyz = std::size_t(ny * nz);
      // Plane ix's particles: [cnt[ix nyz], cnt[(ix + 1) nyz]) in cell order.
      const auto zero = [&](std::size_t ix) {
        if (ix < nx) std::fill(sacc + 3 * cnt[ix * nyz], sacc + 3 * cnt[(ix + 1) * nyz], 0.0);
      };
      const auto write_back = [&](std::size_t ix) {  // force over mass (to a's rows below)
        if (ix >= nx) return;
        const std::size_t b = cnt[ix * nyz], e = cnt[(ix + 1) * nyz];
        if (one_mass_charge)
          divide_rows(sacc + 3 * b, m0, e - b);
        else
          divide_rows(sacc + 3 * b, sm + b, e - b);
      };
      const auto parity = [&](std::size_t ix) { return (lo[0] + std::int64_t(ix)) & 1; };
      for (std::int64_t pass = 0; pass < 2; ++pass) {
        if (pass == 1) {
#pragma omp barrier
        }
        // A plane with no predecessor in the other pass: part 0 zeroes it before the first
        // pass, or writes it back once its first pass is done.
        if (t == 0 && parity(0) != pass) (pass == 0 ? zero(0) : write_back(0));
        // This pass's planes split where their particles do: a plane goes to the part whose
        // share of the pass's particles holds the plane's first one (empty planes too, for
        // their zeroing or write-back of the next plane).
        std::size_t total = 0;
        for (std::size_t ix = 0; ix < nx; ++ix)
          if (parity(ix) == pass) total += cnt[(ix + 1) * nyz] - cnt[ix * nyz];
        std::size_t before = 0;
        for (std::size_t ix = 0; ix < nx; ++ix) {
          if (parity(ix) != pass) continue;
          const bool mine = std::min(before * nt / std::max<std::size_t>(total, 1), nt - 1) == t;
          before += cnt[(ix + 1) * nyz] - cnt[ix * nyz];
          if (!mine) continue;
          // The first pass's plane ix is the first to touch planes ix and ix + 1; after the
          // second pass's plane ix nothing more reaches planes ix and ix + 1.
          if (pass == 0) {
            zero(ix);
            zero(ix + 1);
          }
          std::size_t c = ix * nyz;
          for (std::size_t iy = 0; iy < ny; ++iy)
            for (std::size_t iz = 0; iz < nz; ++iz, ++c) {
              if (cnt[c] == cnt[c + 1]) continue;
              half_cell(g, c, ix, iy, iz);
              if (g.pairs >= kFlushPairs) flush(g);
            }
          flush(g);
          if (pass == 1) {
            write_back(ix);
            write_back(ix + 1);
          }
        }
      }
    } else {
      // Keys order cells by (x, y, z), and as the cells are visited in key order each column's
      // start only moves forward: nine cursors replace 27 lookups. A cell's coordinates are its
      // key's, so where keys were clamped the lookups are too (and stay monotonic); columns
      // clamped onto one another are taken once.
      const std::uint64_t* ck = cell_keys_.data();
      const std::uint32_t* cs = cell_start_.data();
      // (relative coordinates 1 .. hi - lo + 1, looked up from 0 to hi - lo + 2)
      const bool clamped = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}) + 2 > kKeyMax;
      const std::size_t c_begin = cells * t / nt, c_end = cells * (t + 1) / nt;
      std::size_t cursor[9];
      for (std::size_t c = c_begin; c < c_end; ++c) {
        const std::int64_t cx = std::int64_t(ck[c] >> 42),
                           cy = std::int64_t((ck[c] >> 21) & std::uint64_t(kKeyMax)),
                           cz = std::int64_t(ck[c] & std::uint64_t(kKeyMax));
        for (int col = 0; col < 9; ++col) {
          const std::int64_t dx = col / 3 - 1, dy = col % 3 - 1;
          const std::uint64_t lo_key = cell_key(cx + dx, cy + dy, cz - 1);
          const std::uint64_t hi_key = cell_key(cx + dx, cy + dy, cz + 1);
          std::size_t& cur = cursor[col];
          if (c == c_begin) cur = std::size_t(std::lower_bound(ck, ck + cells, lo_key) - ck);
          const std::size_t end = key_run(ck, cells, cur, lo_key, hi_key);
          run_b[col] = cs[cur];
          run_e[col] = cs[end];
        }
        // A column clamped onto another is the same run: kept once, in the centre column where
        // it is that one (cell_forces() finds the cell itself there).
        const auto same = [&](int p, int q) {
          return run_b[p] != run_e[p] && run_b[p] == run_b[q] && run_e[p] == run_e[q];
        };
        for (int col = 0; col < 9 && clamped; ++col) {
          bool dup = col != 4 && same(4, col);
          for (int r = 0; r < col && !dup; ++r) dup = r != 4 && col != 4 && same(r, col);
          if (dup) run_e[col] = run_b[col];
        }
        cell_forces(g, cs[c], cs[c + 1], run_b, run_e);
      }
    }
  }
  // Force over mass in cell order (sm[rank i] = mass[i]; dense grids did it plane by plane).
  if (!dense) divide_rows(sacc, sm, n);
}

}  // namespace simreel::sim::detail
