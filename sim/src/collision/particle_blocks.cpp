// The particle collision pass's block kernels: see particle_blocks.hpp.
#include "collision/particle_blocks.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/vector_clones.hpp"
#include "particles/row_lanes.hpp"

#if SIMREEL_HAS_VECTOR_CLONES
#include <immintrin.h>
#endif

namespace simreel::sim::detail {

namespace {
/// True when none of x[0, m) is infinite or NaN (one pass a compiler vectorises).
SIMREEL_VECTOR_CLONES
bool all_finite(const float* __restrict x, std::size_t m) {
  unsigned bad = 0;
  for (std::size_t k = 0; k < m; ++k)
    bad |= unsigned(!(std::fabs(x[k]) <= std::numeric_limits<float>::max()));
  return bad == 0;
}

/// near[k] |= 1 when s (x[3k + a] - q) - r[k] < 0: a plane whose normal is s e_a (s = ±1), for
/// finite positions. There n · e = s e_a exactly (the other two products are ±0, and adding ±0
/// to a number changes nothing, fused or not), so this is the general test's decision, with
/// one coordinate read instead of three taken apart.
template <int kAxis>
SIMREEL_VECTOR_CLONES void near_axis_plane(const float* __restrict x, const float* __restrict r,
                                           std::size_t n, double s, double q,
                                           std::uint8_t* __restrict near) {
  for (std::size_t k = 0; k < n; ++k)
    near[k] |= std::uint8_t(s * (double(x[3 * k + kAxis]) - q) - double(r[k]) < 0.0);
}

#if SIMREEL_HAS_VECTOR_CLONES
/// Byte j of entry `bits` is bit j of bits (0 or 1): four compare results as four bytes.
constexpr std::array<std::uint32_t, 16> make_bit_bytes() {
  std::array<std::uint32_t, 16> t{};
  for (std::uint32_t b = 0; b < 16; ++b)
    for (std::uint32_t j = 0; j < 4; ++j) t[b] |= ((b >> j) & 1u) << (8 * j);
  return t;
}
inline constexpr std::array<std::uint32_t, 16> kBitBytes = make_bit_bytes();

/// near_axis_plane() four particles at a time with AVX2, for CPUs without AVX-512: the axis
/// coordinates of four rows taken by scalar loads into one 128-bit vector, where the compiler's
/// clone took the rows apart with lane-crossing vpermd (3 micro-ops, one per 4 cycles on AMD
/// Zen 1: docs/benchmarks.md, stop 86). The same double arithmetic in each lane (no fused
/// multiply-add: -ffp-contract=off), so the same decisions.
template <int kAxis>
__attribute__((target("avx2"))) void near_axis_plane_avx2(const float* __restrict x, const float* __restrict r,
                                                          std::size_t n, double s, double q,
                                                          std::uint8_t* __restrict near) {
  const __m256d vs = _mm256_set1_pd(s), vq = _mm256_set1_pd(q), zero = _mm256_setzero_pd();
  std::size_t k = 0;
  for (; k + 4 <= n; k += 4) {
    const float* p = x + 3 * k + kAxis;
    const __m256d c = _mm256_cvtps_pd(_mm_setr_ps(p[0], p[3], p[6], p[9]));
    const __m256d e = _mm256_sub_pd(_mm256_mul_pd(vs, _mm256_sub_pd(c, vq)), _mm256_cvtps_pd(_mm_loadu_ps(r + k)));
    const int bits = _mm256_movemask_pd(_mm256_cmp_pd(e, zero, _CMP_LT_OQ));
    std::uint32_t w;
    std::memcpy(&w, near + k, 4);
    w |= kBitBytes[std::size_t(bits)];
    std::memcpy(near + k, &w, 4);
  }
  for (; k < n; ++k) near[k] |= std::uint8_t(s * (double(x[3 * k + kAxis]) - q) - double(r[k]) < 0.0);
}

/// The CPU has AVX2 and not AVX-512VL (whose clone of near_axis_plane() has eight lanes).
inline bool axis_plane_avx2() {
  static const bool yes = !cpu_has_avx512vl() && cpu_has_avx2();
  return yes;
}
#endif

/// One axis-aligned plane's test: near_axis_plane_avx2() where it is the better form.
template <int kAxis>
void near_axis(const float* __restrict x, const float* __restrict r, std::size_t n, double s, double q,
               std::uint8_t* __restrict near) {
#if SIMREEL_HAS_VECTOR_CLONES
  if (axis_plane_avx2()) {
    near_axis_plane_avx2<kAxis>(x, r, n, s, q, near);
    return;
  }
#endif
  near_axis_plane<kAxis>(x, r, n, s, q, near);
}

/// The axis of a normal that is ±e_a exactly (the other two components ±0), else -1.
int normal_axis(const Collider& c) {
  const double* nv = c.normal.data();
  for (int a = 0; a < 3; ++a)
    if (std::abs(nv[a]) == 1.0 && nv[(a + 1) % 3] == 0.0 && nv[(a + 2) % 3] == 0.0 &&
        c.point.allFinite())  // (an infinite point coordinate makes the general sum NaN)
      return a;
  return -1;
}
}  // namespace

/// near[k] = 1 when particle k (x: n x 3 floats, r: n) ends the step closer than its radius to
/// one of the planes: collide()'s rejection test, the same double arithmetic, in a loop the
/// compiler vectorises (see particle_blocks.hpp).
SIMREEL_VECTOR_CLONES
void near_planes(const float* __restrict x, const float* __restrict r, std::size_t n,
                 const Collider* planes, std::size_t count, std::uint8_t* __restrict near) {
  for (std::size_t k = 0; k < n; ++k) near[k] = 0;
  // An axis-aligned plane (a ground, a wall) reads one coordinate, when the block is finite: an
  // infinite or NaN coordinate off the axis makes the general sum NaN (0 inf), so "not near".
  int finite = -1;  // (checked once, at the first axis-aligned plane)
  for (std::size_t c = 0; c < count; ++c) {
    int axis = normal_axis(planes[c]);
    if (axis >= 0 && finite < 0) finite = int(all_finite(x, 3 * n));
    if (finite == 0) axis = -1;
    if (axis >= 0) {
      const double s = planes[c].normal[axis], q = planes[c].point[axis];
      if (axis == 0) near_axis<0>(x, r, n, s, q, near);
      if (axis == 1) near_axis<1>(x, r, n, s, q, near);
      if (axis == 2) near_axis<2>(x, r, n, s, q, near);
      continue;
    }
    const double n0 = planes[c].normal[0], n1 = planes[c].normal[1], n2 = planes[c].normal[2];
    const double q0 = planes[c].point[0], q1 = planes[c].point[1], q2 = planes[c].point[2];
    for (std::size_t k = 0; k < n; ++k) {
      const double e0 = double(x[3 * k]) - q0, e1 = double(x[3 * k + 1]) - q1,
                   e2 = double(x[3 * k + 2]) - q2;
      near[k] |= std::uint8_t(n0 * e0 + n1 * e1 + n2 * e2 - double(r[k]) < 0.0);
    }
  }
}

/// b = the swept bounds of particles [0, n): see particle_blocks.hpp.
SIMREEL_VECTOR_CLONES
void swept_bounds_plain(const float* __restrict x, const float* __restrict v,
                        const float* __restrict age, const float* __restrict r, std::size_t n,
                        double h, const double* __restrict g, SweptBounds& b) {
  for (std::size_t k = 0; k < n; ++k) {
    const double a = double(age[k]);
    const double dt = h < a ? h : a;  // std::min(age, h)
    const double c = 0.5 * dt * dt;
    const double p0 = double(x[3 * k]), p1 = double(x[3 * k + 1]), p2 = double(x[3 * k + 2]);
    const double s0 = p0 - dt * double(v[3 * k]) + c * g[0];
    const double s1 = p1 - dt * double(v[3 * k + 1]) + c * g[1];
    const double s2 = p2 - dt * double(v[3 * k + 2]) + c * g[2];
    // surface_tol(p1): 1e-7 + 5e-7 max |p1_i| (the largest of three is exact in any order).
    const double m01 = std::abs(p0) < std::abs(p1) ? std::abs(p1) : std::abs(p0);
    const double m = m01 < std::abs(p2) ? std::abs(p2) : m01;
    b.grow[k] = double(r[k]) + (1e-7 + 5e-7 * m);
    // Eigen's cwiseMin / cwiseMax of start s and end p: (p < s) ? p : s and (s < p) ? p : s.
    b.lo[0][k] = p0 < s0 ? p0 : s0;
    b.hi[0][k] = s0 < p0 ? p0 : s0;
    b.lo[1][k] = p1 < s1 ? p1 : s1;
    b.hi[1][k] = s1 < p1 ? p1 : s1;
    b.lo[2][k] = p2 < s2 ? p2 : s2;
    b.hi[2][k] = s2 < p2 ? p2 : s2;
  }
}

namespace {
/// Bounds k of b, grown by b.grow[k], overlap the AABB (center, half): near_aabb's arithmetic.
inline bool overlaps(const SweptBounds& b, std::size_t k, const double* center, const double* half) {
  const double grow = b.grow[k];
  const double e0 = half[0] + grow, e1 = half[1] + grow, e2 = half[2] + grow;
  return (b.lo[0][k] - center[0] <= e0) & (b.lo[1][k] - center[1] <= e1) &
         (b.lo[2][k] - center[2] <= e2) & (b.hi[0][k] - center[0] >= -e0) &
         (b.hi[1][k] - center[1] >= -e1) & (b.hi[2][k] - center[2] >= -e2);
}
}  // namespace

/// near[k] |= 1 when bounds k overlap the solid's AABB: see particle_blocks.hpp.
SIMREEL_VECTOR_CLONES
void near_solid(const SweptBounds& b, std::size_t n, const double* __restrict center,
                const double* __restrict half, std::uint8_t* __restrict near) {
  for (std::size_t k = 0; k < n; ++k) near[k] |= std::uint8_t(overlaps(b, k, center, half));
}

void near_block_plain(const float* __restrict x, const float* __restrict v,
                      const float* __restrict age, const float* __restrict r, std::size_t n,
                      double h, const double* g, const std::vector<Collider>& colliders,
                      SweptBounds& b, std::uint8_t* __restrict near, std::uint8_t* __restrict pend) {
  std::fill(near, near + n, std::uint8_t{0});
  std::fill(pend, pend + n, std::uint8_t{0});
  swept_bounds_plain(x, v, age, r, n, h, g, b);
  std::uint8_t near_c[SweptBounds::kBlock];
  for (const Collider& c : colliders) {
    if (c.shape == Collider::Shape::plane) {
      near_planes(x, r, n, &c, 1, near_c);
      for (std::size_t k = 0; k < n; ++k) near[k] |= near_c[k];
    } else {
      near_solid(b, n, c.aabb_center.data(), c.aabb_half.data(), column_tested(c) ? pend : near);
    }
  }
}

namespace {
void columns_clear_scalar(const SweptBounds& b, std::size_t n, const Collider& c,
                          const std::uint8_t* __restrict pend, std::uint8_t* __restrict clear) {
  const MeshGrid& grid = c.mesh->grid;
  for (std::size_t k = 0; k < n; ++k) {
    if (pend[k] == 0) continue;
    // This mesh's AABB test (near_solid()'s) for the particles asked only: pend may come from
    // another column-tested mesh.
    if (!overlaps(b, k, c.aabb_center.data(), c.aabb_half.data())) continue;
    const double grow = b.grow[k];
    const Vec3 lo(b.lo[0][k] - grow, b.lo[1][k] - grow, b.lo[2][k] - grow);
    const Vec3 hi(b.hi[0][k] + grow, b.hi[1][k] + grow, b.hi[2][k] + grow);
    if (!grid.clear_of(lo, hi)) clear[k] = 0;
  }
}

#if SIMREEL_HAS_VECTOR_CLONES
/// MeshGrid::clear_of()'s column of coordinate v on one axis, in lanes: (v - origin) inv, then
/// std::max(., 0.0) and std::min(., last) as their comparisons and picks, truncated to int.
__attribute__((target("avx512f,avx512vl"), always_inline)) inline __m256i column_cell(
    __m512d v, __m512d origin, __m512d inv, __m512d last) {
  const __m512d zero = _mm512_setzero_pd();
  v = _mm512_mul_pd(_mm512_sub_pd(v, origin), inv);
  v = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(v, zero, _CMP_LT_OQ), v, zero);
  v = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(last, v, _CMP_LT_OQ), v, last);
  return _mm512_maskz_cvttpd_epi32(0xff, v);
}

/// MeshGrid's level q (0..255) in lanes, computed rather than read from its table: z0 + q step
/// (the table's own operations, so its bits) for 1..254, -inf for 0 and +inf for 255.
__attribute__((target("avx512f,avx512vl"), always_inline)) inline __m512d level_lanes(
    __m256i q, const MeshGrid::ColumnTable& t) {
  const __m512d z = _mm512_add_pd(_mm512_set1_pd(t.level_z0),
                                  _mm512_mul_pd(_mm512_maskz_cvtepi32_pd(0xff, q), _mm512_set1_pd(t.level_step)));
  const __m512d lowest = _mm512_mask_blend_pd(_mm256_cmpeq_epi32_mask(q, _mm256_setzero_si256()), z,
                                              _mm512_set1_pd(-std::numeric_limits<double>::infinity()));
  return _mm512_mask_blend_pd(_mm256_cmpeq_epi32_mask(q, _mm256_set1_epi32(255)), lowest,
                              _mm512_set1_pd(std::numeric_limits<double>::infinity()));
}

/// columns_clear_scalar() for eight particles at a time in AVX-512 lanes: overlaps() and
/// MeshGrid::clear_of() with the same double operations in each lane (the clamps as the
/// comparisons std::max / std::min make, truncation to int), the 2 x 2 columns always read (a
/// column read twice changes no minimum or maximum), and the early returns of clear_of() as lane
/// masks in its order: outside the bounds (clear), not ordered (NaN: not clear), more than two
/// columns on an axis (not clear), then the levels. The scalar loop's branches on each
/// particle's answers cost the rain benchmark's first second about a fifth of its time.
__attribute__((target("avx512f,avx512vl")))
void columns_clear_avx512(const SweptBounds& b, std::size_t n, const Collider& c,
                          const std::uint8_t* __restrict pend, std::uint8_t* __restrict clear,
                          std::uint64_t* __restrict memo) {
  const MeshGrid::ColumnTable t = c.mesh->grid.column_table();
  const double* center = c.aabb_center.data();
  const double* half = c.aabb_half.data();
  const __m512i sign = _mm512_set1_epi64(std::int64_t(0x8000000000000000ull));
  const __m256i dim_x = _mm256_set1_epi32(int(t.dim_x)), one = _mm256_set1_epi32(1);
  const __m256i byte = _mm256_set1_epi32(0xff);
  for (std::size_t k0 = 0; k0 < n; k0 += 8) {
    const std::size_t lanes = std::min<std::size_t>(8, n - k0);
    unsigned asked = 0;
    for (std::size_t j = 0; j < lanes; ++j) asked |= unsigned(pend[k0 + j] != 0) << j;
    if (asked == 0) continue;
    const __mmask8 m = __mmask8(asked);
    const __m512d g = _mm512_maskz_loadu_pd(m, b.grow + k0);
    __m512d lo[3], hi[3];
    __mmask8 in_aabb = m;
    for (int a = 0; a < 3; ++a) {
      lo[a] = _mm512_maskz_loadu_pd(m, b.lo[a] + k0);
      hi[a] = _mm512_maskz_loadu_pd(m, b.hi[a] + k0);
      const __m512d e = _mm512_add_pd(_mm512_set1_pd(half[a]), g);
      const __m512d neg_e = _mm512_castsi512_pd(_mm512_xor_epi64(_mm512_castpd_si512(e), sign));
      const __m512d ca = _mm512_set1_pd(center[a]);
      in_aabb &= _mm512_cmp_pd_mask(_mm512_sub_pd(lo[a], ca), e, _CMP_LE_OQ) &
                 _mm512_cmp_pd_mask(_mm512_sub_pd(hi[a], ca), neg_e, _CMP_GE_OQ);
    }
    if (in_aabb == 0) continue;
    __mmask8 kept = in_aabb;  // lanes whose columns do not clear them (so far: all)
    if (!t.empty) {
      __mmask8 outside = 0, ordered = 0xff;
      for (int a = 0; a < 3; ++a) {
        lo[a] = _mm512_sub_pd(lo[a], g);
        hi[a] = _mm512_add_pd(hi[a], g);
        outside |= _mm512_cmp_pd_mask(lo[a], _mm512_set1_pd(t.hi[a]), _CMP_GT_OQ) |
                   _mm512_cmp_pd_mask(hi[a], _mm512_set1_pd(t.lo[a]), _CMP_LT_OQ);
        ordered &= _mm512_cmp_pd_mask(lo[a], hi[a], _CMP_LE_OQ);
      }
      __mmask8 ask = in_aabb & __mmask8(~outside) & ordered;
      __m256i c0[2], c1[2];
      for (int a = 0; a < 2; ++a) {
        const __m512d origin = _mm512_set1_pd(t.lo[a]), inv = _mm512_set1_pd(t.inv_column);
        const __m512d last = _mm512_set1_pd(t.last[a]);
        c0[a] = column_cell(lo[a], origin, inv, last);
        c1[a] = column_cell(hi[a], origin, inv, last);
        ask &= _mm256_mask_cmp_epi32_mask(ask, _mm256_sub_epi32(c1[a], c0[a]), one, _MM_CMPINT_LE);
      }
      __mmask8 clear_lanes = outside;
      if (ask != 0) {
        const __m256i row0 = _mm256_mullo_epi32(c0[1], dim_x), row1 = _mm256_mullo_epi32(c1[1], dim_x);
        const __m256i none = _mm256_setzero_si256();
        const __m256i dx = _mm256_sub_epi32(c1[0], c0[0]), at0 = _mm256_add_epi32(row0, c0[0]);
        // The lanes' columns as ColumnMemo keys, and the lanes whose slot holds that key.
        const __m256i key = _mm256_or_si256(
            _mm256_or_si256(_mm256_slli_epi32(at0, 2), _mm256_slli_epi32(dx, 1)),
            _mm256_sub_epi32(c1[1], c0[1]));
        __m512i entry = _mm512_setzero_si512();
        __mmask8 hit = 0;
        if (memo != nullptr) {
          entry = _mm512_maskz_loadu_epi64(ask, memo + k0);
          hit = _mm256_mask_cmpeq_epi32_mask(ask, _mm512_maskz_cvtepi64_epi32(0xff, entry), key);
        }
        const __mmask8 miss = ask & __mmask8(~hit);
        __m256i qlo = _mm512_maskz_cvtepi64_epi32(0xff, _mm512_and_si512(_mm512_maskz_srli_epi64(0xff, entry, 32), _mm512_set1_epi64(0xff)));
        __m256i qhi = _mm512_maskz_cvtepi64_epi32(0xff, _mm512_and_si512(_mm512_maskz_srli_epi64(0xff, entry, 40), _mm512_set1_epi64(0xff)));
        if (miss != 0) {
          // Two gathers, not four: a word at a column holds its two bytes (low, high level) and
          // the next column's two, and the columns spanned on x are c0 and c0 or c0 + 1, so
          // the words at c0 of both rows hold all (at most) four; the second column's bytes are
          // those of a word shifted right by 16 (c1 = c0 + 1) or by 0 (c1 = c0: the same column
          // twice, which changes no minimum or maximum).
          const __m256i shift = _mm256_slli_epi32(dx, 4);
          const __m256i w00 = _mm256_mmask_i32gather_epi32(none, miss, at0, t.column, 2);
          const __m256i w01 = _mm256_mmask_i32gather_epi32(none, miss, _mm256_add_epi32(row1, c0[0]), t.column, 2);
          const __m256i w10 = _mm256_srlv_epi32(w00, shift), w11 = _mm256_srlv_epi32(w01, shift);
          // (Macros: a lambda here would not take this function's target.)
#define SIMREEL_LOW(w) _mm256_and_si256(w, byte)
#define SIMREEL_HIGH(w) _mm256_and_si256(_mm256_srli_epi32(w, 8), byte)
          const __m256i lo_q = _mm256_min_epu32(_mm256_min_epu32(SIMREEL_LOW(w00), SIMREEL_LOW(w10)),
                                                _mm256_min_epu32(SIMREEL_LOW(w01), SIMREEL_LOW(w11)));
          const __m256i hi_q = _mm256_max_epu32(_mm256_max_epu32(SIMREEL_HIGH(w00), SIMREEL_HIGH(w10)),
                                                _mm256_max_epu32(SIMREEL_HIGH(w01), SIMREEL_HIGH(w11)));
#undef SIMREEL_LOW
#undef SIMREEL_HIGH
          qlo = _mm256_mask_blend_epi32(miss, qlo, lo_q);
          qhi = _mm256_mask_blend_epi32(miss, qhi, hi_q);
          if (memo != nullptr) {
            const __m512i fresh = _mm512_or_si512(
                _mm512_maskz_cvtepu32_epi64(0xff, key),
                _mm512_or_si512(_mm512_maskz_slli_epi64(0xff, _mm512_maskz_cvtepu32_epi64(0xff, lo_q), 32),
                                _mm512_maskz_slli_epi64(0xff, _mm512_maskz_cvtepu32_epi64(0xff, hi_q), 40)));
            _mm512_mask_storeu_epi64(memo + k0, miss, fresh);
          }
        }
        const __m512d level_hi = level_lanes(qhi, t);
        const __m512d level_lo = level_lanes(qlo, t);
        clear_lanes |= ask & (_mm512_cmp_pd_mask(lo[2], level_hi, _CMP_GT_OQ) |
                              _mm512_cmp_pd_mask(hi[2], level_lo, _CMP_LT_OQ));
      }
      kept &= __mmask8(~clear_lanes);
    }
    for (unsigned r = kept; r != 0; r &= r - 1) clear[k0 + std::size_t(std::countr_zero(r))] = 0;
  }
}

/// Lanes k of a 4-bit mask as all-ones 64-bit lanes (for masked loads and double gathers).
__attribute__((target("avx2"), always_inline)) inline __m256i mask_lanes64(unsigned bits) {
  const __m256i bit = _mm256_setr_epi64x(1, 2, 4, 8);
  return _mm256_cmpeq_epi64(_mm256_and_si256(_mm256_set1_epi64x(std::int64_t(bits)), bit), bit);
}

/// The same as 32-bit lanes (for int gathers).
__attribute__((target("avx2"), always_inline)) inline __m128i mask_lanes32(unsigned bits) {
  const __m128i bit = _mm_setr_epi32(1, 2, 4, 8);
  return _mm_cmpeq_epi32(_mm_and_si128(_mm_set1_epi32(int(bits)), bit), bit);
}

/// column_cell() in AVX2's four lanes.
__attribute__((target("avx2"), always_inline)) inline __m128i column_cell4(__m256d v, __m256d origin,
                                                                          __m256d inv, __m256d last) {
  const __m256d zero = _mm256_setzero_pd();
  v = _mm256_mul_pd(_mm256_sub_pd(v, origin), inv);
  v = _mm256_blendv_pd(v, zero, _mm256_cmp_pd(v, zero, _CMP_LT_OQ));
  v = _mm256_blendv_pd(v, last, _mm256_cmp_pd(last, v, _CMP_LT_OQ));
  return _mm256_cvttpd_epi32(v);
}

/// level_lanes() in AVX2's four lanes.
__attribute__((target("avx2"), always_inline)) inline __m256d level_lanes4(
    __m128i q, const MeshGrid::ColumnTable& t) {
  const __m256d z = _mm256_add_pd(_mm256_set1_pd(t.level_z0),
                                  _mm256_mul_pd(_mm256_cvtepi32_pd(q), _mm256_set1_pd(t.level_step)));
  const __m256d at0 = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(_mm_cmpeq_epi32(q, _mm_setzero_si128())));
  const __m256d at255 = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(_mm_cmpeq_epi32(q, _mm_set1_epi32(255))));
  const __m256d lowest =
      _mm256_blendv_pd(z, _mm256_set1_pd(-std::numeric_limits<double>::infinity()), at0);
  return _mm256_blendv_pd(lowest, _mm256_set1_pd(std::numeric_limits<double>::infinity()), at255);
}

/// The compare of four doubles as a 4-bit mask.
__attribute__((target("avx2"), always_inline)) inline unsigned bits4(__m256d m) {
  return unsigned(_mm256_movemask_pd(m));
}

/// columns_clear_avx512() four particles at a time with AVX2, for CPUs without AVX-512: the
/// same operations in each lane and the same order of the early answers, the lane masks kept as
/// four bits (movemask) and widened to vectors for the masked loads and gathers. On the AMD
/// EPYC the scalar loop's branches held a quarter of the rain benchmark's time.
__attribute__((target("avx2")))
void columns_clear_avx2(const SweptBounds& b, std::size_t n, const Collider& c,
                        const std::uint8_t* __restrict pend, std::uint8_t* __restrict clear,
                        std::uint64_t* __restrict memo) {
  const MeshGrid::ColumnTable t = c.mesh->grid.column_table();
  const double* center = c.aabb_center.data();
  const double* half = c.aabb_half.data();
  const __m256d sign = _mm256_castsi256_pd(_mm256_set1_epi64x(std::int64_t(0x8000000000000000ull)));
  const __m128i dim_x = _mm_set1_epi32(int(t.dim_x)), one = _mm_set1_epi32(1);
  for (std::size_t k0 = 0; k0 < n; k0 += 4) {
    const std::size_t lanes = std::min<std::size_t>(4, n - k0);
    unsigned asked = 0;
    for (std::size_t j = 0; j < lanes; ++j) asked |= unsigned(pend[k0 + j] != 0) << j;
    if (asked == 0) continue;
    // A whole block by plain loads (the lanes not asked hold other particles' bounds and are
    // masked out below), a last part by masked ones (past n nothing was written). Masked loads
    // are slow on AMD Zen 1 (docs/benchmarks.md, stop 86).
    const bool whole = lanes == 4;
    const __m256i m = mask_lanes64(asked);
    const __m256d g = whole ? _mm256_loadu_pd(b.grow + k0) : _mm256_maskload_pd(b.grow + k0, m);
    __m256d lo[3], hi[3];
    unsigned in_aabb = asked;
    for (int a = 0; a < 3; ++a) {
      lo[a] = whole ? _mm256_loadu_pd(b.lo[a] + k0) : _mm256_maskload_pd(b.lo[a] + k0, m);
      hi[a] = whole ? _mm256_loadu_pd(b.hi[a] + k0) : _mm256_maskload_pd(b.hi[a] + k0, m);
      const __m256d e = _mm256_add_pd(_mm256_set1_pd(half[a]), g);
      const __m256d neg_e = _mm256_xor_pd(e, sign);
      const __m256d ca = _mm256_set1_pd(center[a]);
      in_aabb &= bits4(_mm256_cmp_pd(_mm256_sub_pd(lo[a], ca), e, _CMP_LE_OQ)) &
                 bits4(_mm256_cmp_pd(_mm256_sub_pd(hi[a], ca), neg_e, _CMP_GE_OQ));
    }
    if (in_aabb == 0) continue;
    unsigned kept = in_aabb;  // lanes whose columns do not clear them (so far: all)
    if (!t.empty) {
      unsigned outside = 0, ordered = 0xf;
      for (int a = 0; a < 3; ++a) {
        lo[a] = _mm256_sub_pd(lo[a], g);
        hi[a] = _mm256_add_pd(hi[a], g);
        outside |= bits4(_mm256_cmp_pd(lo[a], _mm256_set1_pd(t.hi[a]), _CMP_GT_OQ)) |
                   bits4(_mm256_cmp_pd(hi[a], _mm256_set1_pd(t.lo[a]), _CMP_LT_OQ));
        ordered &= bits4(_mm256_cmp_pd(lo[a], hi[a], _CMP_LE_OQ));
      }
      unsigned ask = in_aabb & ~outside & ordered;
      __m128i c0[2], c1[2];
      for (int a = 0; a < 2; ++a) {
        const __m256d origin = _mm256_set1_pd(t.lo[a]), inv = _mm256_set1_pd(t.inv_column);
        const __m256d last = _mm256_set1_pd(t.last[a]);
        c0[a] = column_cell4(lo[a], origin, inv, last);
        c1[a] = column_cell4(hi[a], origin, inv, last);
        ask &= ~unsigned(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(_mm_sub_epi32(c1[a], c0[a]), one))));
      }
      unsigned clear_lanes = outside;
      if (ask != 0) {
        // Four lanes one by one: AVX2's gathers cost more than the loads on the AMD EPYC. A
        // lane's ColumnMemo slot answers when it holds the lane's key; else two words (as in
        // columns_clear_avx512(): the second column's bytes are a word's shifted right by 16
        // when c1 = c0 + 1, by 0 when c1 = c0), and the slot takes their answer.
        alignas(16) std::int32_t at0[4], at1[4], dx[4], key[4], ql[4], qh[4];
        const __m128i row0 = _mm_mullo_epi32(c0[1], dim_x), row1 = _mm_mullo_epi32(c1[1], dim_x);
        const __m128i d = _mm_sub_epi32(c1[0], c0[0]), a0 = _mm_add_epi32(row0, c0[0]);
        _mm_store_si128(reinterpret_cast<__m128i*>(at0), a0);
        _mm_store_si128(reinterpret_cast<__m128i*>(at1), _mm_add_epi32(row1, c0[0]));
        _mm_store_si128(reinterpret_cast<__m128i*>(dx), d);
        _mm_store_si128(reinterpret_cast<__m128i*>(key),
                        _mm_or_si128(_mm_or_si128(_mm_slli_epi32(a0, 2), _mm_slli_epi32(d, 1)),
                                     _mm_sub_epi32(c1[1], c0[1])));
        for (int j = 0; j < 4; ++j) {
          ql[j] = qh[j] = 0;
          if ((ask >> j & 1u) == 0) continue;
          const std::uint64_t e = memo != nullptr ? memo[k0 + std::size_t(j)] : ColumnMemo::kNone;
          if (std::uint32_t(e) == std::uint32_t(key[j])) {
            ql[j] = std::int32_t(e >> 32 & 0xff);
            qh[j] = std::int32_t(e >> 40 & 0xff);
            continue;
          }
          std::uint32_t w00, w01;
          std::memcpy(&w00, t.column + 2 * std::ptrdiff_t(at0[j]), 4);
          std::memcpy(&w01, t.column + 2 * std::ptrdiff_t(at1[j]), 4);
          const unsigned sh = 16u * unsigned(dx[j]);
          const std::uint32_t w10 = w00 >> sh, w11 = w01 >> sh;
          ql[j] = std::int32_t(std::min(std::min(w00 & 0xff, w10 & 0xff), std::min(w01 & 0xff, w11 & 0xff)));
          qh[j] = std::int32_t(std::max(std::max(w00 >> 8 & 0xff, w10 >> 8 & 0xff),
                                        std::max(w01 >> 8 & 0xff, w11 >> 8 & 0xff)));
          if (memo != nullptr)
            memo[k0 + std::size_t(j)] = std::uint64_t(std::uint32_t(key[j])) |
                                        std::uint64_t(ql[j]) << 32 | std::uint64_t(qh[j]) << 40;
        }
        const __m128i qlo = _mm_load_si128(reinterpret_cast<const __m128i*>(ql));
        const __m128i qhi = _mm_load_si128(reinterpret_cast<const __m128i*>(qh));
        const __m256d level_hi = level_lanes4(qhi, t);
        const __m256d level_lo = level_lanes4(qlo, t);
        clear_lanes |= ask & (bits4(_mm256_cmp_pd(lo[2], level_hi, _CMP_GT_OQ)) |
                              bits4(_mm256_cmp_pd(hi[2], level_lo, _CMP_LT_OQ)));
      }
      kept &= ~clear_lanes;
    }
    for (unsigned r = kept; r != 0; r &= r - 1) clear[k0 + std::size_t(std::countr_zero(r))] = 0;
  }
}
#endif
}  // namespace

std::uint64_t* column_memo_slots(const std::vector<Collider>& colliders, std::size_t n,
                                 const Collider*& mesh) {
  thread_local ColumnMemo memo;
  mesh = nullptr;
  for (const Collider& c : colliders)
    if (column_tested(c)) {
      mesh = &c;
      return memo.for_grid(c.mesh->grid, n);
    }
  return nullptr;
}

void columns_clear_block(const SweptBounds& b, std::size_t n, const Collider& c,
                         const std::uint8_t* __restrict pend, std::uint8_t* __restrict clear,
                         int lanes, std::uint64_t* __restrict memo) {
#if SIMREEL_HAS_VECTOR_CLONES
  static const bool avx512 = cpu_has_avx512vl();
  static const bool avx2 = cpu_has_avx2();
  const MeshGrid::ColumnTable t = c.mesh->grid.column_table();
  // The lanes' column index is a 32-bit integer.
  const bool fits = (t.last[0] + 1.0) * (t.last[1] + 1.0) < 0x1p30;
  if (lanes >= 8 && avx512 && fits) {
    columns_clear_avx512(b, n, c, pend, clear, memo);
    return;
  }
  if (lanes >= 4 && avx2 && fits) {
    // A block the collide memo mostly answered (a settled scene) asks for a few particles,
    // each then alone in its four lanes: one at a time is faster there.
    std::size_t asked = 0;
    for (std::size_t k = 0; k < n; ++k) asked += pend[k] != 0;
    if (4 * asked >= n) {
      columns_clear_avx2(b, n, c, pend, clear, memo);
      return;
    }
  }
#else
  (void)lanes;
  (void)memo;
#endif
  columns_clear_scalar(b, n, c, pend, clear);
}

/// The per-particle scalars of gather_block(): mass, radius and each lane's step min(age, h).
SIMREEL_VECTOR_CLONES
void gather_scalars(const float* __restrict mass, const float* __restrict radius,
                    const float* __restrict age, double h, std::size_t len, PlaneRestLanes& l) {
  for (std::size_t k = 0; k < len; ++k) {
    l.m[k] = mass[k];
    l.r[k] = radius[k];
    const double a = age[k];
    l.dt[k] = h < a ? h : a;  // std::min(a, h)
  }
}

/// True when particles [0, len) (len >= 1) share mass[0] and radius[0] bit for bit and are all at
/// least `step_floor` old (so each one's step min(age, h) is h): then their lanes' m, r and dt
/// are lane 0's, bit for bit (a float's bits give its double's). Read from the stored floats in
/// one pass, which costs less than filling every lane's doubles and comparing those.
SIMREEL_VECTOR_CLONES
bool shared_scalars(const float* __restrict mass, const float* __restrict radius,
                    const float* __restrict age, float step_floor, std::size_t len) {
  const std::uint32_t m0 = __builtin_bit_cast(std::uint32_t, mass[0]);
  const std::uint32_t r0 = __builtin_bit_cast(std::uint32_t, radius[0]);
  std::uint32_t diff = 0;
  for (std::size_t k = 0; k < len; ++k)
    diff |= (__builtin_bit_cast(std::uint32_t, mass[k]) ^ m0) |
            (__builtin_bit_cast(std::uint32_t, radius[k]) ^ r0) |
            std::uint32_t(!(age[k] >= step_floor));  // NaN: not shared
  return diff == 0;
}

/// The least float a with double(a) >= h (+inf where no finite float reaches h): for a float age,
/// age >= step_floor(h) exactly when double(age) >= h.
float step_floor(double h) {
  float t = float(h);
  if (double(t) < h) t = std::nextafter(t, std::numeric_limits<float>::infinity());
  return t;
}

/// Lanes [0, len) of `l` from a block of particles (x, v: len x 3; prev: the start-of-step
/// positions or null; mass, radius, age: len), each lane's step min(age, h). The rows go
/// through rows_to_columns(), whose AVX2 form does not take them apart value by value.
void gather_block(const float* __restrict x, const float* __restrict v,
                  const float* __restrict prev, const float* __restrict mass,
                  const float* __restrict radius, const float* __restrict age, double h,
                  std::size_t len, PlaneRestLanes& l) {
  rows_to_columns(x, len, l.bx, l.by, l.bz);
  rows_to_columns(v, len, l.vx, l.vy, l.vz);
  l.shared = len > 0 && shared_scalars(mass, radius, age, step_floor(h), len);
  if (l.shared) {
    l.m[0] = mass[0];
    l.r[0] = radius[0];
    l.dt[0] = h;
  } else {
    gather_scalars(mass, radius, age, h, len, l);
  }
  if (prev != nullptr) rows_to_columns(prev, len, l.ax, l.ay, l.az);
}

/// The lanes' outputs back into the block (x, v: len x 3): the results of the lanes that
/// plane_rest() resolved, the others' values as they were.
void scatter_block(const PlaneRestLanes& l, std::size_t len, float* __restrict x,
                   float* __restrict v) {
  columns_to_rows(l.ox, l.oy, l.oz, len, x);
  columns_to_rows(l.ovx, l.ovy, l.ovz, len, v);
}

SIMREEL_VECTOR_CLONES
bool all_resolved_outside(const PlaneRestLanes& l, std::size_t len) {
  unsigned open = 0;
  for (std::size_t k = 0; k < len; ++k) open |= unsigned(l.ok[k] != 1.0f);
  return open == 0;
}

/// near[k] = 1 when lane k of `l` ends the step closer than its radius to the plane (the test of
/// near_planes(), on the same values).
SIMREEL_VECTOR_CLONES
void near_lanes(const PlaneRestLanes& l, std::size_t len, const PlaneRestParams& p,
                std::uint8_t* __restrict near) {
  const double n0 = p.n[0], n1 = p.n[1], n2 = p.n[2], q0 = p.q[0], q1 = p.q[1], q2 = p.q[2];
  const bool shared = l.shared;
  for (std::size_t k = 0; k < len; ++k)
    near[k] = std::uint8_t(n0 * (l.bx[k] - q0) + n1 * (l.by[k] - q1) + n2 * (l.bz[k] - q2) -
                               l.r[shared ? 0 : k] < 0.0);
}

}  // namespace simreel::sim::detail
