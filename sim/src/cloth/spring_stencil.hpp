#pragma once
// The implicit cloth solver's matrix-vector product as a stencil, and the layout of the solver's
// vectors (private to cloth/).

#include <cstdint>
#include <vector>

#include "cloth/sym3.hpp"
#include "simreel/sim/cloth.hpp"

namespace simreel::sim::detail {

/// The cloth's springs as a stencil, for cloths whose springs join vertices a fixed index apart:
/// their forces (Coutinho §3.9.2), their blocks of the implicit Euler matrix (Baraff & Witkin
/// 1998, eq. 6; Coutinho Appendix B) and the matrix-vector product
///
///   (A y)_i = D_i y_i + Σ_classes [ S_c[i] (y_i - y_{i+o_c}) - S_c[i-o_c] (y_{i-o_c} - y_i) ],
///
/// where a class c holds every spring (a, a + o_c) of one index offset o_c, and S_c[a] is that
/// spring's 3x3 block (h k_d uuᵀ + h² ∂f/∂x, zero where the class has no spring at a). A grid
/// cloth has six classes (§3.9.2, fig. 3.45: stretch 1 and `columns`, shear `columns` ± 1, bend
/// 2 and 2 `columns`); a mesh cloth has too many offsets and keeps the spring-by-spring loops.
///
/// A block is stored as S = q qᵀ + β I (4 numbers, not 6): with the spring Jacobian K = (k - τ)
/// uuᵀ + τ I (τ = k max(0, 1 - L/l), the transverse stiffness) the block is h² K + h k_d uuᵀ =
/// α uuᵀ + β I with α = h² (k - τ) + h k_d >= 0 and β = h² τ, so q = √α u.
///
/// Why: per spring through index lists, the loops read each spring's ends and write each
/// vertex's sum one at a time and do not vectorise; the product alone was 41 % of the 64 x 64
/// peer scene's time, the forces and blocks another 23 %. Here every read is a contiguous run
/// (per-spring data, forces and vectors stored as structures of arrays, padded with zeros so no
/// index leaves the arrays) and the loops over vertices vectorise (AVX2 where the CPU has it,
/// SIMREEL_VECTOR_CLONES). Each spring's force is computed once and added at both ends (the
/// matrix stays exactly symmetric), and each vertex's sum has a fixed order (its own term, then
/// the classes in order), so the result does not depend on the thread count. A spring's
/// direction is from its lower vertex index to its higher, whatever the topology's order.
///
/// The solver's vectors share one layout (stride(), pad()): a vector is 3 component arrays
/// `stride()` apart; a pointer to one points at its x component's vertex 0, and indices
/// [-pad(), n + pad()) are valid (zeros outside [0, n)).
class SpringStencil {
 public:
  /// Finds the offset classes of `topo`'s springs and sets the layout; stores the rest lengths
  /// and the stiffnesses ks, kds (N/m, N s/m; one per spring, in the topology's order). Leaves
  /// the stencil empty() (the caller keeps the spring-by-spring loops; pad() is then 0) when the
  /// springs fall into more than kMaxClasses offsets or two springs join the same pair of
  /// vertices.
  void build(const ClothTopology& topo, const std::vector<double>& ks,
             const std::vector<double>& kds);
  [[nodiscard]] bool empty() const { return classes_ == 0; }
  [[nodiscard]] std::size_t class_count() const { return classes_; }
  [[nodiscard]] std::size_t stride() const { return stride_; }
  [[nodiscard]] std::size_t pad() const { return pad_; }

  /// Every spring's length l, direction u (lower index to higher) and force on its lower vertex
  /// F = (k_s (l - L) + k_d (v_b - v_a) · u) u (Coutinho §3.9.2, eq. 3.101 with damping along
  /// the spring), then into f (a vector of the layout above) every vertex's
  /// m (g - c v_i) + Σ (its springs' forces, + at the lower end, - at the higher); a spring of
  /// length 0 exerts no force. x, v: positions (m) and velocities (m/s), vectors of the layout
  /// above, zero in their padding. `threads` > 1 splits the vertices in fixed chunks.
  void forces(const double* x, const double* v, double m, const Vec3& g, double c, double* f,
              int threads);

  /// From the lengths and directions of the last forces() and the step h (s): every spring's
  /// block S (above) for the next products, and its term of the right-hand side w = h² K
  /// (v_b - v_a) (v: velocities, the layout above) for assemble(). A spring of length 0 gets
  /// S = 0 and w = 0 (the spring-by-spring loops leave it out).
  void blocks(double h, const double* v, int threads);

  /// Spring s's block (q qᵀ + β I) and its length at the last forces() (m).
  [[nodiscard]] Sym3 block(std::size_t s) const;
  [[nodiscard]] double length(std::size_t s) const { return len_[at(s, 1, 0)]; }

  /// Stores spring s's block as q qᵀ + β I for the next products (q = 0, β = 0 leaves the
  /// spring out). For tests; blocks() sets every spring's.
  void set(std::size_t s, const Vec3& q, double beta);

  /// Stores spring s's term of the right-hand side w (assemble() adds it at the spring's lower
  /// vertex and subtracts it at the higher). Shares its storage with the forces. For tests;
  /// blocks() sets every spring's.
  void set_rhs(std::size_t s, const Vec3& w);

  /// For every vertex i: the inverse of its diagonal block D_i + Σ_{springs at i} S_s into `pc`
  /// (6 arrays xx xy xz yy yz zz, the layout above) and b_i = h f_i + Σ_{springs (i, j), i < j}
  /// w_s - Σ_{springs (j, i), j < i} w_s into b (f: a vector of the layout above), both times
  /// mask_i (zero at a pinned vertex). The blocks and terms of the last blocks() (or set,
  /// set_rhs) are used. Requires !empty().
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
  std::vector<std::uint32_t> class_, first_;  // per spring: its class c and lower vertex a
  /// Spring s's entry in component k of a group of `g` arrays per class.
  [[nodiscard]] std::size_t at(std::size_t s, std::size_t g, std::size_t k) const {
    return (g * class_[s] + k) * stride_ + pad_ + first_[s];
  }
  // Per class, one array each (index c stride_ + pad_ + a: the spring (a, a + o_c); zeros where
  // the class has no spring at a):
  std::vector<double> rest_, ks_, kds_;  // rest length L, k_s, k_d
  std::vector<double> len_;              // length l at the last forces()
  std::vector<double> dir_;              // per class 3 arrays: u
  std::vector<double> blocks_;           // per class 4 arrays: q, β
  std::vector<double> forces_;           // per class 3 arrays: F, then w, then S (y_a - y_b)
};

}  // namespace simreel::sim::detail
