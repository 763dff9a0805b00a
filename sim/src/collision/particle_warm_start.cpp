// The particle collisions' warm start (Coutinho §3.6.3's resting contacts carried from one step
// to the next, as Box2D's and Bullet's contact caches do): the previous step's resting impulses
// of each group, kept in contact order and found by place while the stores hold the same
// particles, or in key order (the saved state, a changed store); colliders remapped and systems
// forgotten. The step itself is in particle_collisions.cpp.
#include <algorithm>
#include <limits>

#include <omp.h>

#include "collision/particle_collisions.hpp"
#include "core/counting_sort.hpp"
#include "core/state_io.hpp"
#include "particles/forces.hpp"  // kParallelMin

namespace simreel::sim::detail {

void ParticleCollider::remap_colliders(const std::vector<std::uint32_t>& new_index) {
  constexpr std::uint64_t kWall = std::uint64_t{1} << 63;
  for (WarmCache& c : caches_) {
    key_order(c, 1, sort_scratch_, key_order_tmp_);
    std::size_t keep = 0;
    for (std::size_t q = 0; q < c.ki.size(); ++q) {
      std::uint64_t kj = c.kj[q];
      if ((kj & kWall) != 0) {
        const std::uint64_t old = kj & ~kWall;
        if (old >= new_index.size() || new_index[old] == kRemoved) continue;
        kj = kWall | new_index[old];
      }
      c.ki[keep] = c.ki[q];
      c.kj[keep] = kj;
      c.n[keep] = c.n[q];
      c.pt[keep] = c.pt[q];
      c.pn[keep] = c.pn[q];
      ++keep;
    }
    c.resize_entries(keep);
  }
}

void ParticleCollider::save_warm(StateWriter& out) const {
  out.value(std::uint64_t(caches_.size()));
  for (const WarmCache& stored : caches_) {
    // The saved state holds key order, whichever form the step left.
    WarmCache copy, tmp;
    CountingSortScratch scratch;
    if (!stored.owner.empty()) {
      copy = stored;
      key_order(copy, 1, scratch, tmp);
    }
    const WarmCache& c = stored.owner.empty() ? stored : copy;
    out.value(c.group);
    out.array(c.ki);
    out.array(c.kj);
    out.array(c.n);
    out.array(c.pt);
    out.array(c.pn);
  }
}

void ParticleCollider::load_warm(StateReader& in) {
  // A group without entries: its id and five array counts.
  caches_.resize(in.records(sizeof(std::uint32_t) + 5 * sizeof(std::uint64_t), "particle contact groups"));
  constexpr std::size_t kMax = std::size_t{1} << 40;
  for (WarmCache& c : caches_) {
    for (auto* a : {&c.owner, &c.perm, &c.pair_first, &c.wall_first}) a->clear();  // key order
    c.keys.clear();
    c.by_place = false;
    in.value(c.group);
    in.array(c.ki, kMax, "particle warm-start keys");
    in.array(c.kj, c.ki.size(), "particle warm-start keys");
    in.array(c.n, c.ki.size(), "particle warm-start normals");
    in.array(c.pt, c.ki.size(), "particle warm-start impulses");
    in.array(c.pn, c.ki.size(), "particle warm-start impulses");
    if (c.kj.size() != c.ki.size() || c.n.size() != c.ki.size() || c.pt.size() != c.ki.size() ||
        c.pn.size() != c.ki.size())
      throw StateError("state: particle warm-start arrays of different lengths");
  }
}

void ParticleCollider::forget_system(std::uint32_t serial) {
  caches_.erase(std::remove_if(caches_.begin(), caches_.end(),
                               [serial](const WarmCache& c) { return c.group == serial; }),
                caches_.end());
}

void ParticleCollider::load_warm_start(WarmCache& c) {
  constexpr std::uint64_t kWall = std::uint64_t{1} << 63;
  const std::size_t n = key_flat_.size();
  const int par = threads > 1 && x.size() >= kParallelMin ? threads : 1;
  // Through the working index the cache's step gave each particle, when the store holds the
  // same particles in the same places (the stored flat keys begin the current ones: particles
  // may have been born since, not died) and the cache has its ranges; else by key. One born since
  // has no entries (its key is new), so it has no working index then (kNone).
  constexpr std::uint32_t kNone = 0xffffffffu;
  const std::size_t before = c.keys.size();
  const bool by_place = !c.owner.empty() && c.by_place && before <= n &&
                        std::equal(c.keys.begin(), c.keys.end(), key_flat_.begin());
  if (by_place) {
    prev_working_.resize(n);
    const std::ptrdiff_t np = std::ptrdiff_t(before);
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
    for (std::ptrdiff_t q = 0; q < np; ++q) prev_working_[c.perm[std::size_t(q)]] = std::uint32_t(q);
    std::fill(prev_working_.begin() + std::ptrdiff_t(before), prev_working_.end(), kNone);
  } else {
    key_order(c, par, sort_scratch_, key_order_tmp_);
    // The first cache entry of each particle's key, by a walk over the particles in flat order
    // (keys ascending within a system, systems in registration order), searching only where a
    // key goes back.
    // (The walk's cursor is lower_bound(ki, key) at every particle, so each thread's stretch of
    // particles starts with one.)
    warm_first_.resize(n);
#pragma omp parallel num_threads(par) if (par > 1)
    {
      const std::size_t t = std::size_t(omp_get_thread_num()), parts = std::size_t(omp_get_num_threads());
      const std::size_t f0 = n * t / parts, f1 = n * (t + 1) / parts;
      std::size_t cursor = 0;
      for (std::size_t f = f0; f < f1; ++f) {
        const std::uint64_t kf = key_flat_[f];
        if (f == f0 || kf < key_flat_[f - 1])
          cursor = std::size_t(std::lower_bound(c.ki.begin(), c.ki.end(), kf) - c.ki.begin());
        while (cursor < c.ki.size() && c.ki[cursor] < kf) ++cursor;
        warm_first_[f] = std::uint32_t(cursor);
      }
    }
  }
  const std::ptrdiff_t m = std::ptrdiff_t(contacts.size());
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
  for (std::ptrdiff_t qc = 0; qc < m; ++qc) {
    Contact& ct = contacts[std::size_t(qc)];
    ct.pn = 0.0;
    ct.pt = Vec3::Zero();
    // Only resting and speculative contacts (target <= 0): an impact's impulse is its own, the
    // previous step's says nothing about it.
    if (ct.target > 0.0) continue;
    const bool wall = ct.i == kCollider;
    const std::uint32_t owner = wall ? ct.j : ct.i;
    const std::uint64_t ki = key[owner];
    const std::uint64_t kj = wall ? (kWall | ct.collider) : key[ct.j];
    // The particle's entries: in key order, those with its key (pairs, then collider contacts,
    // each in contact order); by place, those of its kind, the same ones in the same order (a
    // pair's kj never has the collider bit, so only one kind can match).
    std::size_t q = 0, end = c.ki.size();
    if (by_place) {
      const std::uint32_t k = prev_working_[perm_[owner]];
      const std::vector<std::uint32_t>& first = wall ? c.wall_first : c.pair_first;
      q = end = 0;  // none of this kind, or born since
      if (!first.empty() && k != kNone) {
        q = first[k];
        end = first[k + 1];
      }
    } else {
      q = warm_first_[perm_[owner]];
    }
    // A collider may give a particle several contacts: the one with the nearest normal.
    std::size_t best = c.ki.size();
    double best_dot = 0.99;
    for (; q < end && (by_place || c.ki[q] == ki); ++q) {
      if (c.kj[q] != kj) continue;
      const double dot = wall ? c.n[q].dot(ct.n) : 1.0;
      if (dot < best_dot) continue;
      best = q;
      best_dot = dot;
      if (!wall) break;
    }
    if (best == c.ki.size()) continue;
    ct.pn = c.pn[best];
    const Vec3 t = c.pt[best] - c.pt[best].dot(ct.n) * ct.n;  // onto the current tangent plane
    const double bound = ct.mu * ct.pn, len = t.norm();
    ct.pt = len > bound ? Vec3(t * (bound / len)) : t;
  }
}

void ParticleCollider::store_warm_start(WarmCache& c) {
  constexpr std::uint64_t kWall = std::uint64_t{1} << 63;
  // The resting contacts (pn > 0) in contact order: a stable pass that keeps them, split over
  // the threads for a large system (stable_counting_sort() with one bucket).
  const std::size_t n = key_flat_.size();
  const int par = threads > 1 && x.size() >= kParallelMin ? threads : 1;
  stable_counting_sort(
      contacts.size(), 1, par, sort_scratch_,
      [&](std::size_t q) { return contacts[q].pn > 0.0 ? std::size_t(0) : std::size_t(1); },
      [&](std::size_t m) {
        c.resize_entries(m);
        c.owner.resize(m);
      },
      [&](std::size_t q, std::size_t e) {
        const Contact& ct = contacts[q];
        const bool wall = ct.i == kCollider;
        const std::uint32_t owner = wall ? ct.j : ct.i;
        c.owner[e] = owner;
        c.ki[e] = key[owner];
        c.kj[e] = wall ? (kWall | ct.collider) : key[ct.j];
        c.n[e] = ct.n;
        c.pt[e] = ct.pt;
        c.pn[e] = ct.pn;
      });
  c.perm.assign(perm_.begin(), perm_.end());
  // The ranges, where each kind's owners ascend (the pairs come before the collider contacts).
  const std::size_t kept = c.ki.size();
  const std::size_t walls = std::size_t(
      std::partition_point(c.kj.begin(), c.kj.end(), [](std::uint64_t kj) { return (kj & kWall) == 0; }) -
      c.kj.begin());
  const auto ranges = [&](std::vector<std::uint32_t>& first, std::size_t e0, std::size_t e1, bool wall) {
    if (e0 == e1) {  // none of this kind: left empty
      first.clear();
      return true;
    }
    first.resize(n + 1);
    std::size_t k = 0;
    for (std::size_t e = e0; e < e1; ++e) {
      const std::size_t o = c.owner[e];
      // An owner before the last one, or an entry of the other kind in between.
      if (o + 1 < k || o >= n || ((c.kj[e] & kWall) != 0) != wall) return false;
      while (k <= o) first[k++] = std::uint32_t(e);
    }
    while (k <= n) first[k++] = std::uint32_t(e1);
    return true;
  };
  c.by_place = kept <= std::numeric_limits<std::uint32_t>::max() && ranges(c.pair_first, 0, walls, false) &&
               ranges(c.wall_first, walls, kept, true);
  // The flat keys are read no more this step, and run() writes every entry again: handed over
  // instead of copied.
  c.keys.swap(key_flat_);
}

void ParticleCollider::key_order(WarmCache& c, int parts, CountingSortScratch& scratch, WarmCache& tmp) {
  if (c.owner.empty()) {  // key order already (or no entries)
    c.perm.clear();
    c.keys.clear();
    c.pair_first.clear();
    c.wall_first.clear();
    c.by_place = false;
    return;
  }
  // Entries in the flat order of their particle (a stable counting sort: ties in contact order),
  // which is ascending key order unless systems' keys interleave.
  const std::size_t n = c.perm.size();
  stable_counting_sort(
      c.ki.size(), n, parts, scratch, [&](std::size_t e) { return std::size_t(c.perm[c.owner[e]]); },
      [&](std::size_t m) {
        tmp.resize_entries(m);
      },
      [&](std::size_t e, std::size_t r) {
        tmp.ki[r] = c.ki[e];
        tmp.kj[r] = c.kj[e];
        tmp.n[r] = c.n[e];
        tmp.pt[r] = c.pt[e];
        tmp.pn[r] = c.pn[e];
      });
  c.ki.swap(tmp.ki);
  c.kj.swap(tmp.kj);
  c.n.swap(tmp.n);
  c.pt.swap(tmp.pt);
  c.pn.swap(tmp.pn);
  c.owner.clear();
  c.perm.clear();
  c.keys.clear();
  c.pair_first.clear();
  c.wall_first.clear();
  c.by_place = false;
  if (std::is_sorted(c.ki.begin(), c.ki.end())) return;
  // Keys out of order (particles of several systems interleaved): sort by ki, ties in the order
  // above, so lookups stay deterministic.
  std::vector<std::size_t> order(c.ki.size());
  for (std::size_t q = 0; q < order.size(); ++q) order[q] = q;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return c.ki[a] < c.ki[b]; });
  WarmCache s;
  for (std::size_t q : order) {
    s.ki.push_back(c.ki[q]);
    s.kj.push_back(c.kj[q]);
    s.n.push_back(c.n[q]);
    s.pt.push_back(c.pt[q]);
    s.pn.push_back(c.pn[q]);
  }
  s.group = c.group;
  c = std::move(s);
}

}  // namespace simreel::sim::detail
