// Gravitational and Coulomb pair forces between the particles of one system (Coutinho §3.3.4)
// over a grid of cut-off cells; each particle gathers its own force in a fixed order.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

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
    for (std::size_t i = 0; i < n; ++i) order[cell_count_[lin(i)]++] = std::uint32_t(i);
  } else {
    for (std::size_t i = 0; i < n; ++i) order[i] = std::uint32_t(i);
    std::sort(order.begin(), order.end(), [&](std::uint32_t p, std::uint32_t q) {
      return keys[p] != keys[q] ? keys[p] < keys[q] : p < q;
    });
  }
  // Occupied cells in key order: key and first particle of each run.
  cell_keys_.clear();
  cell_start_.clear();
  for (std::size_t s = 0; s < n; ++s)
    if (s == 0 || keys[order[s]] != keys[order[s - 1]]) {
      cell_keys_.push_back(keys[order[s]]);
      cell_start_.push_back(std::uint32_t(s));
    }
  cell_start_.push_back(std::uint32_t(n));
  const double G = pair.gravitational_G, K = pair.coulomb_K;
  // Copy (x, y, z, q, m) into cell order: a neighbour cell's particles are then contiguous and
  // the gather reads memory in order instead of at random.
  sorted_.resize(5 * n);
  for (std::size_t s = 0; s < n; ++s) {
    const std::size_t i = order[s];
    double* o = &sorted_[5 * s];
    o[0] = x[3 * i];
    o[1] = x[3 * i + 1];
    o[2] = x[3 * i + 2];
    o[3] = charge ? charge[i] : 0.0;
    o[4] = mass[i];
  }
  const double* xs = sorted_.data();
  const std::size_t cells = cell_keys_.size();
  const std::uint64_t* ck = cell_keys_.data();
  const std::uint32_t* cs = cell_start_.data();
  // Gather, one occupied cell at a time. Keys order cells by (x, y, z), so the three cells of a
  // neighbour column (dx, dy, dz = -1..1) are one contiguous run of particles, and as the cells
  // are visited in key order each column's start only moves forward: nine cursors replace 27
  // lookups. Particle i sums its neighbours in a fixed order, whichever thread computes it.
  const int parts = n >= kParallelMin / 8 && threads > 1 ? threads : 1;
#pragma omp parallel num_threads(parts) if (parts > 1)
  {
#ifdef _OPENMP
    const std::size_t t = std::size_t(omp_get_thread_num()), nt = std::size_t(omp_get_num_threads());
#else
    const std::size_t t = 0, nt = 1;
#endif
    const std::size_t c_begin = cells * t / nt, c_end = cells * (t + 1) / nt;
    std::size_t cursor[9];
    for (std::size_t c = c_begin; c < c_end; ++c) {
      const double* o0 = xs + 5 * std::size_t(cs[c]);
      const std::int64_t cx = std::int64_t(std::floor(o0[0] * inv)),
                         cy = std::int64_t(std::floor(o0[1] * inv)),
                         cz = std::int64_t(std::floor(o0[2] * inv));
      std::uint32_t run_b[9], run_e[9];
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
      }
      for (std::uint32_t si = cs[c]; si < cs[c + 1]; ++si) {
        const double xi = xs[5 * si], yi = xs[5 * si + 1], zi = xs[5 * si + 2];
        const double qi = xs[5 * si + 3], mi = xs[5 * si + 4];
        double ax = 0, ay = 0, az = 0;
        for (int r = 0; r < 9; ++r)
          for (std::uint32_t s = run_b[r]; s < run_e[r]; ++s) {
            if (s == si) continue;
            const double* o = xs + 5 * std::size_t(s);
            const double ddx = xi - o[0], ddy = yi - o[1], ddz = zi - o[2];
            const double r2 = ddx * ddx + ddy * ddy + ddz * ddz;
            if (!(r2 < cut2)) continue;
            const double s2 = r2 + eps2;
            const double coef = (K * qi * o[3] - G * mi * o[4]) / (s2 * std::sqrt(s2));
            ax += coef * ddx;
            ay += coef * ddy;
            az += coef * ddz;
          }
        const std::size_t i = order[si];
        a[3 * i] += ax / mi;
        a[3 * i + 1] += ay / mi;
        a[3 * i + 2] += az / mi;
      }
    }
  }
}

}  // namespace simreel::sim::detail
