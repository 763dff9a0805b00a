// Cloth integration: implicit Euler after Baraff & Witkin 1998 (Coutinho Appendix B, the implicit
// Euler method for stiff systems) solved by conjugate gradients with a two-level preconditioner,
// and the explicit and semi-implicit Euler alternatives.
#include <algorithm>
#include <cmath>
#include <limits>

#include "cloth/cloth_state.hpp"

namespace simreel::sim {

/// Linearised backward Euler (Baraff & Witkin 1998, eq. 6):
///   (M - h ∂f/∂v - h² ∂f/∂x) Δv = h (f0 + h ∂f/∂x v0),  v1 = v0 + Δv,  x1 = x0 + h v1,
/// solved by preconditioned conjugate gradients, matrix-free over the spring blocks (the matrix
/// is M + Σ_springs S ⊗ (graph Laplacian), S = h k_d nnᵀ + h² K). The preconditioner is block
/// Jacobi plus, for cloths of at least CoarseSpace::kMinVertices free vertices, the additive
/// coarse correction of coarse_space.hpp (refactorised every step). The spring Jacobian
/// K = k_s (nnᵀ + max(0, 1 - L/l)(I - nnᵀ)) drops the transverse term of compressed springs so
/// the matrix stays positive definite (Choi & Ko 2002 make the same choice). Pinned vertices get
/// their velocity from their target; their Δv moves to the right-hand side.
void Cloth::State::integrate_implicit(double h, double t1) {
  const ClothTopology& T = *topo;
  const std::size_t ns = T.spring_count();
  const double h2 = h * h;
  const double diag_m = vertex_mass * (1.0 + h * def.damping);
  const int th = threads;
  const bool par = parallel();
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
  // Spring blocks and their share of the h² ∂f/∂x v0 term, one spring at a time ...
#pragma omp parallel for schedule(static) num_threads(th) if (par)
  for (std::size_t s = 0; s < ns; ++s) {
    const double l = len[s];  // from forces(), same x
    if (!(l > 0.0)) {
      Sp[s] = Sym3{};
      continue;
    }
    const Vec3& u = spring_dir[s];
    const double k = ks[s];
    const double transverse = k * std::max(0.0, 1.0 - T.rest_length[s] / l);
    Sym3 K = Sym3::outer(u, k - transverse);
    K.add_diagonal(transverse);  // k (nnᵀ + τ (I - nnᵀ))
    Sym3 Ss = K.scaled(h2);
    Ss += Sym3::outer(u, h * kds[s]);
    Sp[s] = Ss;
    W[s] = h2 * (K * (v[sb[s]] - v[sa[s]]));
  }
  // ... then gathered by each vertex over its springs in spring order: the same additions in the
  // same order as a scatter over the springs, so the result is that of one thread at any count.
  // The pinned columns move to the right-hand side (-A_ac Δv_c with A_ac = -S).
#pragma omp parallel for schedule(static) num_threads(th) if (par)
  for (std::size_t i = 0; i < n; ++i) {
    Sym3 P{};
    P.add_diagonal(diag_m);
    if (aero != nullptr) P += aero[i].scaled(h);
    if (!fr[i]) {
      b[i].setZero();
      precond[i] = Sym3{};
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
    b[i] = bi;
    precond[i] = P.inverse();
  }
  double* __restrict pd = vertex_work.data();   // per-vertex terms of the sums, added in order
  double* __restrict pd2 = vertex_work2.data();
  // out = A y over the free vertices (zero at pinned ones), and pd[i] = y_i · (A y)_i. Springs
  // first (W = S (y_a - y_c)), then each vertex gathers its springs in spring order (see above).
  auto apply = [&](const std::vector<Vec3>& yv, std::vector<Vec3>& outv) {
    const Vec3* __restrict y = yv.data();
    Vec3* __restrict out = outv.data();
#pragma omp parallel for schedule(static) num_threads(th) if (par)
    for (std::size_t s = 0; s < ns; ++s) W[s] = Sp[s] * Vec3(y[sa[s]] - y[sb[s]]);
#pragma omp parallel for schedule(static) num_threads(th) if (par)
    for (std::size_t i = 0; i < n; ++i) {
      if (!fr[i]) {
        out[i].setZero();
        pd[i] = 0.0;
        continue;
      }
      Vec3 o = aero != nullptr ? Vec3(diag_m * y[i] + h * (aero[i] * y[i])) : Vec3(diag_m * y[i]);
      for (std::uint32_t k = adj_start[i]; k < adj_start[i + 1]; ++k) {
        const std::uint32_t s = adj_spring[k];
        if (sa[s] == i) o += W[s];
        else o -= W[s];
      }
      out[i] = o;
      pd[i] = y[i].dot(o);
    }
  };
  // Preconditioned CG (block Jacobi plus the coarse level); every sum is taken over the vertices
  // in index order.
  if (!coarse_built) {
    coarse.build(T, free);
    coarse_built = true;
  }
  const bool two_level = coarse.factorize(diag_m, aero, h, Sp, len);
  std::vector<Vec3>& sol = p;
  for (std::size_t i = 0; i < n; ++i) sol[i] = fr[i] ? dv[i] : Vec3::Zero();
  apply(sol, Ap);
  double b2 = 0.0, rr = 0.0, rz = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    r[i] = fr[i] ? Vec3(b[i] - Ap[i]) : Vec3::Zero();
    z[i] = precond[i] * r[i];
    b2 += b[i].squaredNorm();
    rr += r[i].squaredNorm();
  }
  if (two_level) coarse.apply_add(r.data(), z.data());
  for (std::size_t i = 0; i < n; ++i) rz += r[i].dot(z[i]);
  const double tol2 = def.cg_tolerance * def.cg_tolerance * b2;
  std::vector<Vec3>& dir = b;  // b is no longer needed
  for (std::size_t i = 0; i < n; ++i) dir[i] = z[i];
  std::size_t it = 0;
  Vec3* __restrict solp = sol.data();
  Vec3* __restrict rp = r.data();
  Vec3* __restrict zp = z.data();
  Vec3* __restrict dp = dir.data();
  const Vec3* __restrict App = Ap.data();
  const Sym3* __restrict pc = precond.data();
  while (it < def.cg_max_iterations && rr > tol2) {
    apply(dir, Ap);
    double pAp = 0.0;
    for (std::size_t i = 0; i < n; ++i) pAp += pd[i];
    if (!(pAp > 0.0)) break;
    const double alpha = rz / pAp;
#pragma omp parallel for schedule(static) num_threads(th) if (par)
    for (std::size_t i = 0; i < n; ++i) {
      solp[i] += alpha * dp[i];
      rp[i] -= alpha * App[i];
      zp[i] = pc[i] * rp[i];
      pd[i] = rp[i].dot(zp[i]);
      pd2[i] = rp[i].squaredNorm();
    }
    if (two_level) coarse.apply_add(rp, zp, pd);  // pd[i] = r_i · z_i again, with the correction
    double rz_new = 0.0;
    rr = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      rz_new += pd[i];
      rr += pd2[i];
    }
    const double beta = rz_new / rz;
    rz = rz_new;
#pragma omp parallel for schedule(static) num_threads(th) if (par)
    for (std::size_t i = 0; i < n; ++i) dp[i] = zp[i] + beta * dp[i];
    ++it;
  }
  cg_iterations = it;
  for (std::size_t i = 0; i < n; ++i) {
    if (fr[i]) dv[i] = sol[i];
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
