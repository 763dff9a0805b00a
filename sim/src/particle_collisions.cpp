// Particle–particle collisions: hashed uniform grid (Coutinho §2.3.1) and sequential impulses
// converging to the simultaneous-impulse solution of §3.6.2 with the pair response of §3.6.1.
#include "particle_collisions.hpp"

#include <algorithm>
#include <cmath>

namespace simreel::sim::detail {

namespace {

std::uint32_t hash_cell(std::int64_t x, std::int64_t y, std::int64_t z, std::uint32_t mask) {
  // Teschner et al. 2003 spatial hash primes.
  const auto h = std::uint64_t(x) * 73856093ull ^ std::uint64_t(y) * 19349663ull ^
                 std::uint64_t(z) * 83492791ull;
  return std::uint32_t(h ^ (h >> 29)) & mask;
}

}  // namespace

void ParticleCollider::run(const std::vector<ParticleGroupMember>& members, double contact_speed) {
  std::size_t n = 0;
  for (const auto& m : members) n += m.store->count;
  x.resize(n);
  v.resize(n);
  inv_mass.resize(n);
  radius.resize(n);
  restitution.resize(n);
  friction.resize(n);
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
    }
  }
  x_before.clear();
  if (n < 2) return;
  find_contacts(contact_speed);
  if (contacts.empty()) return;
  solve();
  x_before = x;
  // Overlaps left by the discrete step are reduced without changing velocities (a fixed share
  // per step, split by inverse mass), in contact order.
  for (const Contact& c : contacts) {
    const Vec3 d = x[c.j] - x[c.i];
    const double dist = d.norm();
    const double depth = radius[c.i] + radius[c.j] - dist;
    if (!(depth > 0.0) || !(dist > 0.0)) continue;
    const Vec3 nn = d / dist;
    const double w = inv_mass[c.i] + inv_mass[c.j];
    const double corr = position_fraction * depth / w;
    x[c.i] -= corr * inv_mass[c.i] * nn;
    x[c.j] += corr * inv_mass[c.j] * nn;
  }
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

void ParticleCollider::find_contacts(double contact_speed) {
  contacts.clear();
  const std::size_t n = x.size();
  if (n < 2) return;
  double sum_r = 0.0, max_r = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    sum_r += radius[i];
    max_r = std::max(max_r, radius[i]);
  }
  cell_size = std::max(4.0 * sum_r / double(n), 2.0 * max_r);
  const double inv_cell = 1.0 / cell_size;
  std::uint32_t table = 1;
  while (table < 2 * n) table <<= 1;
  const std::uint32_t mask = table - 1;
  cell_xyz_.resize(3 * n);
  cell_hash_.resize(n);
  bucket_start_.assign(std::size_t(table) + 1, 0);
  sorted_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a)
      cell_xyz_[3 * i + std::size_t(a)] = std::int64_t(std::floor(x[i][a] * inv_cell));
    cell_hash_[i] = hash_cell(cell_xyz_[3 * i], cell_xyz_[3 * i + 1], cell_xyz_[3 * i + 2], mask);
    ++bucket_start_[cell_hash_[i] + 1];
  }
  for (std::uint32_t b = 0; b < table; ++b) bucket_start_[b + 1] += bucket_start_[b];
  // Counting sort, stable: each bucket lists its particles in ascending index.
  cursor_.assign(bucket_start_.begin(), bucket_start_.end() - 1);
  for (std::size_t i = 0; i < n; ++i) sorted_[cursor_[cell_hash_[i]]++] = std::uint32_t(i);
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t cx = cell_xyz_[3 * i], cy = cell_xyz_[3 * i + 1], cz = cell_xyz_[3 * i + 2];
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const std::int64_t nx = cx + dx, ny = cy + dy, nz = cz + dz;
          const std::uint32_t b = hash_cell(nx, ny, nz, mask);
          for (std::uint32_t q = bucket_start_[b]; q < bucket_start_[b + 1]; ++q) {
            const std::uint32_t j = sorted_[q];
            if (j <= i) continue;
            // Another cell hashed into the same bucket: it is visited from its own offset.
            if (cell_xyz_[3 * j] != nx || cell_xyz_[3 * j + 1] != ny || cell_xyz_[3 * j + 2] != nz)
              continue;
            const Vec3 d = x[j] - x[i];
            const double rr = radius[i] + radius[j];
            const double d2 = d.squaredNorm();
            if (!(d2 < rr * rr) || !(d2 > 0.0)) continue;
            const double dist = std::sqrt(d2);
            Contact c;
            c.i = std::uint32_t(i);
            c.j = j;
            c.n = d / dist;
            c.m_eff = 1.0 / (inv_mass[i] + inv_mass[j]);
            c.depth = rr - dist;
            const double vn = (v[j] - v[i]).dot(c.n);  // < 0: approaching
            const double e = 0.5 * (restitution[i] + restitution[j]);
            c.target = -vn > contact_speed ? -e * vn : 0.0;
            c.mu = 0.5 * (friction[i] + friction[j]);
            contacts.push_back(c);
          }
        }
  }
}

void ParticleCollider::solve() {
  for (Contact& c : contacts) {
    c.pn = 0.0;
    c.pt = Vec3::Zero();
  }
  for (int it = 0; it < iterations; ++it) {
    for (Contact& c : contacts) {
      const double wi = inv_mass[c.i], wj = inv_mass[c.j];
      Vec3 dv = v[c.j] - v[c.i];
      // Normal: accumulated impulse clamped to push only.
      const double vn = dv.dot(c.n);
      const double pn_new = std::max(0.0, c.pn + c.m_eff * (c.target - vn));
      const double dpn = pn_new - c.pn;
      c.pn = pn_new;
      v[c.i] -= (dpn * wi) * c.n;
      v[c.j] += (dpn * wj) * c.n;
      // Friction: cancel the relative sliding, within the Coulomb bound mu P_n.
      dv = v[c.j] - v[c.i];
      const Vec3 vt = dv - dv.dot(c.n) * c.n;
      Vec3 pt_new = c.pt - c.m_eff * vt;
      const double bound = c.mu * c.pn;
      const double len = pt_new.norm();
      if (len > bound) pt_new *= bound / len;
      const Vec3 dpt = pt_new - c.pt;
      c.pt = pt_new;
      v[c.i] -= wi * dpt;
      v[c.j] += wj * dpt;
    }
  }
}

}  // namespace simreel::sim::detail
