#pragma once
// The coarse level of the cloth solver's two-level preconditioner (private to cloth/).

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <cstdint>
#include <vector>

#include "cloth/sym3.hpp"
#include "simreel/sim/cloth.hpp"

namespace simreel::sim::detail {

/// Two-level additive Schwarz preconditioner for the implicit Euler system (M - h ∂f/∂v -
/// h² ∂f/∂x) Δv = b of the cloth (Baraff & Witkin 1998, eq. 6), by plain aggregation:
///
///   z = D⁻¹ r + P A_c⁻¹ Pᵀ r,   A_c = Pᵀ A P,
///
/// with D the 3x3 diagonal blocks (block Jacobi) and P the piecewise-constant
/// prolongation of the aggregates (each free vertex belongs to one; a coarse unknown is one
/// aggregate's velocity change, 3 numbers). Aggregates are grown greedily in vertex order
/// (Vaněk, Mandel & Brezina 1996, phases 1-3) over the stretch springs, and those aggregates
/// are aggregated once more over the graph they form: patches of about 45 vertices on a grid,
/// and any mesh cloth gets the same treatment. The coarse system is solved by a sparse
/// Cholesky factorisation (Eigen's SimplicialLLT, AMD ordering, pattern analysed once),
/// refactorised every step from the spring blocks (a factorisation kept for 4 steps cost more
/// CG iterations than it saved).
///
/// Why: block Jacobi leaves the smooth error modes (the whole sheet swinging or sagging) to the
/// CG, whose iterations grow with the stiffness-to-mass ratio h² k / m (2000 N/m springs on
/// 0.24 g vertices at 64 x 64 and h = 1/60 s: ratio ~2300); the coarse level removes those
/// modes in one solve. Pinned vertices are not in any aggregate (their Δv is known). Measured
/// on the 64 x 64 peer scene of bench_cloth at the default tolerance (|r| <= 1e-2 |b|): 14.3
/// CG iterations per step instead of 30.6, and the sheet 1 s in 2.2 cm rms from a converged
/// solve (tolerance 1e-7) instead of 15 cm: the small residual no longer hides a large error.
/// The iterations hardly grow with the grid (14, 16, 17, 17, 17 per step at 64², 128², 181²,
/// 224², 256² on that scene; block Jacobi alone 31, 35, 57, 53, 11): 1 thread, 240 frames,
/// 128² 8.0 s against 11.9 s, 181² 18.7 s against 40.1 s, 224² 29.8 s against 55.6 s. At 256²
/// block Jacobi alone met the tolerance in 11 iterations and took 23.8 s against 44.7 s (the
/// coarse level's 4,260 unknowns cost a fifth of the time there): the one size measured where
/// the coarse level does not pay.
///
/// Every operation runs in vertex or spring order on one thread: the result does not depend on
/// the thread count.
class CoarseSpace {
 public:
  /// Builds the aggregates and the coarse pattern. `free[i]` is 0 for a pinned vertex. A cloth
  /// with fewer than kMinVertices free vertices gets no coarse level (empty()).
  void build(const ClothTopology& topo, const std::vector<std::uint8_t>& free);
  [[nodiscard]] bool empty() const { return aggregates_ == 0; }
  [[nodiscard]] std::size_t aggregate_count() const { return aggregates_; }
  /// Vertex i's aggregate in [0, aggregate_count()), or -1 for a pinned vertex.
  [[nodiscard]] std::int32_t aggregate_of(std::size_t i) const { return agg_[i]; }

  /// Assembles A_c = Pᵀ A P and factorises it. A's diagonal block at a free vertex i is
  /// diag_m I + h aero[i] (aero may be null: none) plus the blocks S[s] of its springs; a spring
  /// s with len[s] > 0 between two free vertices also puts -S[s] off the diagonal (len[s] = 0:
  /// the spring is left out, as the product leaves it out). Returns false (the coarse level is
  /// then skipped this step) if the factorisation fails, which needs A not positive definite.
  bool factorize(double diag_m, const Sym3* aero, double h, const Sym3* S, const double* len);

  /// z += P A_c⁻¹ Pᵀ r over the free vertices; then, if rz is not null, rz[i] = r_i · z_i for
  /// every vertex (the CG's terms of rᵀz, in the same pass). r and z are structures of arrays
  /// (vertex i's x, y, z at [i], [stride + i], [2 stride + i]; SpringStencil's layout).
  void apply_add(const double* r, double* z, std::size_t stride, double* rz = nullptr);

  /// Appends to `out` the springs whose blocks factorize() reads (those that join two
  /// aggregates or an aggregate and a pinned vertex).
  void list_springs(std::vector<std::uint32_t>& out) const {
    for (const Crossing& c : crossing_) out.push_back(c.spring);
  }

  static constexpr std::size_t kMinVertices = 256;

 private:
  struct Block {
    std::int32_t value[9];  // CSC value offsets of (3I+row, 3J+col); -1 above a diagonal block
  };
  void add(const Block& blk, const Sym3& s, double sign);

  std::size_t n_ = 0, aggregates_ = 0;
  std::vector<std::int32_t> agg_;  // per vertex: its aggregate, -1 if pinned
  // The springs that reach out of an aggregate (the others add nothing to A_c: S - S - S + S),
  // each with the diagonal blocks of its ends' aggregates (-1: a pinned end) and the
  // off-diagonal block between them (-1: none).
  struct Crossing {
    std::uint32_t spring;
    std::int32_t diag_a, diag_b, off;
  };
  std::vector<Crossing> crossing_;
  std::vector<Block> blocks_;  // diagonal blocks first (index = aggregate), then off-diagonal
  std::vector<Sym3> sums_;     // per block: its sum of vertex and spring blocks (factorize)
  Eigen::SparseMatrix<double> Ac_;  // lower triangle
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt_;
  Eigen::VectorXd rc_, ec_;        // Pᵀ r (and 3 dummy entries for pinned vertices), A_c⁻¹ Pᵀ r
  std::vector<std::int32_t> slot_;  // per vertex: 3 × its aggregate, or the dummy's 3 N if pinned
  std::vector<double> ex_;          // ec_ and 3 zeros (the dummy's correction)
  bool ok_ = false;  // the last factorisation succeeded
};

}  // namespace simreel::sim::detail
