// Particle–particle collisions: hashed uniform grid (Coutinho §2.3.1) and sequential impulses
// converging to the simultaneous-impulse solution of §3.6.2 with the pair response of §3.6.1.
#include "collision/particle_collisions.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include "core/state_io.hpp"
#include "core/vector_clones.hpp"
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

/// d2[k] = the squared distance from (xi, yi, zi) to candidate k when it is within reach
/// (ri + r_k + margin min(ri, r_k)) and not coincident, else 0; element-wise (the scalar
/// arithmetic in every lane), so the AVX2 clone gives the same bits.
SIMREEL_VECTOR_CLONES
void within_reach(double xi, double yi, double zi, double ri, double margin,
                  const double* __restrict cx, const double* __restrict cy,
                  const double* __restrict cz, const double* __restrict cr, std::size_t m,
                  double* __restrict d2) {
  for (std::size_t k = 0; k < m; ++k) {
    const double dx = cx[k] - xi, dy = cy[k] - yi, dz = cz[k] - zi;
    const double e = dx * dx + dy * dy + dz * dz;
    const double rj = cr[k];
    const double reach = ri + rj + margin * (rj < ri ? rj : ri);
    d2[k] = e < reach * reach && e > 0.0 ? e : 0.0;
  }
}

}  // namespace

namespace {

/// a[k] = a[order[k]] for every k, through `tmp`.
template <class T>
void permute(std::vector<T>& a, const std::vector<std::uint32_t>& order, std::vector<T>& tmp) {
  tmp.resize(a.size());
  for (std::size_t k = 0; k < a.size(); ++k) tmp[k] = a[order[k]];
  a.swap(tmp);
}

/// a[order[k]] = a[k] for every k (the inverse of permute), through `tmp`.
template <class T>
void unpermute(std::vector<T>& a, const std::vector<std::uint32_t>& order, std::vector<T>& tmp) {
  tmp.resize(a.size());
  for (std::size_t k = 0; k < a.size(); ++k) tmp[order[k]] = a[k];
  a.swap(tmp);
}

}  // namespace

void ParticleCollider::run(const std::vector<ParticleGroupMember>& members, double contact_speed,
                           double h, const std::vector<Collider>* colliders) {
  std::size_t n = 0;
  for (const auto& m : members) n += m.store->count;
  x.resize(n);
  v.resize(n);
  inv_mass.resize(n);
  radius.resize(n);
  restitution.resize(n);
  friction.resize(n);
  key.resize(n);
  collides.resize(n);
  half_dt_.resize(n);
  std::size_t k = 0;
  for (const auto& m : members) {
    const ParticleStore& s = *m.store;
    for (std::size_t i = 0; i < s.count; ++i, ++k) {
      x[k] = Vec3(s.position[3 * i], s.position[3 * i + 1], s.position[3 * i + 2]);
      v[k] = Vec3(s.velocity[3 * i], s.velocity[3 * i + 1], s.velocity[3 * i + 2]);
      inv_mass[k] = 1.0 / double(s.mass[i]);
      radius[k] = s.radius[i];
      restitution[k] = m.restitution;
      friction[k] = m.friction;
      key[k] = (std::uint64_t(m.system) << 40) | s.id[i];
      collides[k] = m.collide ? 1 : 0;
      half_dt_[k] = 0.5 * std::min(double(s.age[i]), h);
    }
  }
  x_before.clear();
  if (n < 2) return;
  key_flat_ = key;
  // The working arrays go into cell order, so that every later pass reads neighbours from
  // nearby memory; perm_ maps them back.
  contacts.clear();
  choose_cells(h);
  const bool reordered = levels == 1 && build_grid();
  if (reordered) {
    permute(x, order_, tmp3_);
    permute(v, order_, tmp3_);
    permute(inv_mass, order_, tmp1_);
    permute(radius, order_, tmp1_);
    permute(restitution, order_, tmp1_);
    permute(friction, order_, tmp1_);
    permute(half_dt_, order_, tmp1_);
    std::vector<std::uint64_t> tk;
    permute(key, order_, tk);
    std::vector<std::uint8_t> tc;
    permute(collides, order_, tc);
    perm_.swap(order_);
    order_.resize(n);
    for (std::size_t q = 0; q < n; ++q) order_[q] = std::uint32_t(q);
    find_pairs(contact_speed, h);
  } else {
    perm_.resize(n);
    for (std::size_t q = 0; q < n; ++q) perm_[q] = std::uint32_t(q);
    find_contacts_hashed(contact_speed, h);
  }
  const std::size_t pair_count = contacts.size();
  if (colliders != nullptr && !colliders->empty())
    find_collider_contacts(*colliders, h, contact_speed);
  bands_.clear();
  if (reordered) make_bands(pair_count);
  WarmCache* cache = nullptr;
  if (warm_start && !members.empty()) {
    for (WarmCache& c : caches_)
      if (c.group == members.front().system) cache = &c;
    if (cache == nullptr) {
      caches_.emplace_back();
      cache = &caches_.back();
      cache->group = members.front().system;
    }
    load_warm_start(*cache);
  }
  v_before_ = v;
  solve();
  if (cache != nullptr) store_warm_start(*cache);
  if (contacts.empty()) return;
  // The position follows the change the contact impulses made to the velocity, taken as a
  // constant force over the step (x1 = x0 + dt v0 + dt² a / 2 in every integrator for a constant
  // acceleration): dt Δv / 2. A stack whose weight the solve cancels stays where it was instead
  // of sinking g h² / 2 per step into overlaps the projection must undo.
  x_before = x;
  for (std::size_t q = 0; q < n; ++q) x[q] += half_dt_[q] * (v[q] - v_before_[q]);
  project_positions();
  // Back to flat order: x, v and x_before are indexed like the members' particles again.
  unpermute(x, perm_, tmp3_);
  unpermute(v, perm_, tmp3_);
  unpermute(x_before, perm_, tmp3_);
  k = 0;
  for (const auto& m : members) {
    ParticleStore& s = *m.store;
    for (std::size_t i = 0; i < s.count; ++i, ++k)
      for (int a = 0; a < 3; ++a) {
        s.position[3 * i + std::size_t(a)] = float(x[k][a]);
        s.velocity[3 * i + std::size_t(a)] = float(v[k][a]);
      }
  }
}

void ParticleCollider::find_collider_contacts(const std::vector<Collider>& colliders, double h,
                                              double contact_speed) {
  constexpr int kMaxPerCollider = 3;
  SurfaceContact found[kMaxPerCollider];
  for (std::size_t p = 0; p < x.size(); ++p) {
    if (!collides.empty() && collides[p] == 0) continue;
    const double r = radius[p];
    for (std::size_t ci = 0; ci < colliders.size(); ++ci) {
      const Collider& col = colliders[ci];
      const HitAction act = col.material.on_hit;
      if (act == HitAction::kill || act == HitAction::split) continue;  // the swept pass's job
      const int m = surface_contacts(col, x[p], r, margin_fraction * r, found, kMaxPerCollider);
      for (int q = 0; q < m; ++q) {
        Contact c;
        c.i = kCollider;
        c.j = std::uint32_t(p);
        c.collider = std::uint32_t(ci);
        c.n = found[q].normal;
        c.depth = -found[q].gap;
        c.m_eff = 1.0 / inv_mass[p];
        c.vc = col.point_velocity(x[p] - (r + found[q].gap) * c.n);
        // Speculative while apart: the particle may still close the gap this step.
        c.target = found[q].gap > 0.0 ? -found[q].gap / h : 0.0;
        const Vec3 dv = v[p] - c.vc;
        const Vec3 vt = dv - dv.dot(c.n) * c.n;
        c.mu = act == HitAction::stick ? std::numeric_limits<double>::infinity()
               : vt.norm() <= contact_speed ? col.material.static_mu()
                                            : col.material.friction;
        contacts.push_back(c);
      }
    }
  }
}

void ParticleCollider::remap_colliders(const std::vector<std::uint32_t>& new_index) {
  constexpr std::uint64_t kWall = std::uint64_t{1} << 63;
  for (WarmCache& c : caches_) {
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
    c.ki.resize(keep);
    c.kj.resize(keep);
    c.n.resize(keep);
    c.pt.resize(keep);
    c.pn.resize(keep);
  }
}

void ParticleCollider::save_warm(StateWriter& out) const {
  out.value(std::uint64_t(caches_.size()));
  for (const WarmCache& c : caches_) {
    out.value(c.group);
    out.array(c.ki);
    out.array(c.kj);
    out.array(c.n);
    out.array(c.pt);
    out.array(c.pn);
  }
}

void ParticleCollider::load_warm(StateReader& in) {
  const auto groups = in.value<std::uint64_t>();
  if (groups > (std::uint64_t{1} << 20)) throw StateError("state: too many particle contact groups");
  caches_.resize(std::size_t(groups));
  constexpr std::size_t kMax = std::size_t{1} << 40;
  for (WarmCache& c : caches_) {
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

void ParticleCollider::load_warm_start(const WarmCache& c) {
  constexpr std::uint64_t kWall = std::uint64_t{1} << 63;
  // The first cache entry of each particle's key, by a walk over the particles in flat order
  // (keys ascending within a system, systems in registration order), searching only where a key
  // goes back.
  const std::size_t n = key_flat_.size();
  warm_first_.resize(n);
  std::size_t cursor = 0;
  for (std::size_t f = 0; f < n; ++f) {
    const std::uint64_t kf = key_flat_[f];
    if (f > 0 && kf < key_flat_[f - 1])
      cursor = std::size_t(std::lower_bound(c.ki.begin(), c.ki.end(), kf) - c.ki.begin());
    while (cursor < c.ki.size() && c.ki[cursor] < kf) ++cursor;
    warm_first_[f] = std::uint32_t(cursor);
  }
  for (Contact& ct : contacts) {
    ct.pn = 0.0;
    ct.pt = Vec3::Zero();
    // Only resting and speculative contacts (target <= 0): an impact's impulse is its own, the
    // previous step's says nothing about it.
    if (ct.target > 0.0) continue;
    const bool wall = ct.i == kCollider;
    const std::uint32_t owner = wall ? ct.j : ct.i;
    const std::uint64_t ki = key[owner];
    const std::uint64_t kj = wall ? (kWall | ct.collider) : key[ct.j];
    // A collider may give a particle several contacts: the one with the nearest normal.
    std::size_t best = c.ki.size();
    double best_dot = 0.99;
    for (std::size_t q = warm_first_[perm_[owner]]; q < c.ki.size() && c.ki[q] == ki; ++q) {
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
  // Entries in the flat order of their first particle (a stable counting sort; ties in contact
  // order), which is ascending key order unless systems' keys interleave.
  const std::size_t n = key_flat_.size();
  count_.assign(n + 1, 0);
  std::size_t m = 0;
  for (const Contact& ct : contacts) {
    if (!(ct.pn > 0.0)) continue;
    ++count_[perm_[ct.i == kCollider ? ct.j : ct.i] + 1];
    ++m;
  }
  for (std::size_t f = 0; f < n; ++f) count_[f + 1] += count_[f];
  c.ki.resize(m);
  c.kj.resize(m);
  c.n.resize(m);
  c.pt.resize(m);
  c.pn.resize(m);
  for (const Contact& ct : contacts) {
    if (!(ct.pn > 0.0)) continue;
    const bool wall = ct.i == kCollider;
    const std::uint32_t owner = wall ? ct.j : ct.i;
    const std::size_t q = count_[perm_[owner]]++;
    c.ki[q] = key[owner];
    c.kj[q] = wall ? (kWall | ct.collider) : key[ct.j];
    c.n[q] = ct.n;
    c.pt[q] = ct.pt;
    c.pn[q] = ct.pn;
  }
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

void ParticleCollider::choose_cells(double h) {
  const std::size_t n = x.size();
  double sum_r = 0.0, max_r = 0.0, min_r = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    sum_r += radius[i];
    max_r = std::max(max_r, radius[i]);
    min_r = std::min(min_r, radius[i]);
  }
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
  bands_.clear();
  if (x.size() < 2) return;
  choose_cells(h);
  if (levels == 1 && build_grid()) {
    find_pairs(contact_speed, h);
  } else {
    find_contacts_hashed(contact_speed, h);
  }
}

bool ParticleCollider::build_grid() {
  const std::size_t n = x.size();
  const double inv = 1.0 / cell_size;
  Vec3 lo = x[0];
  for (std::size_t i = 1; i < n; ++i) lo = lo.cwiseMin(x[i]);
  // Cell coordinates from 1 (a neighbour at -1 stays >= 0), and one spare cell past the largest.
  constexpr double kMaxCells = double(1 << 21);
  std::int64_t dim[3] = {0, 0, 0};
  cell_key_.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      const double c = std::floor((x[i][a] - lo[a]) * inv) + 1.0;
      if (!(c < kMaxCells - 2.0)) return false;  // too wide for 21 bits (or not finite)
      dim[a] = std::max(dim[a], std::int64_t(c) + 2);
    }
  stride_y_ = std::uint64_t(dim[2]);
  stride_x_ = std::uint64_t(dim[1]) * stride_y_;
  cells_x_ = std::uint64_t(dim[0]);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = [&](int a) { return std::uint64_t(std::floor((x[i][a] - lo[a]) * inv) + 1.0); };
    cell_key_[i] = c(0) * stride_x_ + c(1) * stride_y_ + c(2);
  }
  // Particles by (cell key, index): a counting sort when the box has few cells per particle,
  // else a comparison sort of the same keys (the same order either way).
  order_.resize(n);
  const std::uint64_t cells = std::uint64_t(dim[0]) * stride_x_;
  if (cells <= 4 * std::uint64_t(n) + 4096) {
    count_.assign(std::size_t(cells) + 1, 0);
    for (std::size_t i = 0; i < n; ++i) ++count_[std::size_t(cell_key_[i]) + 1];
    for (std::size_t c = 0; c < cells; ++c) count_[c + 1] += count_[c];
    for (std::size_t i = 0; i < n; ++i) order_[count_[std::size_t(cell_key_[i])]++] = std::uint32_t(i);
  } else {
    for (std::size_t i = 0; i < n; ++i) order_[i] = std::uint32_t(i);
    std::sort(order_.begin(), order_.end(), [&](std::uint32_t p, std::uint32_t q) {
      return cell_key_[p] != cell_key_[q] ? cell_key_[p] < cell_key_[q] : p < q;
    });
  }
  sx_.resize(n);
  sy_.resize(n);
  sz_.resize(n);
  sr_.resize(n);
  occupied_.clear();
  cell_first_.clear();
  for (std::size_t s = 0; s < n; ++s) {
    const std::uint32_t i = order_[s];
    sx_[s] = x[i][0];
    sy_[s] = x[i][1];
    sz_[s] = x[i][2];
    sr_[s] = radius[i];
    if (s == 0 || cell_key_[i] != occupied_.back()) {
      occupied_.push_back(cell_key_[i]);
      cell_first_.push_back(std::uint32_t(s));
    }
  }
  cell_first_.push_back(std::uint32_t(n));
  return true;
}

void ParticleCollider::try_pair(std::uint32_t i, std::uint32_t j, double d2,
                                double contact_speed, double h) {
  const Vec3 d = x[j] - x[i];
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
  const double e = 0.5 * (restitution[i] + restitution[j]);
  c.target = dist >= rr ? -(dist - rr) / h : -vn > contact_speed ? -e * vn : 0.0;
  c.mu = 0.5 * (friction[i] + friction[j]);
  contacts.push_back(c);
}

void ParticleCollider::find_pairs(double contact_speed, double h) {
  const double margin = h > 0.0 ? pair_margin_fraction : 0.0;
  const std::size_t cells = occupied_.size();
  const std::uint64_t* key_of = occupied_.data();
  const std::uint32_t* first = cell_first_.data();
  const double *px = sx_.data(), *py = sy_.data(), *pz = sz_.data(), *pr = sr_.data();
  // Half stencil: the cell itself (later particles) and the cell above it (z + 1), then the
  // columns (dx, dy) = (0, 1), (1, -1), (1, 0), (1, 1), three cells each (z - 1 .. z + 1), all
  // later in key order. Cells are visited in key order, so each column's first occupied cell
  // only moves forward: a cursor per column instead of a search.
  const std::uint64_t off[4] = {stride_y_, stride_x_ - stride_y_, stride_x_, stride_x_ + stride_y_};
  std::size_t cursor[4] = {0, 0, 0, 0};
  std::uint32_t run_b[5], run_e[5];
  for (std::size_t c = 0; c < cells; ++c) {
    const std::uint64_t kc = key_of[c];
    run_b[0] = first[c];
    run_e[0] = c + 1 < cells && key_of[c + 1] == kc + 1 ? first[c + 2] : first[c + 1];
    for (int col = 0; col < 4; ++col) {
      const std::uint64_t lo = kc + off[col] - 1, hi = kc + off[col] + 1;
      std::size_t& cur = cursor[col];
      while (cur < cells && key_of[cur] < lo) ++cur;
      std::size_t end = cur;
      while (end < cells && key_of[end] <= hi) ++end;
      run_b[col + 1] = first[cur];
      run_e[col + 1] = first[end];
    }
    // The cell's candidates: its own run (the cell and the one above), then the four columns.
    // Particle si of the cell takes those after its own position, in the same order as a loop
    // over the runs: one vectorised pass for distances and reaches, a branch-free compaction of
    // the pairs within reach, then try_pair() in order.
    std::size_t m = 0;
    for (int col = 0; col < 5; ++col) m += run_e[col] - run_b[col];
    if (cand_s_.size() < m) {
      cand_s_.resize(m);
      cand_keep_.resize(m);
      for (auto* a : {&cand_x_, &cand_y_, &cand_z_, &cand_r_, &cand_d2_}) a->resize(m);
    }
    std::size_t k = 0;
    for (int col = 0; col < 5; ++col)
      for (std::uint32_t sj = run_b[col]; sj < run_e[col]; ++sj, ++k) {
        cand_s_[k] = sj;
        cand_x_[k] = px[sj];
        cand_y_[k] = py[sj];
        cand_z_[k] = pz[sj];
        cand_r_[k] = pr[sj];
      }
    for (std::uint32_t si = first[c]; si < first[c + 1]; ++si) {
      const std::size_t from = si + 1 - first[c];
      within_reach(px[si], py[si], pz[si], pr[si], margin, cand_x_.data() + from,
                   cand_y_.data() + from, cand_z_.data() + from, cand_r_.data() + from, m - from,
                   cand_d2_.data() + from);
      std::size_t kept = 0;
      for (std::size_t q = from; q < m; ++q) {
        cand_keep_[kept] = std::uint32_t(q);
        kept += std::size_t(cand_d2_[q] > 0.0);
      }
      for (std::size_t u = 0; u < kept; ++u) {
        const std::size_t q = cand_keep_[u];
        try_pair(order_[si], order_[cand_s_[q]], cand_d2_[q], contact_speed, h);
      }
    }
  }
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
              try_pair(std::uint32_t(i), j, d2, contact_speed, h);
            }
          }
    }
  }
}

void ParticleCollider::make_bands(std::size_t pair_count) {
  // Band width in columns: about 64 bands over the particles' extent (at least one column) for
  // a system large enough to be solved in parallel; one band (the plain sweep in cell order)
  // below that, which keeps piles of a few thousand particles as quiet as the sequential order
  // (bands two apart are not coupled within a sweep, so an impulse crosses a pile more slowly).
  // The choice depends on the particle count only, never on the thread count.
  const std::uint64_t width =
      x.size() >= kParallelMin ? std::max<std::uint64_t>(1, (cells_x_ + 63) / 64) : cells_x_;
  const std::size_t nb = std::size_t((cells_x_ + width - 1) / width);
  // Sorted position -> band: the column of its cell (cell keys are x-major).
  const auto band_of = [&](std::uint32_t s) {
    return std::size_t(cell_key_[perm_[s]] / stride_x_ / width);
  };
  bands_.assign(nb, Band{0, 0, 0, 0});
  std::size_t b = 0;
  for (std::size_t q = 0; q <= pair_count; ++q) {
    const std::size_t bq = q < pair_count ? band_of(contacts[q].i) : nb;
    for (; b < bq; ++b) {
      bands_[b].pair_end = std::uint32_t(q);
      if (b + 1 < nb) bands_[b + 1].pair_begin = std::uint32_t(q);
    }
  }
  b = 0;
  for (std::size_t q = pair_count; q <= contacts.size(); ++q) {
    const std::size_t bq = q < contacts.size() ? band_of(contacts[q].j) : nb;
    if (q == pair_count) bands_[0].wall_begin = std::uint32_t(q);
    for (; b < bq; ++b) {
      bands_[b].wall_end = std::uint32_t(q);
      if (b + 1 < nb) bands_[b + 1].wall_begin = std::uint32_t(q);
    }
  }
}

void ParticleCollider::solve() {
  for (Contact& c : contacts) {
    const Vec3 p = c.pn * c.n + c.pt;
    if (c.i != kCollider) v[c.i] -= inv_mass[c.i] * p;
    v[c.j] += inv_mass[c.j] * p;
  }
  // One contact's update; `wall` as a template parameter keeps the branches out of the loop.
  const auto update = [&](Contact& c, auto wall_tag) __attribute__((always_inline)) {
    constexpr bool wall = decltype(wall_tag)::value;
    const double wi = wall ? 0.0 : inv_mass[c.i], wj = inv_mass[c.j];
    Vec3 dv = v[c.j] - (wall ? c.vc : v[c.i]);
    // Normal: accumulated impulse clamped to push only.
    const double vn = dv.dot(c.n);
    const double pn_new = std::max(0.0, c.pn + c.m_eff * (c.target - vn));
    const double dpn = pn_new - c.pn;
    c.pn = pn_new;
    if (!wall) v[c.i] -= (dpn * wi) * c.n;
    v[c.j] += (dpn * wj) * c.n;
    // Friction: cancel the relative sliding, within the Coulomb bound mu P_n.
    dv = v[c.j] - (wall ? c.vc : v[c.i]);
    const Vec3 vt = dv - dv.dot(c.n) * c.n;
    Vec3 pt_new = c.pt - c.m_eff * vt;
    const double bound = c.mu * c.pn;
    const double len = pt_new.norm();
    if (len > bound) pt_new *= bound / len;
    const Vec3 dpt = pt_new - c.pt;
    c.pt = pt_new;
    if (!wall) v[c.i] -= wi * dpt;
    v[c.j] += wj * dpt;
  };
  const auto sweep = [&](std::size_t begin, std::size_t end) __attribute__((always_inline)) {
    for (std::size_t q = begin; q < end; ++q) {
      Contact& c = contacts[q];
      if (c.i == kCollider) {
        update(c, std::true_type{});
      } else {
        update(c, std::false_type{});
      }
    }
  };
  if (bands_.empty()) {
    for (int it = 0; it < iterations; ++it) sweep(0, contacts.size());
    return;
  }
  const int nb = int(bands_.size());
  // Two sweeps of bands per iteration, each a fork and a barrier: only for large systems.
  const bool par = threads > 1 && x.size() >= kParallelMin;
  // Pairs of the even bands, of the odd bands, then every collider contact (one particle each:
  // the bands' are independent of each other).
  for (int it = 0; it < iterations; ++it) {
    for (int phase = 0; phase < 2; ++phase) {
#pragma omp parallel for schedule(static) num_threads(threads) if (par)
      for (int b = phase; b < nb; b += 2)
        sweep(bands_[std::size_t(b)].pair_begin, bands_[std::size_t(b)].pair_end);
    }
#pragma omp parallel for schedule(static) num_threads(threads) if (par)
    for (int b = 0; b < nb; ++b)
      sweep(bands_[std::size_t(b)].wall_begin, bands_[std::size_t(b)].wall_end);
  }
}

void ParticleCollider::project_positions() {
  if (x_before.size() != x.size()) x_before = x;
  for (int it = 0; it < position_iterations; ++it) {
    for (const Contact& c : contacts) {
      const bool wall = c.i == kCollider;
      double slop = 0.0, depth = 0.0;
      Vec3 nn = c.n;
      if (wall) {
        // The surface as the plane of its closest feature at the start of the projection.
        depth = c.depth - c.n.dot(x[c.j] - x_before[c.j]);
      } else {
        const Vec3 d = x[c.j] - x[c.i];
        const double dist = d.norm();
        if (!(dist > 0.0)) continue;
        nn = d / dist;
        depth = radius[c.i] + radius[c.j] - dist;
        slop = slop_fraction * std::min(radius[c.i], radius[c.j]);
      }
      // Each contact aims at the same end depth in every sweep, so the sweeps converge to it.
      // A collider contact may close its gap (goal 0) but not go deeper.
      const double goal = wall ? (c.depth > 0.0 ? (1.0 - position_fraction) * c.depth : 0.0)
                               : c.depth - position_fraction * std::max(0.0, c.depth - slop);
      if (!(depth > goal)) continue;
      const double wi = wall ? 0.0 : inv_mass[c.i], wj = inv_mass[c.j];
      const double corr = (depth - goal) / (wi + wj);
      if (!wall) x[c.i] -= corr * wi * nn;
      x[c.j] += corr * wj * nn;
    }
  }
}

}  // namespace simreel::sim::detail
