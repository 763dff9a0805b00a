// The pair lists of the pair forces' dense grid (pair_lists.hpp): scalar, AVX-512VL and AVX2
// forms, each the scalar test's operations in every lane.
#include "particles/pair_lists.hpp"

#include <algorithm>
#include <bit>

#include "core/compress_avx2.hpp"
#include "core/vector_clones.hpp"

#if SIMREEL_HAS_VECTOR_CLONES
#include <immintrin.h>
#endif

namespace simreel::sim::detail {

namespace {

/// Appends the pairs (si, cs[u]) with r2[u] < cut2 (false for NaN), u < len, to (pi, pj, pr2)
/// from place p, in candidate order; returns the new count. The order is the scalar loop's, so
/// which form runs changes nothing but time. The AVX-512 form compresses eight candidates at a
/// time in registers (a store per array per eight, against one per candidate: the scalar loop
/// was ~15 % of the pair-force step); it reads up to 7 elements past len and writes up to 8
/// past the result, which the callers' slack covers.
std::size_t append_within_scalar(std::uint32_t si, const std::uint32_t* __restrict cs,
                                 const double* __restrict r2, std::size_t len, double cut2,
                                 std::uint32_t* __restrict pi, std::uint32_t* __restrict pj,
                                 double* __restrict pr2, std::size_t p) {
  // Branch-free: every candidate is written at the end of the list, which grows only when it
  // lies within the cut-off.
  for (std::size_t u = 0; u < len; ++u) {
    pi[p] = si;
    pj[p] = cs[u];
    pr2[p] = r2[u];
    p += std::size_t(r2[u] < cut2);
  }
  return p;
}

#if SIMREEL_HAS_VECTOR_CLONES
__attribute__((target("avx512f,avx512vl")))
std::size_t append_within_avx512(std::uint32_t si, const std::uint32_t* __restrict cs,
                                 const double* __restrict r2, std::size_t len, double cut2,
                                 std::uint32_t* __restrict pi, std::uint32_t* __restrict pj,
                                 double* __restrict pr2, std::size_t p) {
  const __m512d c = _mm512_set1_pd(cut2);
  const __m256i vi = _mm256_set1_epi32(int(si));
  for (std::size_t u = 0; u < len; u += 8) {
    const __m512d d = _mm512_loadu_pd(r2 + u);
    __mmask8 k = _mm512_cmp_pd_mask(d, c, _CMP_LT_OQ);
    if (len - u < 8) k = __mmask8(k & ((1u << (len - u)) - 1u));
    const __m256i j = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(cs + u));
    _mm512_storeu_pd(pr2 + p, _mm512_maskz_compress_pd(k, d));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(pj + p), _mm256_maskz_compress_epi32(k, j));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(pi + p), vi);
    p += std::size_t(std::popcount(unsigned(k)));
  }
  return p;
}

/// Appends (si, u + l) with r2 < cut2, l < min(left, 8), from place p: eight candidates of the
/// sorted arrays from u, under a lane mask (masked lanes load nothing, so nothing is read past
/// the run). The squared distance is the scalar's ((dx² + dy²) + dz², no contraction). Writes up
/// to 8 entries past the result.
__attribute__((target("avx512f,avx512vl"), always_inline)) inline std::size_t
block_pairs_avx512(__m512d xi, __m512d yi, __m512d zi, __m256i vi, __m512d cut2,
                   const double* __restrict sx, const double* __restrict sy,
                   const double* __restrict sz, std::uint32_t u, std::uint32_t left,
                   std::uint32_t* __restrict pi, std::uint32_t* __restrict pj,
                   double* __restrict pr2, std::size_t p) {
  const __mmask8 lane = __mmask8(0xffu >> (8u - std::min(left, 8u)));
  const __m512d dx = _mm512_sub_pd(xi, _mm512_maskz_loadu_pd(lane, sx + u));
  const __m512d dy = _mm512_sub_pd(yi, _mm512_maskz_loadu_pd(lane, sy + u));
  const __m512d dz = _mm512_sub_pd(zi, _mm512_maskz_loadu_pd(lane, sz + u));
  const __m512d d =
      _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)), _mm512_mul_pd(dz, dz));
  const __mmask8 k = _mm512_mask_cmp_pd_mask(lane, d, cut2, _CMP_LT_OQ);
  const __m256i j = _mm256_add_epi32(_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
                                     _mm256_set1_epi32(int(u)));
  _mm512_storeu_pd(pr2 + p, _mm512_maskz_compress_pd(k, d));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(pj + p), _mm256_maskz_compress_epi32(k, j));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(pi + p), vi);
  return p + std::size_t(std::popcount(unsigned(k)));
}

/// The dense grid's pairs of one cell's particles si in [first, last), appended from place p as
/// the copy-and-append path records them: for each si in turn, the candidates of runs 0..4 of
/// cell order (run 0 from si + 1, the runs [rb[r], re[r]) otherwise), those with
/// |x_si - x_s|² < cut2 in ascending s; so the same pairs, in the same order, with the same r2,
/// and the same bits in the forces. It reads the sorted arrays in place, where the other path
/// first copies the runs into one candidate list: those copies were ~18 % of the pair forces'
/// time at ~2 particles a cell, and this path takes 4-7 % less time in all (100k particles, on
/// an AVX-512 Xeon). Writes up to 8 entries past the result, as append_within_avx512().
__attribute__((target("avx512f,avx512vl")))
std::size_t cell_pairs_avx512(const double* __restrict sx, const double* __restrict sy,
                              const double* __restrict sz, std::uint32_t first,
                              std::uint32_t last, const std::uint32_t* rb,
                              const std::uint32_t* re, double cut2, std::uint32_t* __restrict pi,
                              std::uint32_t* __restrict pj, double* __restrict pr2,
                              std::size_t p) {
  const __m512d c = _mm512_set1_pd(cut2);
  for (std::uint32_t si = first; si < last; ++si) {
    const __m512d xi = _mm512_set1_pd(sx[si]), yi = _mm512_set1_pd(sy[si]),
                  zi = _mm512_set1_pd(sz[si]);
    const __m256i vi = _mm256_set1_epi32(int(si));
    // A run is ~6 particles here: its first block is taken unconditionally (an empty one under
    // an empty mask), so that only runs longer than a block branch.
    for (int r = 0; r < 5; ++r) {
      const std::uint32_t b = r == 0 ? si + 1 : rb[r], len = re[r] - b;
      p = block_pairs_avx512(xi, yi, zi, vi, c, sx, sy, sz, b, len, pi, pj, pr2, p);
      for (std::uint32_t u = 8; u < len; u += 8)
        p = block_pairs_avx512(xi, yi, zi, vi, c, sx, sy, sz, b + u, len - u, pi, pj, pr2, p);
    }
  }
  return p;
}

/// append_within_avx512() four candidates at a time with AVX2 (for CPUs without AVX-512): the
/// kept ones moved to the front by a table (core/compress_avx2.hpp); the last one to three as
/// the scalar form. Writes up to 4 entries past the result.
__attribute__((target("avx2")))
std::size_t append_within_avx2(std::uint32_t si, const std::uint32_t* __restrict cs,
                               const double* __restrict r2, std::size_t len, double cut2,
                               std::uint32_t* __restrict pi, std::uint32_t* __restrict pj,
                               double* __restrict pr2, std::size_t p) {
  const __m256d c = _mm256_set1_pd(cut2);
  const __m128i vi = _mm_set1_epi32(int(si));
  std::size_t u = 0;
  for (; u + 4 <= len; u += 4) {
    const __m256d d = _mm256_loadu_pd(r2 + u);
    const int k = _mm256_movemask_pd(_mm256_cmp_pd(d, c, _CMP_LT_OQ));
    compress_store4(pr2 + p, d, k);
    compress_store4(pj + p, _mm_loadu_si128(reinterpret_cast<const __m128i*>(cs + u)), k);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(pi + p), vi);
    p += std::size_t(std::popcount(unsigned(k)));
  }
  return append_within_scalar(si, cs + u, r2 + u, len - u, cut2, pi, pj, pr2, p);
}

/// block_pairs_avx512() for four candidates with AVX2: lanes past `left` are loaded but not kept
/// (reads up to 3 doubles past a run: see CellPairs). A plain load, not a masked one: on AMD Zen 1
/// the masked loads made the whole pair-force step 18-22 % slower (docs/benchmarks.md, stop 86).
/// Writes up to 4 entries past the result.
__attribute__((target("avx2"), always_inline)) inline std::size_t
block_pairs_avx2(__m256d xi, __m256d yi, __m256d zi, __m128i vi, __m256d cut2,
                 const double* __restrict sx, const double* __restrict sy,
                 const double* __restrict sz, std::uint32_t u, std::uint32_t left,
                 std::uint32_t* __restrict pi, std::uint32_t* __restrict pj,
                 double* __restrict pr2, std::size_t p) {
  const __m256i lane = live_lanes4(left);
  const __m256d dx = _mm256_sub_pd(xi, _mm256_loadu_pd(sx + u));
  const __m256d dy = _mm256_sub_pd(yi, _mm256_loadu_pd(sy + u));
  const __m256d dz = _mm256_sub_pd(zi, _mm256_loadu_pd(sz + u));
  const __m256d d =
      _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
  const int k = _mm256_movemask_pd(_mm256_and_pd(_mm256_cmp_pd(d, cut2, _CMP_LT_OQ), _mm256_castsi256_pd(lane)));
  compress_store4(pr2 + p, d, k);
  compress_store4(pj + p, lane_indices4(u), k);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(pi + p), vi);
  return p + std::size_t(std::popcount(unsigned(k)));
}

/// cell_pairs_avx512() with AVX2's four lanes (block_pairs_avx2()): the same pairs in the same
/// order. Writes up to 4 entries past the result.
__attribute__((target("avx2")))
std::size_t cell_pairs_avx2(const double* __restrict sx, const double* __restrict sy,
                            const double* __restrict sz, std::uint32_t first,
                            std::uint32_t last, const std::uint32_t* rb,
                            const std::uint32_t* re, double cut2, std::uint32_t* __restrict pi,
                            std::uint32_t* __restrict pj, double* __restrict pr2,
                            std::size_t p) {
  const __m256d c = _mm256_set1_pd(cut2);
  for (std::uint32_t si = first; si < last; ++si) {
    const __m256d xi = _mm256_set1_pd(sx[si]), yi = _mm256_set1_pd(sy[si]), zi = _mm256_set1_pd(sz[si]);
    const __m128i vi = _mm_set1_epi32(int(si));
    for (int r = 0; r < 5; ++r) {
      const std::uint32_t b = r == 0 ? si + 1 : rb[r], len = re[r] - b;
      p = block_pairs_avx2(xi, yi, zi, vi, c, sx, sy, sz, b, len, pi, pj, pr2, p);
      for (std::uint32_t u = 4; u < len; u += 4)
        p = block_pairs_avx2(xi, yi, zi, vi, c, sx, sy, sz, b + u, len - u, pi, pj, pr2, p);
    }
  }
  return p;
}

#endif

}  // namespace

AppendWithin append_within(int lanes) {
#if SIMREEL_HAS_VECTOR_CLONES
  if (lanes >= 8) return &append_within_avx512;
  if (lanes >= 4) return &append_within_avx2;
#endif
  (void)lanes;
  return &append_within_scalar;
}


CellPairs cell_pairs(int lanes) {
#if SIMREEL_HAS_VECTOR_CLONES
  if (lanes >= 8) return &cell_pairs_avx512;
  if (lanes >= 4) return &cell_pairs_avx2;
#endif
  (void)lanes;
  return nullptr;
}

}  // namespace simreel::sim::detail
