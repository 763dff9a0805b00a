// Cloth integration: implicit Euler after Baraff & Witkin 1998 (Coutinho Appendix B, the implicit
// Euler method for stiff systems) solved by preconditioned conjugate gradients, and the explicit
// and semi-implicit Euler alternatives.
#include <algorithm>
#include <cmath>
#include <limits>

#include "cloth/cloth_state.hpp"

namespace simreel::sim {

/// Linearised backward Euler (Baraff & Witkin 1998, eq. 6):
///   (M - h ∂f/∂v - h² ∂f/∂x) Δv = h (f0 + h ∂f/∂x v0),  v1 = v0 + Δv,  x1 = x0 + h v1,
/// solved by preconditioned conjugate gradients, matrix-free over the spring blocks (the matrix
/// is M + Σ_springs S ⊗ (graph Laplacian), S = h k_d nnᵀ + h² K). The spring Jacobian
/// K = k_s (nnᵀ + max(0, 1 - L/l)(I - nnᵀ)) drops the transverse term of compressed springs so
/// the matrix stays positive definite (Choi & Ko 2002 make the same choice). Pinned vertices get
/// their velocity from their target; their Δv moves to the right-hand side.
void Cloth::State::integrate_implicit(double h, double t1) {
  const ClothTopology& T = *topo;
  const std::size_t ns = T.spring_count();
  const double h2 = h * h;
  const double diag_m = vertex_mass * (1.0 + h * def.damping);
  // Known Δv of the pinned vertices (from their targets); the free ones keep the previous step's
  // Δv as the CG warm start.
  for (std::size_t i = 0; i < n; ++i) {
    b[i] = h * f[i];
    precond[i] = Sym3{};
    precond[i].add_diagonal(diag_m);
    if (aero_active) precond[i] += aero_damping[i].scaled(h);
  }
  for (const std::uint32_t i : pinned) {
    dv[i] = (pin_target(i, t1) - x[i]) / h - v[i];
    b[i].setZero();
  }
  // Spring blocks, the h² ∂f/∂x v0 term and the pinned columns moved to the right-hand side.
  for (std::size_t s = 0; s < ns; ++s) {
    const std::uint32_t a = T.spring_a[s], c = T.spring_b[s];
    const double l = spring_length[s];  // from forces(), same x
    if (!(l > 0.0)) {
      S[s] = Sym3{};
      continue;
    }
    const Vec3& u = spring_dir[s];
    const double k = ks[s];
    const double transverse = k * std::max(0.0, 1.0 - T.rest_length[s] / l);
    Sym3 K = Sym3::outer(u, k - transverse);
    K.add_diagonal(transverse);  // k (nnᵀ + τ (I - nnᵀ))
    Sym3 Ss = K.scaled(h2);
    Ss += Sym3::outer(u, h * kds[s]);
    S[s] = Ss;
    const Vec3 w = h2 * (K * (v[c] - v[a]));
    if (free[a]) {
      b[a] += w;
      precond[a] += Ss;
      if (!free[c]) b[a] += Ss * dv[c];  // -A_ac Δv_c with A_ac = -S
    }
    if (free[c]) {
      b[c] -= w;
      precond[c] += Ss;
      if (!free[a]) b[c] += Ss * dv[a];
    }
  }
  for (std::size_t i = 0; i < n; ++i) precond[i] = free[i] ? precond[i].inverse() : Sym3{};
  // y -> A y over the free vertices; y and the result are zero at pinned vertices.
  auto apply = [&](const std::vector<Vec3>& y, std::vector<Vec3>& out) {
    if (aero_active)
      for (std::size_t i = 0; i < n; ++i) out[i] = diag_m * y[i] + h * (aero_damping[i] * y[i]);
    else
      for (std::size_t i = 0; i < n; ++i) out[i] = diag_m * y[i];
    for (std::size_t s = 0; s < ns; ++s) {
      const std::uint32_t a = T.spring_a[s], c = T.spring_b[s];
      const Vec3 w = S[s] * Vec3(y[a] - y[c]);
      out[a] += w;
      out[c] -= w;
    }
    for (const std::uint32_t i : pinned) out[i].setZero();
  };
  // Preconditioned CG (block Jacobi), fixed summation order.
  std::vector<Vec3>& sol = p;
  for (std::size_t i = 0; i < n; ++i) sol[i] = free[i] ? dv[i] : Vec3::Zero();
  apply(sol, Ap);
  double b2 = 0.0, rr = 0.0, rz = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    r[i] = free[i] ? Vec3(b[i] - Ap[i]) : Vec3::Zero();
    z[i] = precond[i] * r[i];
    b2 += b[i].squaredNorm();
    rr += r[i].squaredNorm();
    rz += r[i].dot(z[i]);
  }
  const double tol2 = def.cg_tolerance * def.cg_tolerance * b2;
  std::vector<Vec3>& dir = b;  // b is no longer needed
  for (std::size_t i = 0; i < n; ++i) dir[i] = z[i];
  std::size_t it = 0;
  while (it < def.cg_max_iterations && rr > tol2) {
    apply(dir, Ap);
    double pAp = 0.0;
    for (std::size_t i = 0; i < n; ++i) pAp += dir[i].dot(Ap[i]);
    if (!(pAp > 0.0)) break;
    const double alpha = rz / pAp;
    double rz_new = 0.0;
    rr = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      sol[i] += alpha * dir[i];
      r[i] -= alpha * Ap[i];
      z[i] = precond[i] * r[i];
      rz_new += r[i].dot(z[i]);
      rr += r[i].squaredNorm();
    }
    const double beta = rz_new / rz;
    rz = rz_new;
    for (std::size_t i = 0; i < n; ++i) dir[i] = z[i] + beta * dir[i];
    ++it;
  }
  cg_iterations = it;
  for (std::size_t i = 0; i < n; ++i) {
    if (free[i]) dv[i] = sol[i];
    v[i] += dv[i];
    x[i] += h * v[i];
    if (!free[i]) x[i] = pin_target(i, t1);  // exact, whatever the rounding of x + h v
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
