// Dantzig's algorithm for the frictionless contact LCP (Baraff 1994; Coutinho App. G.2).
#include "rigid/lcp.hpp"

#include <cassert>
#include <cmath>
#include <limits>
#include <vector>

namespace simreel::sim::detail {
namespace {

enum class Set : unsigned char { none, clamped, not_clamped };

}  // namespace

LcpResult solve_lcp_dantzig(const MatX& A, const VecX& b, double tol) {
  const Eigen::Index n = b.size();
  assert(A.rows() == n && A.cols() == n);
  LcpResult r;
  r.f = VecX::Zero(n);
  r.a = b;
  const double eps = tol * std::max(1.0, b.cwiseAbs().maxCoeff());
  std::vector<Set> set(static_cast<std::size_t>(n), Set::none);
  std::vector<Eigen::Index> C;  // clamped indices, in entry order (deterministic)
  const int max_pivots = 50 * static_cast<int>(n) + 10;
  constexpr double inf = std::numeric_limits<double>::infinity();
  // Contacts in index order; each is driven to a_d = 0 or left with f_d = 0 when a_d > 0.
  for (Eigen::Index d = 0; d < n; ++d) {
    if (r.a[d] >= -eps) {
      set[std::size_t(d)] = Set::not_clamped;
      continue;
    }
    while (true) {  // drive_to_zero(d)
      if (++r.pivots > max_pivots) return r;
      // fdirection: Δf_d = 1, Δf_C solves A_CC Δf_C = -A_Cd so that Δa_C = 0, else 0.
      VecX df = VecX::Zero(n);
      df[d] = 1.0;
      if (!C.empty()) {
        const auto k = static_cast<Eigen::Index>(C.size());
        MatX Acc(k, k);
        VecX rhs(k);
        for (Eigen::Index i = 0; i < k; ++i) {
          rhs[i] = -A(C[std::size_t(i)], d);
          for (Eigen::Index j = 0; j < k; ++j) Acc(i, j) = A(C[std::size_t(i)], C[std::size_t(j)]);
        }
        const VecX x = Acc.fullPivLu().solve(rhs);
        for (Eigen::Index i = 0; i < k; ++i) df[C[std::size_t(i)]] = x[i];
      }
      const VecX da = A * df;
      // maxstep: the largest s keeping f >= 0 on C, a >= 0 on NC, a_d <= 0.
      double s = inf;
      Eigen::Index j = -1;
      if (da[d] > 0.0) {
        s = -r.a[d] / da[d];
        j = d;
      }
      for (const Eigen::Index i : C)
        if (df[i] < 0.0) {
          const double si = -r.f[i] / df[i];
          if (si < s) {
            s = si;
            j = i;
          }
        }
      for (Eigen::Index i = 0; i < n; ++i)
        if (set[std::size_t(i)] == Set::not_clamped && da[i] < 0.0) {
          const double si = -r.a[i] / da[i];
          if (si < s) {
            s = si;
            j = i;
          }
        }
      if (j < 0) return r;  // unbounded direction: A is not PSD
      s = std::max(s, 0.0);
      r.f += s * df;
      r.a += s * da;
      if (j == d) {
        r.a[d] = 0.0;
        set[std::size_t(d)] = Set::clamped;
        C.push_back(d);
        break;
      }
      if (set[std::size_t(j)] == Set::clamped) {  // f_j reached 0: leaves C
        r.f[j] = 0.0;
        set[std::size_t(j)] = Set::not_clamped;
        std::erase(C, j);
      } else {  // a_j reached 0: joins C
        r.a[j] = 0.0;
        set[std::size_t(j)] = Set::clamped;
        C.push_back(j);
      }
    }
  }
  r.solved = true;
  return r;
}

}  // namespace simreel::sim::detail
