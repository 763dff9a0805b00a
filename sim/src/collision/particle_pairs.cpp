// Particle–particle contacts: the cell size, the grid (a counting sort over linear cell indices,
// or hashed cells at several levels for very different radii; Coutinho §2.3.1–2.3.2) and the
// candidate pairs within reach, in a fixed order. The solve is in particle_collisions.cpp.
#include "collision/particle_collisions.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include <omp.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "collision/pair_candidates.hpp"
#include "core/compress_avx2.hpp"  // compress_width()
#include "core/counting_sort.hpp"
#include "core/key_runs.hpp"
#include "core/run_claims.hpp"
#include "particles/forces.hpp"  // kParallelMin

namespace simreel::sim::detail {

namespace {

std::uint32_t hash_cell(std::int64_t x, std::int64_t y, std::int64_t z, std::uint32_t level,
                        std::uint32_t mask) {
  // Teschner et al. 2003 spatial hash primes; the level (§2.3.2) is one more coordinate.
  const auto h = std::uint64_t(x) * 73856093ull ^ std::uint64_t(y) * 19349663ull ^
                 std::uint64_t(z) * 83492791ull ^ std::uint64_t(level) * 2654435761ull;
  return std::uint32_t(h ^ (h >> 29)) & mask;
}

}  // namespace

void ParticleCollider::choose_cells(double h) {
  const std::size_t n = x.size();
  double sum_r = 0.0, max_r = 0.0, min_r = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    sum_r += radius[i];
    max_r = std::max(max_r, radius[i]);
    min_r = std::min(min_r, radius[i]);
  }
  max_radius_ = max_r;
  const double margin = h > 0.0 ? pair_margin_fraction : 0.0;
  const double reach_d = 2.0 + 2.0 * margin;  // a sphere's reach, times its radius
  // Uniform grid (§2.3.1) unless sizes differ by about an order of magnitude or more; then the
  // multi-level grid (§2.3.2): level l has cells 2 x 2^l the smallest reach, each particle
  // lives in the finest level whose cells hold its reach.
  levels = 1;
  if (max_r > 8.0 * min_r) {
    cell_size = 2.0 * reach_d * min_r;
    while (std::ldexp(cell_size, levels - 1) < reach_d * max_r) ++levels;
  } else {
    cell_size = std::max(4.0 * sum_r / double(n), reach_d * max_r);
  }
}

void ParticleCollider::find_contacts(double contact_speed, double h) {
  contacts.clear();
  wall_vc.clear();
  bands_.clear();
  if (x.size() < 2) return;
  choose_cells(h);
  if (levels == 1 && build_grid()) {
    find_pairs(contact_speed, h);
  } else {
    find_contacts_hashed(contact_speed, h);
  }
}

bool ParticleCollider::build_grid(bool sorted_copies) {
  const std::size_t n = x.size();
  const double inv = 1.0 / cell_size;
  // The passes that write each particle's entry, the minima and maxima (exact in any order) and
  // the counting sort (the serial one's order) split over the threads for a large system.
  const int par = threads > 1 && n >= kParallelMin ? threads : 1;
  const std::ptrdiff_t np = std::ptrdiff_t(n);
  double lx = x[0][0], ly = x[0][1], lz = x[0][2];
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1) reduction(min : lx, ly, lz)
  for (std::ptrdiff_t i = 1; i < np; ++i) {
    const Vec3& p = x[std::size_t(i)];
    lx = std::min(lx, p[0]);
    ly = std::min(ly, p[1]);
    lz = std::min(lz, p[2]);
  }
  const Vec3 lo(lx, ly, lz);
  // Cell coordinates from 1 (a neighbour at -1 stays >= 0), and one spare cell past the largest.
  constexpr double kMaxCells = double(1 << 21);
  double cx = 0.0, cy = 0.0, cz = 0.0;
  bool wide = false;
  cell_key_.resize(n);
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1) \
    reduction(max : cx, cy, cz) reduction(|| : wide)
  for (std::ptrdiff_t i = 0; i < np; ++i) {
    const Vec3& p = x[std::size_t(i)];
    const double c0 = std::floor((p[0] - lo[0]) * inv) + 1.0;
    const double c1 = std::floor((p[1] - lo[1]) * inv) + 1.0;
    const double c2 = std::floor((p[2] - lo[2]) * inv) + 1.0;
    // Too wide for 21 bits (or not finite).
    if (!(c0 < kMaxCells - 2.0) || !(c1 < kMaxCells - 2.0) || !(c2 < kMaxCells - 2.0)) {
      wide = true;
      continue;
    }
    cx = std::max(cx, c0);
    cy = std::max(cy, c1);
    cz = std::max(cz, c2);
    // The coordinates, packed 21 bits each, until the strides are known.
    cell_key_[std::size_t(i)] = (std::uint64_t(c0) << 42) | (std::uint64_t(c1) << 21) | std::uint64_t(c2);
  }
  if (wide) return false;
  const std::int64_t dim[3] = {std::int64_t(cx) + 2, std::int64_t(cy) + 2, std::int64_t(cz) + 2};
  stride_y_ = std::uint64_t(dim[2]);
  stride_x_ = std::uint64_t(dim[1]) * stride_y_;
  cells_x_ = std::uint64_t(dim[0]);
  constexpr std::uint64_t kMask = (std::uint64_t{1} << 21) - 1;
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
  for (std::ptrdiff_t i = 0; i < np; ++i) {
    const std::uint64_t c = cell_key_[std::size_t(i)];
    cell_key_[std::size_t(i)] = (c >> 42) * stride_x_ + ((c >> 21) & kMask) * stride_y_ + (c & kMask);
  }
  // Particles by (cell key, index): a counting sort when the box has few cells per particle,
  // else a comparison sort of the same keys (the same order either way).
  order_.resize(n);
  const std::uint64_t cells = std::uint64_t(dim[0]) * stride_x_;
  if (cells <= 4 * std::uint64_t(n) + 4096) {
    stable_counting_sort(
        n, std::size_t(cells), par, sort_scratch_, [&](std::size_t i) { return std::size_t(cell_key_[i]); },
        [](std::size_t) {}, [&](std::size_t i, std::size_t s) { order_[s] = std::uint32_t(i); });
  } else {
    for (std::size_t i = 0; i < n; ++i) order_[i] = std::uint32_t(i);
    std::sort(order_.begin(), order_.end(), [&](std::uint32_t p, std::uint32_t q) {
      return cell_key_[p] != cell_key_[q] ? cell_key_[p] < cell_key_[q] : p < q;
    });
  }
  sx_.resize(n);
  sy_.resize(n);
  sz_.resize(n);
  if (sorted_copies) {
    sr_.resize(n);
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
    for (std::ptrdiff_t ss = 0; ss < np; ++ss) {
      const std::size_t s = std::size_t(ss);
      const std::uint32_t i = order_[s];
      sx_[s] = x[i][0];
      sy_[s] = x[i][1];
      sz_[s] = x[i][2];
      sr_[s] = radius[i];
    }
  }
  // The occupied cells: each sorted position that starts a cell, in order (for a large system
  // through a count of them per stretch of positions, one stretch per thread).
  const auto starts_cell = [&](std::size_t s) {
    return s == 0 || cell_key_[order_[s]] != cell_key_[order_[s - 1]];
  };
  if (par == 1) {
    occupied_.clear();
    cell_first_.clear();
    for (std::size_t s = 0; s < n; ++s)
      if (starts_cell(s)) {
        occupied_.push_back(cell_key_[order_[s]]);
        cell_first_.push_back(std::uint32_t(s));
      }
    cell_first_.push_back(std::uint32_t(n));
    return true;
  }
  cell_cut_.assign(std::size_t(par) + 1, 0);
#pragma omp parallel num_threads(par)
  {
    const std::size_t t = std::size_t(omp_get_thread_num()), p = std::size_t(omp_get_num_threads());
    const std::size_t s0 = n * t / p, s1 = n * (t + 1) / p;
    std::size_t k = 0;
    for (std::size_t s = s0; s < s1; ++s) k += starts_cell(s) ? 1 : 0;
    cell_cut_[t + 1] = k;
#pragma omp barrier
#pragma omp single
    {
      for (std::size_t u = 0; u < p; ++u) cell_cut_[u + 1] += cell_cut_[u];
      occupied_.resize(cell_cut_[p]);
      cell_first_.resize(cell_cut_[p] + 1);
      cell_first_[cell_cut_[p]] = std::uint32_t(n);
    }
    k = cell_cut_[t];
    for (std::size_t s = s0; s < s1; ++s)
      if (starts_cell(s)) {
        occupied_[k] = cell_key_[order_[s]];
        cell_first_[k++] = std::uint32_t(s);
      }
  }
  return true;
}

void ParticleCollider::try_pair(std::uint32_t i, std::uint32_t j, double d2, const Vec3& d,
                                double contact_speed, double h, std::vector<Contact>& out) {
  if (inv_mass[i] == 0.0 && inv_mass[j] == 0.0) {  // both asleep: neither moves
    // Kept aside with its place in the contact order, in case an impact wakes one of them.
    if (record_sleeper_pairs_) sleeper_pairs_.push_back({i, j, std::uint32_t(out.size()), d2});
    return;
  }
  const double rr = radius[i] + radius[j];
  const double dist = std::sqrt(d2);
  const double vn = (v[j] - v[i]).dot(d) / dist;  // < 0: approaching
  // Apart but within the margin: a speculative resting contact (it may close the gap this step,
  // no more), so a pile's contacts hold without first overlapping. An impact is left until it
  // overlaps, where it gets its restitution.
  if (dist >= rr && -vn > contact_speed) return;
  Contact c;
  c.i = i;
  c.j = j;
  c.n = d / dist;
  c.m_eff = 1.0 / (inv_mass[i] + inv_mass[j]);
  c.depth = rr - dist;
  // Alike for all (surface_): the mean of two equal values is that value to the bit.
  const double e = surface_.uniform ? surface_.restitution : 0.5 * (restitution[i] + restitution[j]);
  c.target = dist >= rr ? -(dist - rr) / h : -vn > contact_speed ? -e * vn : 0.0;
  c.mu = surface_.uniform ? surface_.friction : 0.5 * (friction[i] + friction[j]);
  out.push_back(c);
}

void ParticleCollider::find_pairs(double contact_speed, double h) {
  const std::size_t cells = occupied_.size();
  // A large system's cells in one stretch per thread, each with its own candidates and contact
  // list, joined in order: the same contacts in the same order at any thread count.
  const int parts = threads > 1 && x.size() >= kParallelMin ? threads : 1;
  if (search_.size() < std::size_t(parts)) search_.resize(std::size_t(parts));
  // Room for 1.5 contacts a particle (a dense pile has about that many) before the first push:
  // growing by doubling copies the list several times and faults its pages in twice (the first
  // step of a large system spent a third of its pair search so); untouched room costs no memory.
  const std::size_t n = x.size();
  contacts.reserve(n + n / 2);
  if (any_asleep_ && awake_search_share > 0) {
    std::size_t awake = 0;
    for (const std::uint8_t a : asleep) awake += a == 0;
    if (awake * std::size_t(awake_search_share) <= n) {
      find_pairs_of_awake(contact_speed, h);
      return;
    }
  }
  if (parts == 1) {
    find_pairs_in(0, cells, contact_speed, h, search_[0], contacts);
    return;
  }
  // The cells in chunks of about equal particle counts, kChunks a thread, each thread owning a
  // run of them (run_claims.hpp: a thread done early takes chunks from the back of the
  // others'). Thread 0 takes its own run's chunks in order from the first, so it appends them
  // to `contacts` directly; every other chunk's contacts go to a list of its own, joined after
  // them in chunk order. Any split of the cells gives the same list.
  constexpr std::size_t kChunks = 8;
  const std::size_t p = std::size_t(parts), chunks = kChunks * p;
  std::vector<std::size_t>& cut = cell_cut_;
  cut.assign(chunks + 1, cells);
  cut[0] = 0;
  for (std::size_t c = 1; c < chunks; ++c) {  // the first cell at or past c / chunks of the particles
    const std::uint32_t at = std::uint32_t(n * c / chunks);
    cut[c] = std::size_t(std::lower_bound(cell_first_.begin(), cell_first_.end() - 1, at) - cell_first_.begin());
  }
  if (chunk_out_.size() < chunks) chunk_out_.resize(chunks);
  pair_runs_.resize(p);
  for (std::size_t t = 0; t < p; ++t) pair_runs_[t] = claim_run(kChunks * t, kChunks * (t + 1));
  std::size_t direct = 0;  // chunks [0, direct) are in `contacts`
#pragma omp parallel num_threads(parts)
  {
    const std::size_t t = std::size_t(omp_get_thread_num());
    PairSearch& ps = search_[t];
    drain_runs(pair_runs_.data(), p, t, [&](std::size_t c) {
      if (t == 0 && c == direct) {
        find_pairs_in(cut[c], cut[c + 1], contact_speed, h, ps, contacts);
        ++direct;
        return;
      }
      std::vector<Contact>& out = chunk_out_[c];
      out.clear();
      const std::size_t own = cell_first_[cut[c + 1]] - cell_first_[cut[c]];
      out.reserve(own + own / 2);
      find_pairs_in(cut[c], cut[c + 1], contact_speed, h, ps, out);
    });
  }
  for (std::size_t c = direct; c < chunks; ++c)
    contacts.insert(contacts.end(), chunk_out_[c].begin(), chunk_out_[c].end());
}

void ParticleCollider::find_pairs_in(std::size_t cell_begin, std::size_t cell_end,
                                     double contact_speed, double h, PairSearch& ps,
                                     std::vector<Contact>& out) {
  const double margin = h > 0.0 ? pair_margin_fraction : 0.0;
  const std::size_t cells = occupied_.size();
  const std::uint64_t* key_of = occupied_.data();
  const std::uint32_t* first = cell_first_.data();
  const double *px = sx_.data(), *py = sy_.data(), *pz = sz_.data(), *pr = sorted_radius();
  // No pair reaches further than two of the largest spheres: reach_box is within_reach()'s reach
  // on the largest radius by the same rounded operations, so no pair's reach exceeds it. A
  // candidate farther than it along an axis from every particle of a cell (fl(c - x_i) >
  // reach_box, so fl(c - x_i)² >= reach², and the squared distance is no smaller) is out of
  // reach of each of them.
  const double reach_box = (max_radius_ + max_radius_) + margin * max_radius_;
  const int lanes = std::min(compress_width(), pair_search_lanes);
  const GatherInBox gather = gather_in_box(lanes);
  const InReach in_reach_wide = in_reach(lanes);
  // Half stencil: the cell itself (later particles) and the cell above it (z + 1), then the
  // columns (dx, dy) = (0, 1), (1, -1), (1, 0), (1, 1), three cells each (z - 1 .. z + 1), all
  // later in key order. Cells are visited in key order, so each column's first occupied cell
  // only moves forward: a cursor per column instead of a search.
  const std::uint64_t off[4] = {stride_y_, stride_x_ - stride_y_, stride_x_, stride_x_ + stride_y_};
  // A search from a cell past the first starts each column's cursor where the walk from the
  // first cell would have brought it.
  std::size_t cursor[4] = {0, 0, 0, 0};
  if (cell_begin > 0 && cell_begin < cell_end)
    for (int col = 0; col < 4; ++col)
      cursor[col] = std::size_t(std::lower_bound(key_of, key_of + cells, key_of[cell_begin] + off[col] - 1) - key_of);
  std::uint32_t run_b[5], run_e[5];
  for (std::size_t c = cell_begin; c < cell_end; ++c) {
    const std::uint64_t kc = key_of[c];
    run_b[0] = first[c];
    run_e[0] = c + 1 < cells && key_of[c + 1] == kc + 1 ? first[c + 2] : first[c + 1];
    // The cell's candidates: its own run (the cell and the one above), then the four columns.
    // Particle si of the cell takes those after its own position, in the same order as a loop
    // over the runs: one vectorised pass for distances and reaches, a branch-free compaction of
    // the pairs within reach, then try_pair() in order. m counts them as the runs are found, in
    // registers (a sum over run_b and run_e afterwards was vectorised into 128-bit loads of the
    // four-byte stores just made, which the store buffer cannot forward).
    std::size_t m = run_e[0] - run_b[0];
    for (int col = 0; col < 4; ++col) {
      const std::uint64_t lo = kc + off[col] - 1, hi = kc + off[col] + 1;
      const std::size_t end = key_run(key_of, cells, cursor[col], lo, hi);
      const std::size_t cur = cursor[col];
      run_b[col + 1] = first[cur];
      run_e[col + 1] = first[end];
      m += first[end] - first[cur];
    }
    if (ps.cand_s.size() < m + 8) {  // + 8: gather_in_box()'s slack
      ps.cand_s.resize(m + 8);
      ps.hit_u.resize(m + 8);
      for (auto* a : {&ps.cand_x, &ps.cand_y, &ps.cand_z, &ps.cand_r, &ps.cand_d2}) a->resize(m + 8);
    }
    // Only the candidates within reach_box of the box around the cell's particles: one farther
    // along an axis is out of reach of all of them (within_reach() would give 0 for each, see
    // reach_box), so the pairs and their order are those of the whole runs. The cell's own
    // particles lie in the box and keep their places at the front.
    ReachBox box{px[first[c]], py[first[c]], pz[first[c]], px[first[c]], py[first[c]], pz[first[c]], reach_box};
    for (std::uint32_t si = first[c] + 1; si < first[c + 1]; ++si) {
      box.lx = std::min(box.lx, px[si]);
      box.hx = std::max(box.hx, px[si]);
      box.ly = std::min(box.ly, py[si]);
      box.hy = std::max(box.hy, py[si]);
      box.lz = std::min(box.lz, pz[si]);
      box.hz = std::max(box.hz, pz[si]);
    }
    m = gather(run_b, run_e, 5, px, py, pz, pr, box, ps.cand_s.data(), ps.cand_x.data(),
               ps.cand_y.data(), ps.cand_z.data(), ps.cand_r.data());
    // With particles asleep, a sleeping one meets only the awake candidates (try_pair() would
    // drop a pair of sleepers): the same contacts in the same order, and a settled pile's cells
    // cost a scan of their flags.
    std::size_t ma = 0, pa = 0;
    if (any_asleep_) {
      if (ps.awake_s.size() < m) {
        ps.awake_s.resize(m);
        for (auto* a : {&ps.awake_x, &ps.awake_y, &ps.awake_z, &ps.awake_r, &ps.awake_d2}) a->resize(m);
      }
      for (std::size_t q = 0; q < m; ++q) {
        ps.awake_s[ma] = std::uint32_t(q);
        ps.awake_x[ma] = ps.cand_x[q];
        ps.awake_y[ma] = ps.cand_y[q];
        ps.awake_z[ma] = ps.cand_z[q];
        ps.awake_r[ma] = ps.cand_r[q];
        ma += std::size_t(asleep[order_[ps.cand_s[q]]] == 0);
      }
    }
    for (std::uint32_t si = first[c]; si < first[c + 1]; ++si) {
      const std::size_t from = si + 1 - first[c];
      if (any_asleep_ && asleep[order_[si]] != 0) {
        while (pa < ma && ps.awake_s[pa] < from) ++pa;
        within_reach(px[si], py[si], pz[si], pr[si], margin, ps.awake_x.data() + pa,
                     ps.awake_y.data() + pa, ps.awake_z.data() + pa, ps.awake_r.data() + pa, ma - pa,
                     ps.awake_d2.data() + pa);
        for (std::size_t u = pa; u < ma; ++u)
          if (ps.awake_d2[u] > 0.0)
            try_pair(order_[si], order_[ps.cand_s[ps.awake_s[u]]], ps.awake_d2[u], contact_speed, h, out);
        continue;
      }
      // One pass for the distances and the compaction of those within reach, where the CPU
      // has the lanes, instead of within_reach() and a scan of its output.
      if (in_reach_wide != nullptr) {
        const std::size_t hits =
            in_reach_wide(px[si], py[si], pz[si], pr[si], margin, ps.cand_x.data() + from, ps.cand_y.data() + from,
                          ps.cand_z.data() + from, ps.cand_r.data() + from, m - from, ps.hit_u.data(),
                          ps.cand_d2.data());
        // d from the sorted copies, bit for bit x[j] - x[i].
        const double xi = px[si], yi = py[si], zi = pz[si];
        for (std::size_t u = 0; u < hits; ++u) {
          const std::size_t q = from + ps.hit_u[u];
          try_pair(order_[si], order_[ps.cand_s[q]], ps.cand_d2[u],
                   Vec3(ps.cand_x[q] - xi, ps.cand_y[q] - yi, ps.cand_z[q] - zi), contact_speed, h, out);
        }
        continue;
      }
      within_reach(px[si], py[si], pz[si], pr[si], margin, ps.cand_x.data() + from,
                   ps.cand_y.data() + from, ps.cand_z.data() + from, ps.cand_r.data() + from, m - from,
                   ps.cand_d2.data() + from);
      // The candidates within reach, in order: two at a time by a compare and its mask (about
      // one in twenty is within reach, so a per-candidate loop costs more than the pairs).
      const double* d2 = ps.cand_d2.data();
      std::size_t q = from;
#if defined(__SSE2__)
      for (; q + 2 <= m; q += 2)
        for (unsigned bits = unsigned(_mm_movemask_pd(_mm_cmpgt_pd(_mm_loadu_pd(d2 + q), _mm_setzero_pd())));
             bits != 0; bits &= bits - 1) {
          const std::size_t u = q + std::size_t(std::countr_zero(bits));
          try_pair(order_[si], order_[ps.cand_s[u]], d2[u], contact_speed, h, out);
        }
#endif
      for (; q < m; ++q)
        if (d2[q] > 0.0) try_pair(order_[si], order_[ps.cand_s[q]], d2[q], contact_speed, h, out);
    }
  }
}

void ParticleCollider::find_pairs_of_awake(double contact_speed, double h) {
  const double margin = h > 0.0 ? pair_margin_fraction : 0.0;
  const std::size_t cells = occupied_.size();
  const std::uint64_t* key_of = occupied_.data();
  const std::uint32_t* first = cell_first_.data();
  const double *px = sx_.data(), *py = sy_.data(), *pz = sz_.data(), *pr = sorted_radius();
  const auto awake_at = [&](std::uint32_t s) { return asleep[order_[s]] == 0; };
  awake_pairs_.clear();
  for (std::size_t c = 0; c < cells; ++c) {
    bool any = false;
    for (std::uint32_t s = first[c]; s < first[c + 1]; ++s) any = any || awake_at(s);
    if (!any) continue;
    // The nine columns (dx, dy) around the cell, three cells each (z - 1 .. z + 1). Cell
    // coordinates start at 1 with a spare cell past the last: no key wraps.
    std::uint32_t rb[9], re[9];
    int runs = 0;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy) {
        const std::uint64_t lo = key_of[c] + std::uint64_t(dx) * stride_x_ + std::uint64_t(dy) * stride_y_ - 1;
        const std::uint64_t* b = std::lower_bound(key_of, key_of + cells, lo);
        const std::uint64_t* e = b;
        while (e != key_of + cells && *e <= lo + 2) ++e;
        if (b == e) continue;
        rb[runs] = first[b - key_of];
        re[runs++] = first[e - key_of];
      }
    for (std::uint32_t s = first[c]; s < first[c + 1]; ++s) {
      if (!awake_at(s)) continue;
      for (int r = 0; r < runs; ++r) {
        // From s to each of the run, where the half stencil tests from the lower of the two:
        // the same squared distance and reach to the bit (x_a - x_b is -(x_b - x_a) exactly;
        // the sum and the smaller of two radii do not depend on their order).
        const std::size_t len = re[r] - rb[r];
        if (awake_d2_.size() < len) awake_d2_.resize(len);
        within_reach(px[s], py[s], pz[s], pr[s], margin, px + rb[r], py + rb[r], pz + rb[r], pr + rb[r], len,
                     awake_d2_.data());
        for (std::uint32_t u = rb[r]; u < re[r]; ++u) {
          const double d2 = awake_d2_[u - rb[r]];
          // A pair of two awake ones is taken from the lower; a sleeper's from the awake one
          // (and none with itself: d2 is 0).
          if (!(d2 > 0.0) || (u < s && awake_at(u))) continue;
          awake_pairs_.push_back({std::min(s, u), std::max(s, u), d2});
        }
      }
    }
  }
  // The half stencil's order: by the lower sorted position, then the higher (its candidate runs
  // ascend in key, so in sorted position).
  std::sort(awake_pairs_.begin(), awake_pairs_.end(), [](const ReachPair& a, const ReachPair& b) {
    return a.lo != b.lo ? a.lo < b.lo : a.hi < b.hi;
  });
  for (const ReachPair& p : awake_pairs_)
    try_pair(order_[p.lo], order_[p.hi], p.d2, Vec3(px[p.hi] - px[p.lo], py[p.hi] - py[p.lo], pz[p.hi] - pz[p.lo]),
             contact_speed, h, contacts);
}

void ParticleCollider::find_sleeping_neighbours(const std::vector<std::uint32_t>& woken, double h) {
  const double margin = h > 0.0 ? pair_margin_fraction : 0.0;
  const auto was_woken = [&](std::uint32_t u) {
    return std::binary_search(woken.begin(), woken.end(), u);
  };
  for (const std::uint32_t w : woken) {
    const std::uint64_t kw = cell_key_[perm_[w]];
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          // Cell coordinates start at 1 with a spare cell past the last: no key wraps.
          const std::uint64_t kc = kw + std::uint64_t(dx) * stride_x_ + std::uint64_t(dy) * stride_y_ +
                                   std::uint64_t(dz);
          const auto it = std::lower_bound(occupied_.begin(), occupied_.end(), kc);
          if (it == occupied_.end() || *it != kc) continue;
          const std::size_t c = std::size_t(it - occupied_.begin());
          for (std::uint32_t u = cell_first_[c]; u < cell_first_[c + 1]; ++u) {
            // Its partner was asleep at the search too: still asleep, or woken with it (that
            // pair is taken once, from the smaller index).
            if (u == w || (asleep[u] == 0 && !(u > w && was_woken(u)))) continue;
            double d2 = 0.0;
            const std::uint32_t i = std::min(w, u), j = std::max(w, u);
            const double* sr = sorted_radius();
            within_reach(sx_[i], sy_[i], sz_[i], sr[i], margin, &sx_[j], &sy_[j], &sz_[j], &sr[j], 1, &d2);
            if (!(d2 > 0.0)) continue;
            // find_pairs() lists contacts by their first particle: the pair goes after those of i.
            const auto at = std::upper_bound(contacts.begin(), contacts.end(), i,
                                             [](std::uint32_t a, const Contact& c) { return a < c.i; });
            sleeper_pairs_.push_back({i, j, std::uint32_t(at - contacts.begin()), d2});
          }
        }
  }
  std::sort(sleeper_pairs_.begin(), sleeper_pairs_.end(), [](const SleeperPair& a, const SleeperPair& b) {
    return a.before != b.before ? a.before < b.before : a.i != b.i ? a.i < b.i : a.j < b.j;
  });
}

void ParticleCollider::find_contacts_hashed(double contact_speed, double h) {
  const std::size_t n = x.size();
  const double margin = h > 0.0 ? pair_margin_fraction : 0.0;
  const double reach_d = 2.0 + 2.0 * margin;  // a sphere's reach, times its radius
  std::uint32_t table = 1;
  while (table < 2 * n) table <<= 1;
  const std::uint32_t mask = table - 1;
  cell_xyz_.resize(3 * n);
  cell_hash_.resize(n);
  level_.resize(n);
  bucket_start_.assign(std::size_t(table) + 1, 0);
  sorted_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t l = 0;
    while (int(l) + 1 < levels && std::ldexp(cell_size, int(l)) < reach_d * radius[i]) ++l;
    level_[i] = std::uint8_t(l);
    const double inv_cell = 1.0 / std::ldexp(cell_size, int(l));
    for (int a = 0; a < 3; ++a)
      cell_xyz_[3 * i + std::size_t(a)] = std::int64_t(std::floor(x[i][a] * inv_cell));
    cell_hash_[i] = hash_cell(cell_xyz_[3 * i], cell_xyz_[3 * i + 1], cell_xyz_[3 * i + 2], l, mask);
    ++bucket_start_[cell_hash_[i] + 1];
  }
  for (std::uint32_t b = 0; b < table; ++b) bucket_start_[b + 1] += bucket_start_[b];
  // Counting sort, stable: each bucket lists its particles in ascending index.
  cursor_.assign(bucket_start_.begin(), bucket_start_.end() - 1);
  for (std::size_t i = 0; i < n; ++i) sorted_[cursor_[cell_hash_[i]]++] = std::uint32_t(i);
  for (std::size_t i = 0; i < n; ++i) {
    // Own level (pairs j > i), then every coarser one: a pair of different levels is found once,
    // from its smaller particle, in the 27 cells of the larger one's level (its cells are at
    // least both reaches).
    for (int l = level_[i]; l < levels; ++l) {
      std::int64_t cx = cell_xyz_[3 * i], cy = cell_xyz_[3 * i + 1], cz = cell_xyz_[3 * i + 2];
      if (l != level_[i]) {
        const double inv_cell = 1.0 / std::ldexp(cell_size, l);
        cx = std::int64_t(std::floor(x[i][0] * inv_cell));
        cy = std::int64_t(std::floor(x[i][1] * inv_cell));
        cz = std::int64_t(std::floor(x[i][2] * inv_cell));
      }
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const std::int64_t nx = cx + dx, ny = cy + dy, nz = cz + dz;
            const std::uint32_t b = hash_cell(nx, ny, nz, std::uint32_t(l), mask);
            for (std::uint32_t q = bucket_start_[b]; q < bucket_start_[b + 1]; ++q) {
              const std::uint32_t j = sorted_[q];
              if ((levels > 1 && level_[j] != l) || (l == level_[i] && j <= i)) continue;
              // Another cell hashed into the same bucket: it is visited from its own offset.
              if (cell_xyz_[3 * j] != nx || cell_xyz_[3 * j + 1] != ny ||
                  cell_xyz_[3 * j + 2] != nz)
                continue;
              const Vec3 d = x[j] - x[i];
              const double reach = radius[i] + radius[j] + margin * std::min(radius[i], radius[j]);
              const double d2 = d.squaredNorm();
              if (!(d2 < reach * reach) || !(d2 > 0.0)) continue;
              try_pair(std::uint32_t(i), j, d2, contact_speed, h, contacts);
            }
          }
    }
  }
}

}  // namespace simreel::sim::detail
