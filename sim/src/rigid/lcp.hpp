#pragma once
// Reference solver for the frictionless contact LCP (Coutinho §3.6.4, §4.8, App. G.2):
//   a = A f + b,   f >= 0,   a >= 0,   fᵀ a = 0,
// by Dantzig's principal pivoting as presented by Baraff 1994 ("Fast Contact Force Computation
// for Nonpenetrating Rigid Bodies", SIGGRAPH): contacts enter one at a time; contact d is
// driven until a_d = 0 while the clamped set C keeps a_C = 0 and the not-clamped set NC keeps
// f_NC = 0, taking the largest step that leaves every f and a non-negative (maxstep) and moving
// the index that blocks it between C and NC. Terminates for symmetric positive semi-definite A
// (a contact LCP's A = J M⁻¹ Jᵀ), with redundant contacts included. Small dense problems only
// (cubic per pivot): the check of the iterative solver, not a production path. Private.

#include <Eigen/Dense>

namespace simreel::sim::detail {

using MatX = Eigen::MatrixXd;
using VecX = Eigen::VectorXd;

struct LcpResult {
  VecX f;              ///< (n) forces or impulses, >= 0
  VecX a;              ///< (n) A f + b, >= 0 (to tolerance)
  int pivots = 0;      ///< steps taken (each a solve with the clamped block)
  bool solved = false;  ///< false: a step could not be bounded (A not PSD) or pivot limit hit
};

/// Solves the LCP for a symmetric positive semi-definite n x n `A` and an n-vector `b`.
/// `tol` (relative to the largest |b|) decides when a_i counts as >= 0. Asserts on a size
/// mismatch; a non-PSD A or a cycling pivot sequence returns solved = false.
[[nodiscard]] LcpResult solve_lcp_dantzig(const MatX& A, const VecX& b, double tol = 1e-12);

}  // namespace simreel::sim::detail
