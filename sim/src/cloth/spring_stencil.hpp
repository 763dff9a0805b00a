#pragma once
// The implicit cloth solver's matrix-vector product as a stencil, and the layout of the solver's
// vectors (private to cloth/).

#include <cstdint>
#include <vector>

#include "cloth/sym3.hpp"
#include "simreel/sim/cloth.hpp"

namespace simreel::sim::detail {

/// The spring part of the implicit Euler matrix (Baraff & Witkin 1998, eq. 6; Coutinho
/// Appendix B) applied as a stencil, for cloths whose springs join vertices a fixed index apart:
///
///   (A y)_i = D_i y_i + Σ_classes [ S_c[i] (y_i - y_{i+o_c}) - S_c[i-o_c] (y_{i-o_c} - y_i) ],
///
/// where a class c holds every spring (a, a + o_c) of one index offset o_c, and S_c[a] is that
/// spring's 3x3 block (h k_d nnᵀ + h² ∂f/∂x, zero where the class has no spring at a). A grid
/// cloth has six classes (§3.9.2, fig. 3.45: stretch 1 and `columns`, shear `columns` ± 1, bend
/// 2 and 2 `columns`); a mesh cloth has too many offsets and keeps the spring-by-spring product.
///
/// Why: the spring-by-spring product reads each spring's ends and writes each vertex's sum
/// through index lists, which the compiler cannot vectorise; it was 41 % of the 64 x 64 peer
/// scene's time. Here every read is a contiguous run (blocks, forces and vectors stored as
/// structures of arrays, padded with zeros so no index leaves the arrays) and the loops over
/// vertices vectorise (AVX2 where the CPU has it, SIMREEL_VECTOR_CLONES). Each spring's force
/// S (y_a - y_b) is computed once and added at both ends, as in the spring-by-spring product,
/// and each vertex's sum has a fixed order (its mass term, then the classes in order), so the
/// result does not depend on the thread count. D_i is the vertex's own block (m' I plus its
/// lumped aerodynamic damping).
///
/// The solver's vectors share one layout (stride(), pad()): a vector is 3 component arrays
/// `stride()` apart; a pointer to one points at its x component's vertex 0, and indices
/// [-pad(), n + pad()) are valid (zeros outside [0, n)).
class SpringStencil {
 public:
  /// Finds the offset classes of `topo`'s springs and sets the layout. Leaves the stencil
  /// empty() (the caller keeps the spring-by-spring product; pad() is then 0) when the springs
  /// fall into more than kMaxClasses offsets or two springs join the same pair of vertices.
  void build(const ClothTopology& topo);
  [[nodiscard]] bool empty() const { return classes_ == 0; }
  [[nodiscard]] std::size_t class_count() const { return classes_; }
  [[nodiscard]] std::size_t stride() const { return stride_; }
  [[nodiscard]] std::size_t pad() const { return pad_; }

  /// Stores spring s's block for the next products (a zero block leaves the spring out).
  void set(std::size_t s, const Sym3& b) { b.store(blocks_.data() + slot_[s], stride_); }

  /// Stores spring s's term of the right-hand side, w = h² K (v_b - v_a) (assemble() adds it at
  /// its first vertex a and subtracts it at b). Shares its storage with apply()'s forces.
  void set_rhs(std::size_t s, const Vec3& w) {
    double* p = forces_.data() + rhs_slot_[s];
    p[0] = w.x();
    p[stride_] = w.y();
    p[2 * stride_] = w.z();
  }

  /// For every vertex i: the inverse of its diagonal block D_i + Σ_{springs at i} S_s into `pc`
  /// (6 arrays xx xy xz yy yz zz, the layout above) and b_i = h f_i + Σ_{springs (i, j)} w_s -
  /// Σ_{springs (j, i)} w_s into b (f: n Vec3 as 3n doubles), both times mask_i (zero at a pinned
  /// vertex). The blocks and terms set before (set, set_rhs) are used. Requires !empty().
  void assemble(const double* diag, const double* mask, double h, const double* f, double* pc,
                double* b, int threads);

  /// out_i = mask_i (D_i y_i + the springs' terms above) and yAy_i = y_i · out_i for every
  /// vertex i in [0, n). y and out are vectors of the layout above (y zero in its padding);
  /// `diag` holds D as 6 arrays (xx xy xz yy yz zz) `stride()` apart; mask_i is 1 for a free
  /// vertex and 0 for a pinned one. `threads` > 1 splits the vertices in fixed chunks (the same
  /// bits at any count). Requires !empty().
  void apply(const double* y, const double* diag, const double* mask, double* out, double* yAy,
             int threads);

  static constexpr std::size_t kMaxClasses = 8;

 private:
  std::size_t n_ = 0, classes_ = 0;
  std::size_t pad_ = 0;     // the largest offset
  std::size_t stride_ = 0;  // n_ + 2 pad_, rounded up (see build)
  std::vector<std::size_t> offset_;  // per class: o_c
  std::vector<std::size_t> slot_;    // per spring: its xx entry in blocks_
  std::vector<std::size_t> rhs_slot_;  // per spring: its x entry in forces_
  std::vector<double> blocks_;       // per class, 6 arrays (xx xy xz yy yz zz), layout above
  std::vector<double> forces_;       // per class, the springs' forces S (y_a - y_b), a vector
};

}  // namespace simreel::sim::detail
