// Four-lane compress for AVX2 (which lacks AVX-512's vcompress): the lanes of a compare mask
// moved to the front, in order, by a table of permutations. The pair searches' AVX2 forms use it
// where AVX-512VL's eight lanes are missing (particle_pairs.cpp, pair_forces.cpp).
#pragma once

#include "core/vector_clones.hpp"

#if SIMREEL_HAS_VECTOR_CLONES
#include <immintrin.h>

#include <cstddef>
#include <cstdint>

namespace simreel::sim::detail {

/// Entry `mask` (bits of a four-lane compare mask) holds, for each kept lane j in turn, its
/// 32-bit lanes: doubles 2j and 2j + 1 (vpermd), 32-bit integers j (vpermilps); the rest repeat
/// lane 0 (stored past the count, in the callers' slack).
struct Compress4Table {
  alignas(32) std::int32_t d[16][8];
  alignas(16) std::int32_t u[16][4];
};

constexpr Compress4Table make_compress4_table() {
  Compress4Table t{};
  for (int mask = 0; mask < 16; ++mask) {
    int k = 0;
    for (int j = 0; j < 4; ++j)
      if (mask & (1 << j)) {
        t.d[mask][2 * k] = 2 * j;
        t.d[mask][2 * k + 1] = 2 * j + 1;
        t.u[mask][k] = j;
        ++k;
      }
    for (; k < 4; ++k) t.d[mask][2 * k] = 0, t.d[mask][2 * k + 1] = 1, t.u[mask][k] = 0;
  }
  return t;
}

inline constexpr Compress4Table kCompress4 = make_compress4_table();

/// Stores the lanes of v kept by mask (bits 0-3) at out, in order; writes 4 doubles.
__attribute__((target("avx2"), always_inline)) inline void compress_store4(double* out, __m256d v, int mask) {
  const __m256i perm = _mm256_load_si256(reinterpret_cast<const __m256i*>(kCompress4.d[mask]));
  _mm256_storeu_pd(out, _mm256_castsi256_pd(_mm256_permutevar8x32_epi32(_mm256_castpd_si256(v), perm)));
}

/// Stores the 32-bit lanes of v kept by mask (bits 0-3) at out, in order; writes 4.
__attribute__((target("avx2"), always_inline)) inline void compress_store4(std::uint32_t* out, __m128i v, int mask) {
  const __m128i perm = _mm_load_si128(reinterpret_cast<const __m128i*>(kCompress4.u[mask]));
  _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm_castps_si128(_mm_permutevar_ps(_mm_castsi128_ps(v), perm)));
}

/// All ones in the first min(left, 4) 64-bit lanes, zero in the rest: a mask for
/// _mm256_maskload_pd (masked lanes read nothing) and for the compare.
__attribute__((target("avx2"), always_inline)) inline __m256i live_lanes4(std::size_t left) {
  return _mm256_cmpgt_epi64(_mm256_set1_epi64x(std::int64_t(left < 4 ? left : 4)), _mm256_setr_epi64x(0, 1, 2, 3));
}

/// {base, base + 1, base + 2, base + 3}.
__attribute__((target("avx2"), always_inline)) inline __m128i lane_indices4(std::uint32_t base) {
  return _mm_add_epi32(_mm_set1_epi32(int(base)), _mm_setr_epi32(0, 1, 2, 3));
}

}  // namespace simreel::sim::detail
#endif

namespace simreel::sim::detail {

/// The widest compress this CPU runs, checked once: 8 (AVX-512VL's vcompress), 4 (AVX2 and the
/// tables above) or 1 (one element at a time; also without SIMREEL_VECTOR_CLONES).
inline int compress_width() {
#if SIMREEL_HAS_VECTOR_CLONES
  static const int w = cpu_has_avx512vl() ? 8 : cpu_has_avx2() ? 4 : 1;
  return w;
#else
  return 1;
#endif
}

}  // namespace simreel::sim::detail
