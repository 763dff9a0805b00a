// Particle–particle collisions: sequential impulses converging to the simultaneous-impulse
// solution of §3.6.2 with the pair response of §3.6.1, warm starting, position projection. The
// grid and the pair search (Coutinho §2.3.1) are in particle_pairs.cpp, the bands, the sweeps and
// the projection in particle_solve.cpp, the warm starts in particle_warm_start.cpp; here the step,
// sleep and the collider contacts.
#include "collision/particle_collisions.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <omp.h>

#include "core/vector_clones.hpp"
#include "particles/forces.hpp"  // kParallelMin

namespace simreel::sim::detail {


namespace {

/// a[order[k]] = a[k] for every k, through `tmp`; `threads` > 1 splits k (each element is
/// written once, so the result does not depend on it).
template <class T>
void unpermute(std::vector<T>& a, const std::vector<std::uint32_t>& order, std::vector<T>& tmp,
               int threads = 1) {
  tmp.resize(a.size());
  const std::ptrdiff_t n = std::ptrdiff_t(a.size());
#pragma omp parallel for schedule(static) num_threads(threads) if (threads > 1)
  for (std::ptrdiff_t k = 0; k < n; ++k) tmp[order[std::size_t(k)]] = a[std::size_t(k)];
  a.swap(tmp);
}

}  // namespace

void ParticleCollider::run(const std::vector<ParticleGroupMember>& members, double contact_speed,
                           double h, const std::vector<Collider>* colliders) {
  std::size_t n = 0;
  member_base_.clear();
  for (const auto& m : members) {
    member_base_.push_back(n);
    n += m.store->count;
  }
  x.resize(n);
  radius.resize(n);
  key_flat_.resize(n);
  flat_.resize(n);
  any_asleep_ = false;
  // Members alike in restitution, friction and colliding (always so for one): the pair search
  // and the collider contacts take those values from `surface_` and fill_working() does not
  // write them per particle. Only for this run(): direct calls use the arrays.
  surface_.uniform = uniform_surface && !members.empty();
  for (const auto& m : members)
    surface_.uniform = surface_.uniform && m.restitution == members[0].restitution &&
                       m.friction == members[0].friction && m.collide == members[0].collide;
  if (surface_.uniform) {
    surface_.restitution = members[0].restitution;
    surface_.friction = members[0].friction;
    surface_.collide = members[0].collide;
  }
  struct EndRun {  // every return of run()
    ParticleCollider& pc;
    ~EndRun() {
      pc.surface_.uniform = false;
      pc.sorted_radius_is_radius_ = false;
    }
  } end_run{*this};
  // Passes over particles or contacts that write each element once split over the threads for
  // a large system; the results do not depend on it.
  const int par = threads > 1 && n >= kParallelMin ? threads : 1;
  // In flat (member) order, what the grid needs (positions, radii) and the warm-start keys; the
  // other working arrays are filled once the grid has chosen their order (fill_working()).
  for (std::size_t mi = 0; mi < members.size(); ++mi) {
    const ParticleGroupMember& m = members[mi];
    ParticleStore& s = *m.store;
    if (s.track_rest && !m.sleep)  // sleep not allowed now: wake them all
      for (std::size_t i = 0; i < s.count; ++i) s.rest[4 * i + 3] = 0.0f;
    bool slept = false;
    const std::size_t base = member_base_[mi];
    const std::ptrdiff_t count = std::ptrdiff_t(s.count);
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1) reduction(|| : slept)
    for (std::ptrdiff_t ii = 0; ii < count; ++ii) {
      const std::size_t i = std::size_t(ii), k = base + i;
      const float* p = &s.position[3 * i];
      const float* u = &s.velocity[3 * i];
      x[k] = Vec3(p[0], p[1], p[2]);
      radius[k] = s.radius[i];
      const std::uint64_t key_k = (std::uint64_t(m.system) << 40) | s.id[i];
      key_flat_[k] = key_k;
      const bool asleep_k = m.sleep && s.rest[4 * i + 3] >= kSleepTime;
      slept = slept || asleep_k;
      flat_[k] = FlatParticle{{p[0], p[1], p[2]}, {u[0], u[1], u[2]}, s.mass[i], s.radius[i],
                              s.age[i], std::uint8_t(asleep_k ? 1 : 0), key_k};
    }
    any_asleep_ = any_asleep_ || slept;
  }
  x_before.clear();
  if (n < 2) return;
  // The resting threshold of §3.6.3 for pairs, with the g h one step of gravity adds left out
  // as collide()'s is_resting() does for colliders: a particle resting on one that a collider
  // (or sleep) held this step meets it at g h (16 cm/s at 60 Hz, over the contact speed), its
  // weight, not an impact to bounce from or to wake a sleeper with.
  double g = 0.0;
  for (const auto& m : members) g = std::max(g, m.gravity);
  const double pair_rest_speed = contact_speed + g * h;
  // The working arrays go into cell order, so that every later pass reads neighbours from
  // nearby memory; perm_ maps them back.
  contacts.clear();
  wall_vc.clear();
  sleeper_pairs_.clear();
  choose_cells(h);
  const bool reordered = levels == 1 && build_grid(false);
  if (reordered) {
    perm_.swap(order_);
    order_.resize(n);
    {
      const std::ptrdiff_t np = std::ptrdiff_t(n);
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
      for (std::ptrdiff_t q = 0; q < np; ++q) order_[std::size_t(q)] = std::uint32_t(q);
    }
    fill_working(members, h, par, true);
    find_pairs(pair_rest_speed, h);
  } else {
    perm_.resize(n);
    for (std::size_t q = 0; q < n; ++q) perm_[q] = std::uint32_t(q);
    fill_working(members, h, par, false);
    record_sleeper_pairs_ = any_asleep_;
    find_contacts_hashed(pair_rest_speed, h);
    record_sleeper_pairs_ = false;
  }
  grid_sorted_ = reordered;
  if (any_asleep_) wake_on_impact(pair_rest_speed, h);  // may add pairs
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
  solve_rows();  // v: before the solve; body_: after it
  if (cache != nullptr) store_warm_start(*cache);
  if (contacts.empty()) {  // nothing changed v
    if (any_asleep_) unpermute(asleep, perm_, tmp_byte_);
    update_rest(members, h, par);
    return;
  }
  // The position follows the change the contact impulses made to the velocity, taken as a
  // constant force over the step (x1 = x0 + dt v0 + dt² a / 2 in every integrator for a constant
  // acceleration): dt Δv / 2. A stack whose weight the solve cancels stays where it was instead
  // of sinking g h² / 2 per step into overlaps the projection must undo.
  {
    x_before.resize(n);
    const std::ptrdiff_t np = std::ptrdiff_t(n);
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
    for (std::ptrdiff_t q = 0; q < np; ++q) {
      const std::size_t u = std::size_t(q);
      const Vec3 after(body_[u].v[0], body_[u].v[1], body_[u].v[2]);
      x_before[u] = x[u];
      x[u] += half_dt_[u] * (after - v[u]);
      v[u] = after;
    }
  }
  project_positions(true);
  // Back to the members' particles, each working entry written to its own (x, v and x_before
  // stay in working order).
  {
    const std::ptrdiff_t np = std::ptrdiff_t(n);
    const bool one = members.size() == 1;
    if (one) {
      // The particles come in no order of their own (as in fill_working()): their lines are
      // asked for, for writing, some entries ahead, so that the stores' misses overlap.
      float* pos = members[0].store->position.data();
      float* vel = members[0].store->velocity.data();
      const std::uint32_t* perm = perm_.data();
      constexpr std::size_t kAhead = 16;
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
      for (std::ptrdiff_t qq = 0; qq < np; ++qq) {
        const std::size_t q = std::size_t(qq);
        if (q + kAhead < n) {
          const std::size_t f = 3 * std::size_t(perm[q + kAhead]);
          __builtin_prefetch(pos + f, 1);
          __builtin_prefetch(vel + f, 1);
        }
        const std::size_t i = 3 * std::size_t(perm[q]);
        for (std::size_t a = 0; a < 3; ++a) {
          pos[i + a] = float(x[q][a]);
          vel[i + a] = float(v[q][a]);
        }
      }
    } else {
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
      for (std::ptrdiff_t qq = 0; qq < np; ++qq) {
        const std::size_t q = std::size_t(qq);
        const auto [mi, i] = member_particle(std::uint32_t(q));
        ParticleStore& s = *members[mi].store;
        for (int a = 0; a < 3; ++a) {
          s.position[3 * i + std::size_t(a)] = float(x[q][a]);
          s.velocity[3 * i + std::size_t(a)] = float(v[q][a]);
        }
      }
    }
  }
  if (any_asleep_) unpermute(asleep, perm_, tmp_byte_, par);
  update_rest(members, h, par);
}

ParticleCollider::MemberParticle ParticleCollider::member_particle(std::uint32_t q) const {
  const std::size_t f = flat_index(q);
  const std::size_t mi =
      std::size_t(std::upper_bound(member_base_.begin(), member_base_.end(), f) - member_base_.begin()) - 1;
  return {mi, f - member_base_[mi]};
}

namespace {

/// fill_working()'s destinations, as plain pointers in a local value: the compiler keeps them
/// in registers instead of reloading each vector's data pointer after every store (a store
/// through a double* might, for all it knows, change the vectors themselves).
struct WorkingColumns {
  Vec3 *x, *v;
  double *inv_mass, *radius, *restitution, *friction, *half_dt, *inv_mass_awake;
  std::uint64_t* key;
  std::uint8_t *collides, *asleep;
  double *sx, *sy, *sz;  ///< null: no sorted grid copies
  // restitution, friction and collides null: not written (alike for all); inv_mass_awake
  // null: likewise (none sleeps)
};

/// One member's surface parameters, likewise hoisted.
struct MemberColumns {
  double restitution, friction;
  std::uint8_t collides;
  explicit MemberColumns(const ParticleGroupMember& m)
      : restitution(m.restitution), friction(m.friction), collides(m.collide ? 1 : 0) {}
};

/// Working entry q from the packed particle f of member m, h (s) the step.
__attribute__((always_inline)) inline void fill_entry(const WorkingColumns& o, const MemberColumns& m,
                                                      std::size_t q,
                                                      const ParticleCollider::FlatParticle& f,
                                                      double h) {
  const Vec3 x(f.x[0], f.x[1], f.x[2]);
  const double inv_mass = 1.0 / double(f.mass), radius = f.radius;
  const std::uint8_t asleep = f.asleep;
  o.x[q] = x;
  o.v[q] = Vec3(f.v[0], f.v[1], f.v[2]);
  o.inv_mass[q] = asleep != 0 ? 0.0 : inv_mass;
  o.radius[q] = radius;
  if (o.restitution != nullptr) {
    o.restitution[q] = m.restitution;
    o.friction[q] = m.friction;
    o.collides[q] = m.collides;
  }
  o.key[q] = f.key;
  o.half_dt[q] = 0.5 * std::min(double(f.age), h);
  o.asleep[q] = asleep;
  if (o.inv_mass_awake != nullptr) o.inv_mass_awake[q] = inv_mass;
  if (o.sx != nullptr) {  // the pair search's sorted copies (build_grid(false) left them)
    o.sx[q] = x[0];
    o.sy[q] = x[1];
    o.sz[q] = x[2];
  }
}

}  // namespace

void ParticleCollider::fill_working(const std::vector<ParticleGroupMember>& members, double h,
                                    int par, bool grid) {
  const std::size_t n = perm_.size();
  v.resize(n);
  inv_mass.resize(n);
  key.resize(n);
  half_dt_.resize(n);
  asleep.resize(n);
  // Each array written here is one more stream of stores per particle, and the pass is bound by
  // them (dropping four of fifteen made it a third faster): what the step does not read is
  // left out. The members' surface values when they are alike (surface_), the mass of the
  // awake when none sleeps (only wake_on_impact() reads it), and the pair search's sorted radii,
  // which are `radius` itself in cell order (sorted_radius_is_radius_).
  const bool surface = !surface_.uniform;
  if (surface) {
    restitution.resize(n);
    friction.resize(n);
    collides.resize(n);
  }
  if (any_asleep_) inv_mass_awake_.resize(n);
  sorted_radius_is_radius_ = grid;
  const WorkingColumns o{x.data(),
                         v.data(),
                         inv_mass.data(),
                         radius.data(),
                         surface ? restitution.data() : nullptr,
                         surface ? friction.data() : nullptr,
                         half_dt_.data(),
                         any_asleep_ ? inv_mass_awake_.data() : nullptr,
                         key.data(),
                         surface ? collides.data() : nullptr,
                         asleep.data(),
                         grid ? sx_.data() : nullptr,
                         grid ? sy_.data() : nullptr,
                         grid ? sz_.data() : nullptr};
  const std::uint32_t* perm = perm_.data();
  const FlatParticle* flat = flat_.data();
  // Each working entry read straight from its particle's packed line (one pass, not a flat fill
  // and then a permutation of every array).
  const std::ptrdiff_t np = std::ptrdiff_t(n);
  if (members.size() == 1) {
    const MemberColumns m(members[0]);
    constexpr std::size_t kAhead = 16;
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
    for (std::ptrdiff_t qq = 0; qq < np; ++qq) {
      const std::size_t q = std::size_t(qq);
      // The particles come in no order of their own: their lines are asked for some entries
      // ahead, so that the loads overlap instead of each missing in turn (a hint only).
      if (q + kAhead < n) __builtin_prefetch(flat + perm[q + kAhead]);
      fill_entry(o, m, q, flat[perm[q]], h);
    }
    return;
  }
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
  for (std::ptrdiff_t qq = 0; qq < np; ++qq) {
    const std::size_t q = std::size_t(qq);
    const std::size_t mi = member_particle(std::uint32_t(q)).member;
    fill_entry(o, MemberColumns(members[mi]), q, flat[perm[q]], h);
  }
}

void ParticleCollider::update_rest(const std::vector<ParticleGroupMember>& members, double h,
                                   int par) {
  // Flat order here (run() has written the particles and put `asleep` back). A particle slower
  // than the sleep speed after the solve, or that moved less than the sleep speed times the step
  // since the last step's end, adds the step to its time at rest; reaching kSleepTime it falls
  // asleep where it is, its velocity zeroed. Either reading alone misses a bead that does not
  // move: one caged by sleeping neighbours can keep a velocity that the solve leaves sliding
  // along two of them and the overlap projection takes back every step (it stands still while
  // its velocity reads 1-4 cm/s); one pressed between a neighbour and a mesh's facets can be
  // put back and forth by 50 um a step with a velocity of 1e-20 m/s. Both stayed awake for ever.
  // An awake particle's rest[0..2] (read only while asleep) hold its position at the end of the
  // last step for this test; while asleep, the position it sleeps at (the same place).
  const float reach = kSleepSpeed * float(h);
  std::size_t k = 0;
  for (const auto& m : members) {
    ParticleStore& s = *m.store;
    if (!s.track_rest || !m.sleep) {
      k += s.count;
      continue;
    }
    // Each particle's test reads and writes its own entries only: split over the threads.
    const std::size_t base = k;
    const std::ptrdiff_t count = std::ptrdiff_t(s.count);
    k += s.count;
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
    for (std::ptrdiff_t ii = 0; ii < count; ++ii) {
      const std::size_t i = std::size_t(ii);
      float* r = &s.rest[4 * i];
      if (asleep[base + i] != 0) continue;  // asleep all step: it did not move
      const float* x = &s.position[3 * i];
      const float* vf = &s.velocity[3 * i];
      const float dx = x[0] - r[0], dy = x[1] - r[1], dz = x[2] - r[2];
      for (std::size_t a = 0; a < 3; ++a) r[a] = x[a];
      const bool slow = vf[0] * vf[0] + vf[1] * vf[1] + vf[2] * vf[2] < kSleepSpeed * kSleepSpeed;
      if (!slow && !(dx * dx + dy * dy + dz * dz < reach * reach)) {
        r[3] = 0.0f;
        continue;
      }
      r[3] = std::min(kSleepTime, r[3] + float(h));
      if (r[3] < kSleepTime) continue;
      for (std::size_t a = 0; a < 3; ++a) s.velocity[3 * i + a] = 0.0f;
    }
  }
}

void ParticleCollider::wake_on_impact(double contact_speed, double h) {
  bool woke = false;
  woken_.clear();
  for (const Contact& c : contacts) {
    if (c.i == kCollider || (asleep[c.i] == 0) == (asleep[c.j] == 0)) continue;
    // Overlapping and approaching faster than the contact speed: an impact, not a resting
    // contact (§3.6.3).
    if (!(c.depth > 0.0) || !((v[c.j] - v[c.i]).dot(c.n) < -contact_speed)) continue;
    const std::uint32_t s = asleep[c.i] != 0 ? c.i : c.j;
    asleep[s] = 0;
    inv_mass[s] = inv_mass_awake_[s];
    if (grid_sorted_) woken_.push_back(s);
    woke = true;
  }
  if (!woke) return;
  if (grid_sorted_) {
    std::sort(woken_.begin(), woken_.end());
    find_sleeping_neighbours(woken_, h);
  }
  // A woken particle must rest on its sleeping neighbours this step already: without those
  // contacts it falls for a step, reaches them faster than the wake speed and wakes them in
  // turn, and the waking runs down through a settled pile. Its pairs go where the pair search
  // would have put them, so the contact order is the one of a search that had it awake.
  bool any = false;
  for (const SleeperPair& sp : sleeper_pairs_) any = any || asleep[sp.i] == 0 || asleep[sp.j] == 0;
  if (any) {
    tmp_contacts_.swap(contacts);
    contacts.clear();
    std::size_t q = 0;
    for (const SleeperPair& sp : sleeper_pairs_) {
      if (asleep[sp.i] != 0 && asleep[sp.j] != 0) continue;
      for (; q < sp.before; ++q) contacts.push_back(tmp_contacts_[q]);
      try_pair(sp.i, sp.j, sp.d2, contact_speed, h, contacts);
    }
    for (; q < tmp_contacts_.size(); ++q) contacts.push_back(tmp_contacts_[q]);
  }
  for (Contact& c : contacts)
    if (c.i != kCollider) c.m_eff = 1.0 / (inv_mass[c.i] + inv_mass[c.j]);
}

void ParticleCollider::find_collider_contacts(const std::vector<Collider>& colliders, double h,
                                              double contact_speed) {
  constexpr int kMaxPerCollider = 3;
  SurfaceContact found[kMaxPerCollider];
  for (std::size_t p = 0; p < x.size(); ++p) {
    if (surface_.uniform ? !surface_.collide : !collides.empty() && collides[p] == 0) continue;
    if (!asleep.empty() && asleep[p] != 0) continue;  // it does not move: nothing to hold
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
        const Vec3 vc = col.point_velocity(x[p] - (r + found[q].gap) * c.n);
        // Speculative while apart: the particle may still close the gap this step.
        c.target = found[q].gap > 0.0 ? -found[q].gap / h : 0.0;
        const Vec3 dv = v[p] - vc;
        const Vec3 vt = dv - dv.dot(c.n) * c.n;
        c.mu = act == HitAction::stick ? std::numeric_limits<double>::infinity()
               : vt.norm() <= contact_speed ? col.material.static_mu()
                                            : col.material.friction;
        contacts.push_back(c);
        wall_vc.push_back(vc);
      }
    }
  }
}

}  // namespace simreel::sim::detail
