// Cloth integration: implicit Euler after Baraff & Witkin 1998 (Coutinho Appendix B, the implicit
// Euler method for stiff systems) solved by conjugate gradients with a two-level preconditioner,
// and the explicit and semi-implicit Euler alternatives.
#include <algorithm>
#include <cmath>
#include <limits>

#include "cloth/cloth_state.hpp"
#include "core/vector_clones.hpp"

namespace simreel::sim {

namespace {

/// One CG step's element-wise work on vertices [i0, i1) (vectors as structures of arrays,
/// components `stride` apart): x += α d, r -= α Ap, z = P r (P: the inverse diagonal blocks,
/// 6 arrays xx xy xz yy yz zz), and the terms r_i · z_i and r_i · r_i of the next sums.
SIMREEL_VECTOR_CLONES
void cg_update(std::ptrdiff_t i0, std::ptrdiff_t i1, double alpha, std::ptrdiff_t st,
               double* __restrict x, double* __restrict r, double* __restrict z,
               const double* __restrict d, const double* __restrict Ap,
               const double* __restrict P, double* __restrict rz, double* __restrict rr) {
  for (std::ptrdiff_t i = i0; i < i1; ++i) {
    x[i] += alpha * d[i];
    x[st + i] += alpha * d[st + i];
    x[2 * st + i] += alpha * d[2 * st + i];
    const double rx = r[i] - alpha * Ap[i];
    const double ry = r[st + i] - alpha * Ap[st + i];
    const double rzc = r[2 * st + i] - alpha * Ap[2 * st + i];
    r[i] = rx;
    r[st + i] = ry;
    r[2 * st + i] = rzc;
    const double pxx = P[i], pxy = P[st + i], pxz = P[2 * st + i], pyy = P[3 * st + i],
                 pyz = P[4 * st + i], pzz = P[5 * st + i];
    const double zx = pxx * rx + pxy * ry + pxz * rzc;
    const double zy = pxy * rx + pyy * ry + pyz * rzc;
    const double zz = pxz * rx + pyz * ry + pzz * rzc;
    z[i] = zx;
    z[st + i] = zy;
    z[2 * st + i] = zz;
    rz[i] = rx * zx + ry * zy + rzc * zz;
    rr[i] = rx * rx + ry * ry + rzc * rzc;
  }
}

/// d = z + β d on vertices [i0, i1) (layout as cg_update).
SIMREEL_VECTOR_CLONES
void cg_direction(std::ptrdiff_t i0, std::ptrdiff_t i1, double beta, std::ptrdiff_t st,
                  const double* __restrict z, double* __restrict d) {
  for (std::ptrdiff_t i = i0; i < i1; ++i) {
    d[i] = z[i] + beta * d[i];
    d[st + i] = z[st + i] + beta * d[st + i];
    d[2 * st + i] = z[2 * st + i] + beta * d[2 * st + i];
  }
}

/// Σ a[0 .. n) in a fixed order that does not depend on the thread count or the CPU: eight
/// running sums over i mod 8, added pairwise at the end. A single running sum waits for each
/// addition to finish (four cycles a term), and the CG took three such sums per iteration.
SIMREEL_VECTOR_CLONES
double ordered_sum(const double* __restrict a, std::size_t n) {
  double lane[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8)
    for (std::size_t k = 0; k < 8; ++k) lane[k] += a[i + k];
  double tail = 0.0;
  for (; i < n; ++i) tail += a[i];
  const double low = (lane[0] + lane[1]) + (lane[2] + lane[3]);
  const double high = (lane[4] + lane[5]) + (lane[6] + lane[7]);
  return (low + high) + tail;
}

constexpr std::ptrdiff_t kChunk = 512;  // vertices per task of the parallel loops

}  // namespace

/// Linearised backward Euler (Baraff & Witkin 1998, eq. 6):
///   (M - h ∂f/∂v - h² ∂f/∂x) Δv = h (f0 + h ∂f/∂x v0),  v1 = v0 + Δv,  x1 = x0 + h v1,
/// solved by preconditioned conjugate gradients, matrix-free over the spring blocks (the matrix
/// is M + Σ_springs S ⊗ (graph Laplacian), S = h k_d nnᵀ + h² K): as a stencil for a grid cloth
/// (spring_stencil.hpp), spring by spring for a mesh cloth. The preconditioner is block Jacobi
/// plus, for cloths of at least CoarseSpace::kMinVertices free vertices, the additive coarse
/// correction of coarse_space.hpp (refactorised every step). The spring Jacobian
/// K = k_s (nnᵀ + max(0, 1 - L/l)(I - nnᵀ)) drops the transverse term of compressed springs so
/// the matrix stays positive definite (Choi & Ko 2002 make the same choice). Pinned vertices get
/// their velocity from their target; their Δv moves to the right-hand side. The CG's vectors are
/// structures of arrays (the stencil's layout) so its loops vectorise.
void Cloth::State::integrate_implicit(double h, double t1) {
  const ClothTopology& T = *topo;
  const std::size_t ns = T.spring_count();
  const double h2 = h * h;
  const double diag_m = vertex_mass * (1.0 + h * def.damping);
  const int th = threads;
  const bool par = parallel();
  const bool use_stencil = !stencil.empty();
  if (!coarse_built) {
    coarse.build(T, free);
    cg_vectors.assign(6 * 3 * stencil.stride(), 0.0);
    cg_precond.assign(2 * 6 * stencil.stride(), 0.0);
    free_mask.assign(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) free_mask[i] = free[i] ? 1.0 : 0.0;
    listed_springs.clear();
    if (use_stencil) {
      coarse.list_springs(listed_springs);
      for (const std::uint32_t c : pinned)
        for (std::uint32_t k = T.adj_start[c]; k < T.adj_start[c + 1]; ++k)
          listed_springs.push_back(T.adj_spring[k]);
      std::sort(listed_springs.begin(), listed_springs.end());
      listed_springs.erase(std::unique(listed_springs.begin(), listed_springs.end()),
                           listed_springs.end());
    }
    coarse_built = true;
  }
  if (use_stencil) {
    // The blocks and right-hand-side terms of every spring, vectorised by offset class
    // (spring_stencil.hpp); the few the coarse level and the pinned columns read one by one are
    // copied out.
    stencil.blocks(h, soa.data() + stencil.pad() + 3 * stencil.stride(), par ? th : 1);
    for (const std::uint32_t s : listed_springs) {
      S[s] = stencil.block(s);
      spring_length[s] = stencil.length(s);
    }
  }
  const std::size_t st = stencil.stride();
  const auto sst = std::ptrdiff_t(st);
  // The CG's vectors, each pointing at its x component's vertex 0 (padding before it).
  double* vec = cg_vectors.data() + stencil.pad();
  double* __restrict sol = vec;
  double* __restrict r = vec + 3 * st;
  double* __restrict z = vec + 6 * st;
  double* __restrict dir = vec + 9 * st;
  double* __restrict Ap = vec + 12 * st;
  double* __restrict b = vec + 15 * st;
  double* __restrict pc = cg_precond.data() + stencil.pad();
  double* __restrict dg = pc + 6 * st;  // each vertex's own block m' I + h aero_i
  auto put_sym = [st](double* u, std::size_t i, const Sym3& m) { m.store(u + i, st); };
  auto get = [st](const double* u, std::size_t i) { return Vec3(u[i], u[st + i], u[2 * st + i]); };
  auto put = [st](double* u, std::size_t i, const Vec3& w) {
    u[i] = w.x();
    u[st + i] = w.y();
    u[2 * st + i] = w.z();
  };
  // Raw pointers: the loops below write through them, and a vector member reloaded after every
  // store (aliasing) cost a fifth of the product's time.
  const std::uint32_t* __restrict sa = T.spring_a.data();
  const std::uint32_t* __restrict sb = T.spring_b.data();
  const std::uint32_t* __restrict adj_start = T.adj_start.data();
  const std::uint32_t* __restrict adj_spring = T.adj_spring.data();
  const double* __restrict len = spring_length.data();
  const std::uint8_t* __restrict fr = free.data();
  Sym3* __restrict Sp = S.data();
  Vec3* __restrict W = spring_work.data();
  const Sym3* __restrict aero = aero_active ? aero_damping.data() : nullptr;
  // Known Δv of the pinned vertices (from their targets); the free ones keep the previous step's
  // Δv as the CG warm start.
  for (const std::uint32_t i : pinned) dv[i] = (pin_target(i, t1) - x[i]) / h - v[i];
  if (use_stencil) {
    // Each vertex's own block and the stencil's sums (spring_stencil.hpp) with the forces in
    // the stencil's layout, where forces() left them (a triangle-list aerodynamics pass added to
    // f only: copied over); then the pinned columns move to the right-hand side (-A_ac Δv_c with
    // A_ac = -S), one pinned vertex at a time.
    double* __restrict fs = soa.data() + stencil.pad() + 6 * st;
    const bool copy_f = aero_active && !aero_grid;
#pragma omp parallel for schedule(static) num_threads(th) if (par)
    for (std::size_t i = 0; i < n; ++i) {
      Sym3 D{};
      D.add_diagonal(diag_m);
      if (aero != nullptr) D += aero[i].scaled(h);
      put_sym(dg, i, D);
      if (copy_f) put(fs, i, f[i]);
    }
    stencil.assemble(dg, free_mask.data(), h, fs, pc, b, par ? th : 1);
    for (const std::uint32_t c : pinned)
      for (std::uint32_t k = adj_start[c]; k < adj_start[c + 1]; ++k) {
        const std::uint32_t s = adj_spring[k];
        const std::uint32_t i = sa[s] == c ? sb[s] : sa[s];
        if (fr[i] && len[s] > 0.0) put(b, i, get(b, i) + Sp[s] * dv[c]);
      }
  } else {
    // Spring blocks and their share of the h² ∂f/∂x v0 term, one spring at a time ...
#pragma omp parallel for schedule(static) num_threads(th) if (par)
    for (std::size_t s = 0; s < ns; ++s) {
      const double l = len[s];  // from forces(), same x
      if (!(l > 0.0)) {
        Sp[s] = Sym3{};
        continue;
      }
      // S = h² K + h k_d uuᵀ = α uuᵀ + β I with K = (k - τ) uuᵀ + τ I (τ: the transverse
      // stiffness), and h² K (v_b - v_a) from the same two numbers.
      const Vec3& u = spring_dir[s];
      const double k = ks[s];
      const double transverse = k * std::max(0.0, 1.0 - T.rest_length[s] / l);
      const double along = h2 * (k - transverse), beta = h2 * transverse;
      Sym3 Ss = Sym3::outer(u, along + h * kds[s]);
      Ss.add_diagonal(beta);
      Sp[s] = Ss;
      const Vec3 dvs = v[sb[s]] - v[sa[s]];
      W[s] = (along * u.dot(dvs)) * u + beta * dvs;
    }
    // ... then gathered by each vertex over its springs in spring order: the same additions in
    // the same order as a scatter over the springs, so the result is that of one thread at any
    // count. The pinned columns move to the right-hand side (-A_ac Δv_c with A_ac = -S).
#pragma omp parallel for schedule(static) num_threads(th) if (par)
    for (std::size_t i = 0; i < n; ++i) {
      Sym3 P{};
      P.add_diagonal(diag_m);
      if (aero != nullptr) P += aero[i].scaled(h);
      put_sym(dg, i, P);
      if (!fr[i]) {
        put(b, i, Vec3::Zero());
        put_sym(pc, i, Sym3{});
        continue;
      }
      Vec3 bi = h * f[i];
      for (std::uint32_t k = adj_start[i]; k < adj_start[i + 1]; ++k) {
        const std::uint32_t s = adj_spring[k];
        if (!(len[s] > 0.0)) continue;
        const std::uint32_t a = sa[s], c = sb[s];
        if (a == i) {
          bi += W[s];
          P += Sp[s];
          if (!fr[c]) bi += Sp[s] * dv[c];
        } else {
          bi -= W[s];
          P += Sp[s];
          if (!fr[a]) bi += Sp[s] * dv[a];
        }
      }
      put(b, i, bi);
      put_sym(pc, i, P.inverse());
    }
  }
  double* __restrict pd = vertex_work.data();   // per-vertex terms of the sums, added in order
  double* __restrict pd2 = vertex_work2.data();
  // out = A y over the free vertices (zero at pinned ones), and pd[i] = y_i · (A y)_i.
  auto apply = [&](const double* y, double* out) {
    if (use_stencil) {
      stencil.apply(y, dg, free_mask.data(), out, pd, par ? th : 1);
    } else {
      // Springs first (W = S (y_a - y_c)), then each vertex gathers its springs in spring order.
#pragma omp parallel for schedule(static) num_threads(th) if (par)
      for (std::size_t s = 0; s < ns; ++s) W[s] = Sp[s] * Vec3(get(y, sa[s]) - get(y, sb[s]));
#pragma omp parallel for schedule(static) num_threads(th) if (par)
      for (std::size_t i = 0; i < n; ++i) {
        if (!fr[i]) {
          put(out, i, Vec3::Zero());
          pd[i] = 0.0;
          continue;
        }
        const Vec3 yi = get(y, i);
        Vec3 o(dg[i] * yi.x() + dg[st + i] * yi.y() + dg[2 * st + i] * yi.z(),
               dg[st + i] * yi.x() + dg[3 * st + i] * yi.y() + dg[4 * st + i] * yi.z(),
               dg[2 * st + i] * yi.x() + dg[4 * st + i] * yi.y() + dg[5 * st + i] * yi.z());
        for (std::uint32_t k = adj_start[i]; k < adj_start[i + 1]; ++k) {
          const std::uint32_t s = adj_spring[k];
          if (sa[s] == i) o += W[s];
          else o -= W[s];
        }
        put(out, i, o);
        pd[i] = yi.dot(o);
      }
    }
  };
  const std::ptrdiff_t chunks = (std::ptrdiff_t(n) + kChunk - 1) / kChunk;
  auto chunk_end = [&](std::ptrdiff_t k) { return std::min(std::ptrdiff_t(n), (k + 1) * kChunk); };
  // Preconditioned CG (block Jacobi plus the coarse level); every sum runs over per-vertex terms
  // in a fixed order (ordered_sum, or index order), so the thread count does not change it.
  const bool two_level = coarse.factorize(diag_m, aero, h, Sp, len);
  for (std::size_t i = 0; i < n; ++i) put(sol, i, fr[i] ? dv[i] : Vec3::Zero());
  apply(sol, Ap);
  double b2 = 0.0, rr = 0.0, rz = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 bi = get(b, i);
    const Vec3 ri = fr[i] ? Vec3(bi - get(Ap, i)) : Vec3::Zero();
    put(r, i, ri);
    const Vec3 zi(pc[i] * ri.x() + pc[st + i] * ri.y() + pc[2 * st + i] * ri.z(),
                  pc[st + i] * ri.x() + pc[3 * st + i] * ri.y() + pc[4 * st + i] * ri.z(),
                  pc[2 * st + i] * ri.x() + pc[4 * st + i] * ri.y() + pc[5 * st + i] * ri.z());
    put(z, i, zi);
    b2 += bi.squaredNorm();
    rr += ri.squaredNorm();
  }
  if (two_level) coarse.apply_add(r, z, st);
  for (std::size_t i = 0; i < n; ++i) rz += get(r, i).dot(get(z, i));
  const double tol2 = def.cg_tolerance * def.cg_tolerance * b2;
  for (std::size_t i = 0; i < n; ++i) put(dir, i, get(z, i));
  std::size_t it = 0;
  while (it < def.cg_max_iterations && rr > tol2) {
    apply(dir, Ap);
    const double pAp = ordered_sum(pd, n);
    if (!(pAp > 0.0)) break;
    const double alpha = rz / pAp;
#pragma omp parallel for schedule(static) num_threads(th) if (par)
    for (std::ptrdiff_t k = 0; k < chunks; ++k)
      cg_update(k * kChunk, chunk_end(k), alpha, sst, sol, r, z, dir, Ap, pc, pd, pd2);
    if (two_level) coarse.apply_add(r, z, st, pd);  // pd[i] = r_i · z_i, with the correction
    const double rz_new = ordered_sum(pd, n);
    rr = ordered_sum(pd2, n);
    const double beta = rz_new / rz;
    rz = rz_new;
#pragma omp parallel for schedule(static) num_threads(th) if (par)
    for (std::ptrdiff_t k = 0; k < chunks; ++k)
      cg_direction(k * kChunk, chunk_end(k), beta, sst, z, dir);
    ++it;
  }
  cg_iterations = it;
  for (std::size_t i = 0; i < n; ++i) {
    if (fr[i]) dv[i] = get(sol, i);
    v[i] += dv[i];
    x[i] += h * v[i];
    if (!fr[i]) x[i] = pin_target(i, t1);  // exact, whatever the rounding of x + h v
  }
}

void Cloth::State::integrate_explicit(double h, double t1, bool semi) {
  for (std::size_t i = 0; i < n; ++i) {
    if (!free[i]) {
      const Vec3 target = pin_target(i, t1);
      v[i] = (target - x[i]) / h;
      x[i] = target;
      continue;
    }
    const Vec3 a = f[i] / vertex_mass;
    if (semi) {
      v[i] += h * a;
      x[i] += h * v[i];
    } else {
      x[i] += h * v[i];
      v[i] += h * a;
    }
  }
}

}  // namespace simreel::sim
