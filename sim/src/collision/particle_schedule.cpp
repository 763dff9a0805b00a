// The order of the particle contacts' sweeps (particle_solve.cpp): the bands of grid columns
// that two threads may sweep at once, the wavefront order within a band (the same Gauss–Seidel
// sweep to the bit, its neighbouring updates independent) and the lone contacts, which only the
// first sweep visits.
#include <algorithm>
#include <cassert>
#include <cstdint>
#include <vector>

#include <omp.h>

#include "collision/particle_collisions.hpp"
#include "particles/forces.hpp"  // kParallelMin

namespace simreel::sim::detail {

void ParticleCollider::make_bands(std::size_t pair_count) {
  // Band width in columns: about 64 bands over the particles' extent (at least one column) for
  // a system large enough to be solved in parallel; one band (the plain sweep in cell order)
  // below that, which keeps piles of a few thousand particles as quiet as the sequential order
  // (bands two apart are not coupled within a sweep, so an impulse crosses a pile more slowly).
  // The choice depends on the particle count only, never on the thread count.
  const std::uint64_t width =
      x.size() >= kParallelMin ? std::max<std::uint64_t>(1, (cells_x_ + 63) / 64) : cells_x_;
  const std::size_t nb = std::size_t((cells_x_ + width - 1) / width);
  // Sorted position -> band: the column of its cell (cell keys are x-major), so the band grows
  // with the sorted position, and the pairs (by their first particle) and the collider contacts
  // (by their particle) are in sorted order: each band's range is found by a binary search.
  const auto band_of = [&](std::uint32_t s) {
    return std::size_t(cell_key_[perm_[s]] / stride_x_ / width);
  };
  band_first_.resize(nb + 1);
  const std::uint32_t n = std::uint32_t(x.size());
  for (std::size_t b = 0; b <= nb; ++b) {
    std::uint32_t lo = b == 0 ? 0 : band_first_[b - 1], hi = n;
    while (lo < hi) {  // the first sorted position in band b or later
      const std::uint32_t mid = lo + (hi - lo) / 2;
      if (band_of(mid) < b) lo = mid + 1; else hi = mid;
    }
    band_first_[b] = lo;
  }
  const auto first_at = [&](std::size_t begin, std::size_t end, std::uint32_t s, bool wall) {
    const auto it = std::partition_point(
        contacts.begin() + std::ptrdiff_t(begin), contacts.begin() + std::ptrdiff_t(end),
        [&](const Contact& c) { return (wall ? c.j : c.i) < s; });
    return std::uint32_t(it - contacts.begin());
  };
  bands_.resize(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    Band& band = bands_[b];
    band.pair_begin = b == 0 ? 0 : bands_[b - 1].pair_end;
    band.pair_end = b + 1 == nb ? std::uint32_t(pair_count)
                                : first_at(band.pair_begin, pair_count, band_first_[b + 1], false);
    band.wall_begin = b == 0 ? std::uint32_t(pair_count) : bands_[b - 1].wall_end;
    band.wall_end = b + 1 == nb ? std::uint32_t(contacts.size())
                                : first_at(band.wall_begin, contacts.size(), band_first_[b + 1], true);
  }
#if !defined(NDEBUG)
  for (std::size_t b = 0; b < nb; ++b) {
    for (std::uint32_t q = bands_[b].pair_begin; q < bands_[b].pair_end; ++q) {
      assert(band_of(contacts[q].i) == b);
      assert(band_of(contacts[q].j) == b || band_of(contacts[q].j) == b + 1);
    }
    for (std::uint32_t q = bands_[b].wall_begin; q < bands_[b].wall_end; ++q)
      assert(band_of(contacts[q].j) == b);
  }
#endif
}

void ParticleCollider::cut_bands(int parts, std::vector<std::size_t>& cut) const {
  const std::size_t nb = bands_.size(), m = contacts.size();
  cut.assign(std::size_t(parts) + 1, nb);
  cut[0] = 0;
  // Contacts up to the end of band b: its pairs' end plus its walls' count so far.
  std::size_t b = 0;
  for (int t = 1; t < parts; ++t) {
    const std::size_t goal = m * std::size_t(t) / std::size_t(parts);
    while (b < nb && std::size_t(bands_[b].pair_end) + (bands_[b].wall_end - bands_[0].wall_begin) < goal)
      ++b;
    cut[std::size_t(t)] = std::max(cut[std::size_t(t) - 1], std::min(nb, b + 1));
  }
}

void ParticleCollider::schedule() {
  const std::size_t m = contacts.size();
  sched_.resize(m);
  work_.resize(m);
  const int lanes = wavefront ? solve_lanes(max_lanes) : 1;
  work_vc_.resize(m);
  work_depth_.resize(m);
  wave_.resize(m);
  pair_next_.assign(m, 0);
  // The bands are ordered on their own (a band's windows, its particles' latest waves in the
  // thread's own array), so large systems split them over the threads; the order is the same.
  const int par = threads > 1 && x.size() >= kParallelMin && bands_.size() > 1 ? threads : 1;
  if (wave_scratch_.size() < std::size_t(par)) wave_scratch_.resize(std::size_t(par));
  for (int t = 0; t < par; ++t) wave_scratch_[std::size_t(t)].last_wave.assign(x.size(), 0);
  // Each particle's contacts, counted to 2: a contact whose particles have one each is lone.
  degree_.assign(lone_contacts ? x.size() : 0, 0);
  if (lone_contacts)
    for (const Contact& c : contacts) {
      degree_[c.j] = std::uint8_t(std::min(2, degree_[c.j] + 1));
      if (c.i != kCollider) degree_[c.i] = std::uint8_t(std::min(2, degree_[c.i] + 1));
    }
  const auto lone = [&](const Contact& c) {
    return lone_contacts && degree_[c.j] == 1 && (c.i == kCollider || degree_[c.i] == 1);
  };
  // Contact q's wave is one past the latest wave of the contacts before it (in its window) that
  // share a particle with it, so a particle's contacts keep their order and the contacts of one
  // wave share none: sorting a window by wave (stably) changes no result, and the sweep can
  // overlap each wave's contacts. Windows of kWindow contacts keep the reordered sweep's reads
  // near each other in memory. The window's contacts are idx[0, len), placed from work position
  // `out`.
  constexpr std::size_t kWindow = 2048;
  const auto order_window = [&](const std::uint32_t* idx, std::size_t len, std::size_t out, WaveScratch& ws) {
    std::vector<std::uint32_t>& last_wave = ws.last_wave;
    std::vector<std::uint32_t>& wave_count = ws.wave_count;
    std::uint32_t top = 0;
    for (std::size_t k = 0; k < len; ++k) {
      const std::uint32_t q = idx[k];
      const Contact& c = contacts[q];
      const bool wall = c.i == kCollider;
      std::uint32_t w = last_wave[c.j];
      if (!wall) w = std::max(w, last_wave[c.i]);
      // Wave k's pairs are 2k + 2, its collider contacts 2k + 3: the sweep's branch on the
      // contact's kind then changes once per wave.
      w = 2 * (w / 2 + 1) + (wall ? 1u : 0u);
      wave_[q] = w;
      last_wave[c.j] = w;
      if (!wall) last_wave[c.i] = w;
      top = std::max(top, w);
    }
    wave_count.assign(std::size_t(top) + 2, 0);
    for (std::size_t k = 0; k < len; ++k) ++wave_count[wave_[idx[k]] + 1];
    for (std::size_t w = 0; w + 1 < wave_count.size(); ++w) wave_count[w + 1] += wave_count[w];
    for (std::size_t k = 0; k < len; ++k) sched_[out + wave_count[wave_[idx[k]]]++] = idx[k];
    // Runs of neighbours in one wave go to the widest update the CPU runs together (pair_next_).
    const std::size_t end = out + len;
    for (std::size_t k = out; k < end;) {
      const std::uint32_t wk = wave_[sched_[k]];  // sorted: k .. k + r - 1 alike where the last is
      if (lanes >= 8 && k + 7 < end && wave_[sched_[k + 7]] == wk) {
        pair_next_[k] = 3;
        k += 8;
      } else if (lanes >= 4 && k + 3 < end && wave_[sched_[k + 3]] == wk) {
        pair_next_[k] = 2;
        k += 4;
      } else if (lanes >= 2 && k + 1 < end && wave_[sched_[k + 1]] == wk) {
        pair_next_[k] = 1;
        k += 2;
      } else {
        ++k;
      }
    }
    for (std::size_t k = 0; k < len; ++k) {
      const Contact& c = contacts[idx[k]];
      last_wave[c.j] = 0;
      if (c.i != kCollider) last_wave[c.i] = 0;
    }
  };
  // The range [begin, end): its coupled contacts in windows (or in contact order without the
  // wavefront), then its lone ones, pairs before collider contacts (one wave: they share no
  // particle). Returns the work position of the first lone one.
  const auto order_range = [&](std::size_t begin, std::size_t end, WaveScratch& ws) {
    std::vector<std::uint32_t>& coupled = ws.coupled;
    std::vector<std::uint32_t>& alone = ws.lone;
    coupled.clear();
    alone.clear();
    // (`contacts` holds the pairs, then the collider contacts, so the lone ones come in that order.)
    for (std::size_t q = begin; q < end; ++q) (lone(contacts[q]) ? alone : coupled).push_back(std::uint32_t(q));
    if (wavefront) {
      for (std::size_t w = 0; w < coupled.size(); w += kWindow)
        order_window(coupled.data() + w, std::min(coupled.size() - w, kWindow), begin + w, ws);
    } else {
      std::copy(coupled.begin(), coupled.end(), sched_.begin() + std::ptrdiff_t(begin));
    }
    const std::size_t first_lone = begin + coupled.size();
    std::copy(alone.begin(), alone.end(), sched_.begin() + std::ptrdiff_t(first_lone));
    for (std::size_t k = first_lone; k < end;) {  // runs of one kind in the widest lanes
      const bool wall = contacts[sched_[k]].i == kCollider;
      const auto same = [&](std::size_t r) { return (contacts[sched_[r]].i == kCollider) == wall; };
      if (lanes >= 8 && k + 7 < end && same(k + 7)) {
        pair_next_[k] = 3;
        k += 8;
      } else if (lanes >= 4 && k + 3 < end && same(k + 3)) {
        pair_next_[k] = 2;
        k += 4;
      } else if (lanes >= 2 && k + 1 < end && same(k + 1)) {
        pair_next_[k] = 1;
        k += 2;
      } else {
        ++k;
      }
    }
    return std::uint32_t(first_lone);
  };
  if (bands_.empty()) {
    lone_begin_ = order_range(0, m, wave_scratch_[0]);
  } else {
    const int nb = int(bands_.size());
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
    for (int bi = 0; bi < nb; ++bi) {
      WaveScratch& ws = wave_scratch_[std::size_t(omp_get_thread_num())];
      Band& b = bands_[std::size_t(bi)];
      b.pair_lone = order_range(b.pair_begin, b.pair_end, ws);
      b.wall_lone = order_range(b.wall_begin, b.wall_end, ws);
    }
  }
  const std::ptrdiff_t mm = std::ptrdiff_t(m);
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
  for (std::ptrdiff_t kk = 0; kk < mm; ++kk) {
    const std::size_t k = std::size_t(kk);
    const Contact& c = contacts[sched_[k]];
    work_.i[k] = c.i;
    work_.j[k] = c.j;
    for (int a = 0; a < 3; ++a) {
      work_.n[a][k] = c.n[a];
      work_.pt[a][k] = c.pt[a];
    }
    work_.m_eff[k] = c.m_eff;
    work_.target[k] = c.target;
    work_.mu[k] = c.mu;
    work_.pn[k] = c.pn;
    work_depth_[k] = c.depth;
    if (c.i == kCollider) work_vc_[k] = wall_vc[sched_[k] - (m - wall_vc.size())];
  }
}

}  // namespace simreel::sim::detail
