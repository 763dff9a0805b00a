// The coarse level of the cloth solver's two-level preconditioner: plain aggregation over the
// spring graph (Vaněk, Mandel & Brezina 1996) and a sparse Cholesky solve of Pᵀ A P.
#include "cloth/coarse_space.hpp"

#include "core/vector_clones.hpp"

#include <algorithm>
#include <map>
#include <utility>

namespace simreel::sim::detail {

namespace {

/// Plain aggregation of a graph (CSR: node i's neighbours adj[start[i] .. start[i+1])) over the
/// nodes with mask[i] = 1, in node order (Vaněk, Mandel & Brezina 1996, phases 1-3). Writes each
/// node's aggregate to label (-1 outside the mask) and returns the aggregate count.
std::int32_t aggregate(const std::vector<std::uint32_t>& start, const std::vector<std::uint32_t>& adj,
                       const std::vector<std::uint8_t>& mask, std::vector<std::int32_t>& label) {
  const std::size_t n = mask.size();
  label.assign(n, -1);
  std::int32_t m = 0;
  // Phase 1: a node whose neighbours are all unaggregated seeds an aggregate of itself and them.
  for (std::size_t i = 0; i < n; ++i) {
    if (!mask[i] || label[i] >= 0) continue;
    bool clear = true;
    for (std::uint32_t k = start[i]; k < start[i + 1]; ++k) clear = clear && label[adj[k]] < 0;
    if (!clear) continue;
    label[i] = m;
    for (std::uint32_t k = start[i]; k < start[i + 1]; ++k) label[adj[k]] = m;
    ++m;
  }
  // Phase 2: a node left over joins the aggregate of its first aggregated neighbour (as phase 1
  // left them, so the joins do not chain).
  const std::vector<std::int32_t> seeded = label;
  for (std::size_t i = 0; i < n; ++i) {
    if (!mask[i] || seeded[i] >= 0) continue;
    for (std::uint32_t k = start[i]; k < start[i + 1] && label[i] < 0; ++k)
      if (seeded[adj[k]] >= 0) label[i] = seeded[adj[k]];
  }
  // Phase 3: what is still left (no aggregated neighbour) forms aggregates of its own.
  for (std::size_t i = 0; i < n; ++i) {
    if (!mask[i] || label[i] >= 0) continue;
    label[i] = m;
    for (std::uint32_t k = start[i]; k < start[i + 1]; ++k)
      if (label[adj[k]] < 0) label[adj[k]] = m;
    ++m;
  }
  return m;
}

}  // namespace

void CoarseSpace::build(const ClothTopology& T, const std::vector<std::uint8_t>& free) {
  n_ = T.vertex_count();
  aggregates_ = 0;
  ok_ = false;
  agg_.assign(n_, -1);
  const std::size_t n_free = std::size_t(std::count(free.begin(), free.end(), std::uint8_t(1)));
  if (n_free < kMinVertices) return;
  // The graph of the free vertices over the stretch springs (the mesh edges), in CSR form.
  std::vector<std::uint32_t> start(n_ + 1, 0), adj;
  for (std::size_t i = 0; i < n_; ++i) {
    if (free[i])
      for (std::uint32_t k = T.adj_start[i]; k < T.adj_start[i + 1]; ++k) {
        const std::uint32_t j = T.adj_other[k];
        if (free[j] && T.kind[T.adj_spring[k]] == SpringKind::stretch) adj.push_back(j);
      }
    start[i + 1] = std::uint32_t(adj.size());
  }
  std::int32_t m = aggregate(start, adj, free, agg_);  // crosses of ~5 vertices on a grid
  // The graph of those aggregates (an edge where a stretch spring joins two), aggregated again:
  // ~45 vertices per aggregate on a grid. Measured on the 64 x 64 peer scene (bench_cloth): one
  // aggregation over all springs (286 aggregates) took 9.8 CG iterations per step but its
  // factorisation and solves cost more than they saved; the stretch graph once (704), 7.5
  // iterations and slower still; twice (88), 14.4 iterations and the least time; three times
  // (128 x 128), slower than block Jacobi alone.
  std::vector<std::vector<std::uint32_t>> nb(static_cast<std::size_t>(m));
  for (std::size_t i = 0; i < n_; ++i) {
    if (agg_[i] < 0) continue;
    for (std::uint32_t k = start[i]; k < start[i + 1]; ++k) {
      const std::int32_t a = agg_[i], b = agg_[adj[k]];
      if (a != b) nb[std::size_t(a)].push_back(std::uint32_t(b));
    }
  }
  std::vector<std::uint32_t> coarse_start(std::size_t(m) + 1, 0), coarse_adj;
  for (std::size_t a = 0; a < std::size_t(m); ++a) {
    std::sort(nb[a].begin(), nb[a].end());
    nb[a].erase(std::unique(nb[a].begin(), nb[a].end()), nb[a].end());
    coarse_adj.insert(coarse_adj.end(), nb[a].begin(), nb[a].end());
    coarse_start[a + 1] = std::uint32_t(coarse_adj.size());
  }
  std::vector<std::int32_t> coarser;
  m = aggregate(coarse_start, coarse_adj, std::vector<std::uint8_t>(std::size_t(m), 1), coarser);
  for (std::size_t i = 0; i < n_; ++i)
    if (agg_[i] >= 0) agg_[i] = coarser[std::size_t(agg_[i])];
  aggregates_ = std::size_t(m);

  // Coarse pattern: a diagonal block per aggregate, an off-diagonal block per pair of
  // aggregates a spring joins (lower triangle: I > J).
  const std::size_t ns = T.spring_count();
  crossing_.clear();
  std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> off_index;
  std::vector<std::pair<std::int32_t, std::int32_t>> block_ij;
  for (std::int32_t a = 0; a < m; ++a) block_ij.emplace_back(a, a);
  for (std::size_t s = 0; s < ns; ++s) {
    const std::int32_t Ia = agg_[T.spring_a[s]], Ib = agg_[T.spring_b[s]];
    if (Ia == Ib) continue;  // inside one aggregate (S - S - S + S = 0), or both pinned
    Crossing c{std::uint32_t(s), Ia, Ib, -1};
    if (Ia >= 0 && Ib >= 0) {
      const auto key = std::make_pair(std::max(Ia, Ib), std::min(Ia, Ib));
      const auto [it, added] = off_index.emplace(key, std::int32_t(block_ij.size()));
      if (added) block_ij.push_back(key);
      c.off = it->second;
    }
    crossing_.push_back(c);
  }
  const auto N = Eigen::Index(3 * aggregates_);
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(9 * block_ij.size());
  for (const auto& [I, J] : block_ij)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        if (I != J || r >= c) entries.emplace_back(3 * I + r, 3 * J + c, 0.0);
  Ac_.resize(N, N);
  Ac_.setFromTriplets(entries.begin(), entries.end());
  Ac_.makeCompressed();
  blocks_.assign(block_ij.size(), Block{});
  sums_.assign(block_ij.size(), Sym3{});
  const auto offset = [&](Eigen::Index row, Eigen::Index col) {
    const int* first = Ac_.innerIndexPtr() + Ac_.outerIndexPtr()[col];
    const int* last = Ac_.innerIndexPtr() + Ac_.outerIndexPtr()[col + 1];
    return std::int32_t(std::lower_bound(first, last, int(row)) - Ac_.innerIndexPtr());
  };
  for (std::size_t k = 0; k < block_ij.size(); ++k) {
    const auto [I, J] = block_ij[k];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        blocks_[k].value[3 * r + c] = I != J || r >= c ? offset(3 * I + r, 3 * J + c) : -1;
  }
  llt_.analyzePattern(Ac_);
  // Pinned vertices point at a dummy aggregate past the last (its sums are discarded, its
  // correction is zero): the restriction and prolongation loops then have no branch.
  slot_.resize(n_);
  for (std::size_t i = 0; i < n_; ++i)
    slot_[i] = agg_[i] >= 0 ? 3 * agg_[i] : std::int32_t(N);
  rc_.setZero(N + 3);
  ec_.setZero(N);
  ex_.assign(std::size_t(N) + 3, 0.0);
}

void CoarseSpace::add(const Block& blk, const Sym3& s, double sign) {
  const double e[9] = {s.xx, s.xy, s.xz, s.xy, s.yy, s.yz, s.xz, s.yz, s.zz};
  double* val = Ac_.valuePtr();
  for (int k = 0; k < 9; ++k)
    if (blk.value[k] >= 0) val[blk.value[k]] += sign * e[k];
}

bool CoarseSpace::factorize(double diag_m, const Sym3* aero, double h, const Sym3* S,
                            const double* len) {
  if (empty()) return false;
  // Each block's terms summed as Sym3 first, then written to A_c once: the writes go through
  // the CSC offsets one entry at a time, and per vertex and spring they were most of this
  // function's time.
  std::fill(sums_.begin(), sums_.end(), Sym3{});
  for (std::size_t i = 0; i < n_; ++i) {
    if (agg_[i] < 0) continue;
    Sym3& d = sums_[std::size_t(agg_[i])];
    if (aero != nullptr) d += aero[i].scaled(h);
    d.add_diagonal(diag_m);
  }
  for (const Crossing& c : crossing_) {
    if (!(len[c.spring] > 0.0)) continue;
    const Sym3& b = S[c.spring];
    if (c.diag_a >= 0) sums_[std::size_t(c.diag_a)] += b;
    if (c.diag_b >= 0) sums_[std::size_t(c.diag_b)] += b;
    if (c.off >= 0) sums_[std::size_t(c.off)] += b;  // enters with a minus sign
  }
  std::fill(Ac_.valuePtr(), Ac_.valuePtr() + Ac_.nonZeros(), 0.0);
  for (std::size_t k = 0; k < blocks_.size(); ++k)
    add(blocks_[k], sums_[k], k < aggregates_ ? 1.0 : -1.0);
  llt_.factorize(Ac_);
  ok_ = llt_.info() == Eigen::Success;
  return ok_;
}

namespace {

/// z_i += e[slot_i .. slot_i + 2] (components `stride` apart), then rz_i = r_i · z_i if rz is
/// not null: the prolongation P e and the CG's terms of rᵀz, element-wise.
SIMREEL_VECTOR_CLONES
void prolong(std::size_t n, const std::int32_t* __restrict slot, const double* __restrict e,
             const double* __restrict r, double* __restrict z, std::size_t stride,
             double* __restrict rz) {
  const double *rx = r, *ry = r + stride, *rzc = r + 2 * stride;
  double *zx = z, *zy = z + stride, *zz = z + 2 * stride;
  for (std::size_t i = 0; i < n; ++i) {
    zx[i] += e[slot[i]];
    zy[i] += e[slot[i] + 1];
    zz[i] += e[slot[i] + 2];
  }
  if (rz != nullptr)
    for (std::size_t i = 0; i < n; ++i) rz[i] = rx[i] * zx[i] + ry[i] * zy[i] + rzc[i] * zz[i];
}

}  // namespace

void CoarseSpace::apply_add(const double* r, double* z, std::size_t stride, double* rz) {
  if (!ok_) return;
  const double *rx = r, *ry = r + stride, *rzc = r + 2 * stride;
  rc_.setZero();
  double* rc = rc_.data();
  for (std::size_t i = 0; i < n_; ++i) {
    const std::int32_t k = slot_[i];
    rc[k] += rx[i];
    rc[k + 1] += ry[i];
    rc[k + 2] += rzc[i];
  }
  const Eigen::Index N = ec_.size();
  ec_ = llt_.solve(rc_.head(N));
  std::copy(ec_.data(), ec_.data() + N, ex_.begin());  // ex_'s last 3 (the dummy) stay zero
  prolong(n_, slot_.data(), ex_.data(), r, z, stride, rz);
}

}  // namespace simreel::sim::detail
