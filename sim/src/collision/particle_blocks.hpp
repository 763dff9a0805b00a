#pragma once
// The particle collision pass's block kernels (private): the rejection tests of collide() for a
// block of particles, the plane-rest lanes' gather and scatter, and the Z-order that visits
// particles near solids in spatial order. Element-wise loops the compiler vectorises, built for
// AVX2 and the baseline (SIMREEL_VECTOR_CLONES on the definitions: the same bits either way;
// GCC 12 emits a broken resolver in every caller whose declaration carries target_clones, so the
// declarations here do not); particle_response.cpp is their only user.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "collision/collider_impl.hpp"
#include "collision/plane_rest.hpp"

namespace simreel::sim::detail {

/// near[k] = 1 when particle k (x: n x 3 floats, m; r: n, m) ends the step closer than its
/// radius to one of the planes: collide()'s rejection test n · (p - q) - r < 0, the same double
/// arithmetic, in a loop the compiler vectorises. A plane whose normal is exactly ±e_a reads p_a
/// alone when the block's positions are finite (the off-axis products are then ±0: the same
/// decision; SimParticleBlocks.NearPlanesDecidesAsTheParticleTest). The fast rejection before
/// Coutinho §3.4's swept-sphere test.
void near_planes(const float* __restrict x, const float* __restrict r, std::size_t n,
                 const Collider* planes, std::size_t count, std::uint8_t* __restrict near);

/// A block's swept bounds in start_of_step()'s plain case (semi-implicit Euler without drag:
/// x0 = x1 - dt v1 + dt²/2 g, dt = min(age, h)): per axis the smaller and the larger of the start
/// and end positions (Eigen's cwiseMin / cwiseMax of start and end), and the growth r +
/// surface_tol(end) (m); structure of arrays for up to kBlock particles.
struct SweptBounds {
  static constexpr std::size_t kBlock = 256;
  double lo[3][kBlock], hi[3][kBlock], grow[kBlock];
};

/// b = the swept bounds of particles [0, n) (x, v: n x 3 floats; age, r: n; n <= kBlock): the
/// same double arithmetic as collide()'s start_of_step() and surface_tol(), in a loop the
/// compiler vectorises.
void swept_bounds_plain(const float* __restrict x, const float* __restrict v,
                        const float* __restrict age, const float* __restrict r, std::size_t n,
                        double h, const double* __restrict g, SweptBounds& b);

/// near[k] |= 1 when bounds k of b, grown by b.grow[k], overlap the solid's world AABB (center,
/// half): collide()'s rejection test for a solid (near_aabb), the same double arithmetic.
void near_solid(const SweptBounds& b, std::size_t n, const double* __restrict center,
                const double* __restrict half, std::uint8_t* __restrict near);

/// An open mesh that does not move: a particle whose swept bounds (grown by its radius and
/// surface_tol) hold no point of any triangle meets nothing there (its sweep finds no hit, and an
/// open mesh has no inside to remove it from), so the mesh's own columns (MeshGrid::clear_of) can
/// reject it after its AABB: rain above a terrain.
inline bool column_tested(const Collider& c) {
  return c.shape == Collider::Shape::mesh && c.unposed && !c.mesh->closed;
}

/// collide()'s rejection test for a block of particles [0, n) (n <= kBlock) in
/// start_of_step()'s plain case: b = their swept bounds (swept_bounds_plain()); near[k] = 1 when
/// particle k ends the step within a plane (near_planes()) or its bounds overlap the AABB of a
/// solid that is not column-tested (near_solid()); pend[k] = 1 when they overlap a
/// column-tested mesh's AABB (for columns_clear_block()).
void near_block_plain(const float* __restrict x, const float* __restrict v,
                      const float* __restrict age, const float* __restrict r, std::size_t n,
                      double h, const double* g, const std::vector<Collider>& colliders,
                      SweptBounds& b, std::uint8_t* __restrict near, std::uint8_t* __restrict pend);

/// Column answers of earlier steps, for columns_clear_block(): one slot per particle index
/// holding the key of the columns a particle's box last spanned there (the first column's index
/// times 4, plus 2 when it spans the next column on x, plus 1 for the next row) with the lowest
/// and highest level over them as the grid's table gives them (bits 32-39, 40-47). A slot is a
/// function of its key and the grid alone, so it stays right whichever particle later has the
/// index; only another grid voids it (MeshGrid::serial()). A drop falling through the same
/// columns step after step reads its own slot, in index order, instead of a line of the table
/// at random (what the columns' test mostly waited on). No answer depends on it.
struct ColumnMemo {
  static constexpr std::uint64_t kNone = 0xffffffffu;  ///< no key (2^30 columns at most)
  std::uint64_t serial = 0;          ///< the grid the slots were filled from (0: none)
  std::vector<std::uint64_t> slot;
  /// The slots of particles [0, n) for grid g: all emptied first when they were g's.
  std::uint64_t* for_grid(const MeshGrid& g, std::size_t n) {
    if (serial != g.serial()) {
      slot.assign(std::max(n, slot.size()), kNone);
      serial = g.serial();
    } else if (slot.size() < n) {
      slot.resize(n, kNone);
    }
    return slot.data();
  }
};

/// This thread's ColumnMemo slots, slot i for particle i < n, for the first column-tested mesh
/// among colliders, which `mesh` is set to; null (and mesh null) when there is none. (Per thread:
/// a slot is right whichever particle met it before, so threads need not share.)
std::uint64_t* column_memo_slots(const std::vector<Collider>& colliders, std::size_t n,
                                 const Collider*& mesh);

/// clear[k] = 0 for each k with pend[k] set whose bounds overlap column-tested mesh c's AABB (as
/// near_solid()) and are not cleared by its columns (c.mesh->grid.clear_of() of the bounds grown
/// by b.grow[k]); the others' entries untouched. collide()'s columns_clear() for a block.
/// `lanes`: the most particles at once, as the CPU runs them: 8 (AVX-512VL), 4 (AVX2) or 1 (the
/// same answers at each; the tests compare them). `memo`: null, or the block's particles'
/// ColumnMemo slots for c's grid (n of them), read and written by the 8- and 4-lane forms (the
/// same answers with or without).
void columns_clear_block(const SweptBounds& b, std::size_t n, const Collider& c,
                         const std::uint8_t* __restrict pend, std::uint8_t* __restrict clear,
                         int lanes = 8, std::uint64_t* __restrict memo = nullptr);

/// Lanes [0, len) of `l` from a block of particles (x, v: len x 3; prev: the start-of-step
/// positions or null; mass, radius, age: len), each lane's step min(age, h). Where the block's
/// particles share one mass and radius and are all at least h old, only lane 0 of m, r and dt
/// is filled and l.shared is set (PlaneRestLanes::shared).
void gather_block(const float* __restrict x, const float* __restrict v,
                  const float* __restrict prev, const float* __restrict mass,
                  const float* __restrict radius, const float* __restrict age, double h,
                  std::size_t len, PlaneRestLanes& l);

/// True when every lane of l's first len was resolved by plane_rest() and stored outside the
/// plane (ok == 1): a settled block, whose per-lane follow-up in plane_block() would do nothing.
bool all_resolved_outside(const PlaneRestLanes& l, std::size_t len);

/// The lanes' outputs back into the block (x, v: len x 3): the results of the lanes that
/// plane_rest() resolved, the others' values as they were.
void scatter_block(const PlaneRestLanes& l, std::size_t len, float* __restrict x,
                   float* __restrict v);

/// near[k] = 1 when lane k of `l` ends the step closer than its radius to the plane (the test of
/// near_planes(), on the same values; the radius lane 0's where l.shared).
void near_lanes(const PlaneRestLanes& l, std::size_t len, const PlaneRestParams& p,
                std::uint8_t* __restrict near);

/// kSpread3[v]: the 10 bits of v spread to every third bit (a Morton code's one axis).
inline constexpr auto kSpread3 = [] {
  std::array<std::uint32_t, 1024> t{};
  for (std::uint32_t v = 0; v < 1024; ++v)
    for (int b = 0; b < 10; ++b) t[v] |= ((v >> b) & 1u) << (3 * b);
  return t;
}();

/// Z-order (Morton) codes of positions over the solids' joint bounds: 1024 steps per axis of
/// one quantum for all (a flat terrain's few centimetres of height must not outweigh metres
/// across it), clamped.
struct ZOrder {
  double origin[3] = {0.0, 0.0, 0.0};
  double scale = 0.0;  ///< (1/m)
  ZOrder() = default;
  explicit ZOrder(const std::vector<Collider>& colliders) {
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const Collider& c : colliders) {
      if (c.shape == Collider::Shape::plane) continue;
      lo = lo.cwiseMin(c.aabb_center - c.aabb_half);
      hi = hi.cwiseMax(c.aabb_center + c.aabb_half);
    }
    scale = 1023.0 / std::max((hi - lo).maxCoeff(), 1e-9);
    for (int k = 0; k < 3; ++k) origin[k] = lo[k];
  }
  /// The 30-bit code of position p (3 floats).
  std::uint64_t code(const float* p) const {
    std::uint64_t c = 0;
    for (int k = 0; k < 3; ++k)
      c |= std::uint64_t(kSpread3[std::size_t(std::clamp((double(p[k]) - origin[k]) * scale, 0.0, 1023.0))]) << k;
    return c;
  }
  /// Sorts keys (code << 32 | index) by code, stably (radix, 10 bits at a time; tmp: scratch).
  static void sort(std::vector<std::uint64_t>& keys, std::vector<std::uint64_t>& tmp) {
    tmp.resize(keys.size());
    for (int pass = 0; pass < 3; ++pass) {
      const int shift = 32 + 10 * pass;
      std::uint32_t count[1025] = {};
      for (const std::uint64_t k : keys) ++count[((k >> shift) & 1023) + 1];
      for (int d = 0; d < 1024; ++d) count[d + 1] += count[d];
      for (const std::uint64_t k : keys) tmp[count[(k >> shift) & 1023]++] = k;
      keys.swap(tmp);
    }
  }
};


}  // namespace simreel::sim::detail
