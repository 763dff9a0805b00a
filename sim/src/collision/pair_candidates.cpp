// The pair search's candidate tests (pair_candidates.hpp): scalar, AVX-512VL and AVX2 forms.
#include "collision/pair_candidates.hpp"

#include <bit>

#include "core/compress_avx2.hpp"
#include "core/vector_clones.hpp"

#if SIMREEL_HAS_VECTOR_CLONES
#include <immintrin.h>
#endif

namespace simreel::sim::detail {

SIMREEL_VECTOR_CLONES
void within_reach(double xi, double yi, double zi, double ri, double margin,
                  const double* __restrict cx, const double* __restrict cy,
                  const double* __restrict cz, const double* __restrict cr, std::size_t m,
                  double* __restrict d2) {
  for (std::size_t k = 0; k < m; ++k) {
    const double dx = cx[k] - xi, dy = cy[k] - yi, dz = cz[k] - zi;
    const double e = dx * dx + dy * dy + dz * dz;
    const double rj = cr[k];
    const double reach = ri + rj + margin * (rj < ri ? rj : ri);
    d2[k] = e < reach * reach && e > 0.0 ? e : 0.0;
  }
}

namespace {

/// Writes the sorted positions s in the runs [rb[u], re[u]) (u < runs, in order) that are not
/// farther than box.reach past the box along any axis (fl(c - hi) <= reach and fl(lo - c) <=
/// reach on x, y and z) to the candidate arrays (cs: s; cx, cy, cz, cr: its position and
/// radius), in order; returns the count. Which form runs changes nothing but time. The AVX-512
/// form tests eight at a time and compresses in registers; it writes up to 8 entries past the
/// result (the callers' slack). All of a cell's runs in one call: one call per cell, not per run.
std::size_t gather_in_box_scalar(const std::uint32_t* rb, const std::uint32_t* re, int runs,
                                 const double* __restrict px, const double* __restrict py,
                                 const double* __restrict pz, const double* __restrict pr,
                                 const ReachBox& box, std::uint32_t* __restrict cs,
                                 double* __restrict cx, double* __restrict cy,
                                 double* __restrict cz, double* __restrict cr) {
  std::size_t k = 0;
  // Branch-free: every position is written at the end of the list, which grows only when kept.
  for (int u = 0; u < runs; ++u) {
    for (std::uint32_t s = rb[u], e = re[u]; s < e; ++s) {
      const double x = px[s], y = py[s], z = pz[s];
      cs[k] = s;
      cx[k] = x;
      cy[k] = y;
      cz[k] = z;
      cr[k] = pr[s];
      k += std::size_t((x - box.hx <= box.reach) & (box.lx - x <= box.reach) &
                       (y - box.hy <= box.reach) & (box.ly - y <= box.reach) &
                       (z - box.hz <= box.reach) & (box.lz - z <= box.reach));
    }
  }
  return k;
}

#if SIMREEL_HAS_VECTOR_CLONES
__attribute__((target("avx512f,avx512vl")))
std::size_t gather_in_box_avx512(const std::uint32_t* rb, const std::uint32_t* re, int runs,
                                 const double* __restrict px, const double* __restrict py,
                                 const double* __restrict pz, const double* __restrict pr,
                                 const ReachBox& box, std::uint32_t* __restrict cs,
                                 double* __restrict cx, double* __restrict cy,
                                 double* __restrict cz, double* __restrict cr) {
  std::size_t k = 0;
  const __m512d hx = _mm512_set1_pd(box.hx), hy = _mm512_set1_pd(box.hy), hz = _mm512_set1_pd(box.hz);
  const __m512d lx = _mm512_set1_pd(box.lx), ly = _mm512_set1_pd(box.ly), lz = _mm512_set1_pd(box.lz);
  const __m512d reach = _mm512_set1_pd(box.reach);
  const __m256i step = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  for (int u = 0; u < runs; ++u) {
    for (std::uint32_t s = rb[u], e = re[u]; s < e; s += 8) {
      // Masked loads: nothing read past e.
      const __mmask8 live = e - s >= 8 ? __mmask8(0xff) : __mmask8((1u << (e - s)) - 1u);
      const __m512d x = _mm512_maskz_loadu_pd(live, px + s), y = _mm512_maskz_loadu_pd(live, py + s);
      const __m512d z = _mm512_maskz_loadu_pd(live, pz + s), r = _mm512_maskz_loadu_pd(live, pr + s);
      __mmask8 keep = live;
      keep &= _mm512_cmp_pd_mask(_mm512_sub_pd(x, hx), reach, _CMP_LE_OQ);
      keep &= _mm512_cmp_pd_mask(_mm512_sub_pd(lx, x), reach, _CMP_LE_OQ);
      keep &= _mm512_cmp_pd_mask(_mm512_sub_pd(y, hy), reach, _CMP_LE_OQ);
      keep &= _mm512_cmp_pd_mask(_mm512_sub_pd(ly, y), reach, _CMP_LE_OQ);
      keep &= _mm512_cmp_pd_mask(_mm512_sub_pd(z, hz), reach, _CMP_LE_OQ);
      keep &= _mm512_cmp_pd_mask(_mm512_sub_pd(lz, z), reach, _CMP_LE_OQ);
      // Compress in registers, then a full store (a compressing store to memory is microcoded
      // and slow on some cores). Also when none is kept: whether a block keeps any is data, and
      // the mispredicted branch that skipped it cost more than the stores (the 100k cloud's step
      // ~3 % faster without it and in_reach_avx512()'s).
      _mm512_storeu_pd(cx + k, _mm512_maskz_compress_pd(keep, x));
      _mm512_storeu_pd(cy + k, _mm512_maskz_compress_pd(keep, y));
      _mm512_storeu_pd(cz + k, _mm512_maskz_compress_pd(keep, z));
      _mm512_storeu_pd(cr + k, _mm512_maskz_compress_pd(keep, r));
      const __m256i idx = _mm256_add_epi32(_mm256_set1_epi32(int(s)), step);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(cs + k), _mm256_maskz_compress_epi32(keep, idx));
      k += std::size_t(std::popcount(unsigned(keep)));
    }
  }
  return k;
}

/// The candidates [0, m) within reach of particle (xi, yi, zi, ri): within_reach()'s test with
/// the same operations in each of eight lanes, so the same pairs. Their places and squared
/// distances go to the front of `hit` and `hd2`, in order (up to 8 entries are written past the
/// count: the callers' slack); returns the count. One pass instead of within_reach() and a scan
/// of its output, most of whose candidates are out of reach.
__attribute__((target("avx512f,avx512vl")))
std::size_t in_reach_avx512(double xi, double yi, double zi, double ri, double margin,
                            const double* __restrict cx, const double* __restrict cy,
                            const double* __restrict cz, const double* __restrict cr,
                            std::size_t m, std::uint32_t* __restrict hit, double* __restrict hd2) {
  const __m512d x = _mm512_set1_pd(xi), y = _mm512_set1_pd(yi), z = _mm512_set1_pd(zi);
  const __m512d r = _mm512_set1_pd(ri), mg = _mm512_set1_pd(margin), zero = _mm512_setzero_pd();
  const __m256i step = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  std::size_t k = 0;
  for (std::size_t b = 0; b < m; b += 8) {
    const __mmask8 live = m - b >= 8 ? __mmask8(0xff) : __mmask8((1u << (m - b)) - 1u);
    const __m512d dx = _mm512_sub_pd(_mm512_maskz_loadu_pd(live, cx + b), x);
    const __m512d dy = _mm512_sub_pd(_mm512_maskz_loadu_pd(live, cy + b), y);
    const __m512d dz = _mm512_sub_pd(_mm512_maskz_loadu_pd(live, cz + b), z);
    const __m512d e = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)),
                                    _mm512_mul_pd(dz, dz));
    const __m512d rj = _mm512_maskz_loadu_pd(live, cr + b);
    const __m512d smaller = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(rj, r, _CMP_LT_OQ), r, rj);  // rj < ri ? rj : ri
    const __m512d reach = _mm512_add_pd(_mm512_add_pd(r, rj), _mm512_mul_pd(mg, smaller));
    const __mmask8 keep = live & _mm512_cmp_pd_mask(e, _mm512_mul_pd(reach, reach), _CMP_LT_OQ) &
                          _mm512_cmp_pd_mask(e, zero, _CMP_GT_OQ);
    // Stored also when none is in reach (two in three blocks, unpredictably): see gather_in_box_avx512().
    _mm512_storeu_pd(hd2 + k, _mm512_maskz_compress_pd(keep, e));
    const __m256i idx = _mm256_add_epi32(_mm256_set1_epi32(int(b)), step);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(hit + k), _mm256_maskz_compress_epi32(keep, idx));
    k += std::size_t(std::popcount(unsigned(keep)));
  }
  return k;
}

/// gather_in_box_scalar() four at a time with AVX2 (for CPUs without AVX-512): the same tests by
/// the same operations, the kept lanes moved to the front by a table (core/compress_avx2.hpp).
/// The same entries in the same order; writes up to 4 entries past the result.
__attribute__((target("avx2")))
std::size_t gather_in_box_avx2(const std::uint32_t* rb, const std::uint32_t* re, int runs,
                               const double* __restrict px, const double* __restrict py,
                               const double* __restrict pz, const double* __restrict pr,
                               const ReachBox& box, std::uint32_t* __restrict cs,
                               double* __restrict cx, double* __restrict cy,
                               double* __restrict cz, double* __restrict cr) {
  std::size_t k = 0;
  const __m256d hx = _mm256_set1_pd(box.hx), hy = _mm256_set1_pd(box.hy), hz = _mm256_set1_pd(box.hz);
  const __m256d lx = _mm256_set1_pd(box.lx), ly = _mm256_set1_pd(box.ly), lz = _mm256_set1_pd(box.lz);
  const __m256d reach = _mm256_set1_pd(box.reach);
  for (int u = 0; u < runs; ++u) {
    for (std::uint32_t s = rb[u], e = re[u]; s < e; s += 4) {
      // Nothing read past e: a run's whole blocks by plain loads, its last part by masked ones
      // (those lanes are not kept). Masked loads are slow on AMD Zen 1 (docs/benchmarks.md,
      // stop 86), and the sorted arrays have no slack to read into.
      const __m256i live = live_lanes4(e - s);
      __m256d x, y, z, r;
      if (e - s >= 4) {
        x = _mm256_loadu_pd(px + s), y = _mm256_loadu_pd(py + s);
        z = _mm256_loadu_pd(pz + s), r = _mm256_loadu_pd(pr + s);
      } else {
        x = _mm256_maskload_pd(px + s, live), y = _mm256_maskload_pd(py + s, live);
        z = _mm256_maskload_pd(pz + s, live), r = _mm256_maskload_pd(pr + s, live);
      }
      __m256d keep = _mm256_and_pd(_mm256_castsi256_pd(live), _mm256_cmp_pd(_mm256_sub_pd(x, hx), reach, _CMP_LE_OQ));
      keep = _mm256_and_pd(keep, _mm256_cmp_pd(_mm256_sub_pd(lx, x), reach, _CMP_LE_OQ));
      keep = _mm256_and_pd(keep, _mm256_cmp_pd(_mm256_sub_pd(y, hy), reach, _CMP_LE_OQ));
      keep = _mm256_and_pd(keep, _mm256_cmp_pd(_mm256_sub_pd(ly, y), reach, _CMP_LE_OQ));
      keep = _mm256_and_pd(keep, _mm256_cmp_pd(_mm256_sub_pd(z, hz), reach, _CMP_LE_OQ));
      keep = _mm256_and_pd(keep, _mm256_cmp_pd(_mm256_sub_pd(lz, z), reach, _CMP_LE_OQ));
      const int mask = _mm256_movemask_pd(keep);
      // Stored also when none is kept: see gather_in_box_avx512().
      compress_store4(cx + k, x, mask);
      compress_store4(cy + k, y, mask);
      compress_store4(cz + k, z, mask);
      compress_store4(cr + k, r, mask);
      compress_store4(cs + k, lane_indices4(s), mask);
      k += std::size_t(std::popcount(unsigned(mask)));
    }
  }
  return k;
}

/// in_reach_avx512()'s pass four at a time with AVX2: within_reach()'s test by the same
/// operations in each lane, the places and squared distances of those within reach at the
/// front of `hit` and `hd2`, in order (up to 4 entries written past the count); returns it.
__attribute__((target("avx2")))
std::size_t in_reach_avx2(double xi, double yi, double zi, double ri, double margin,
                          const double* __restrict cx, const double* __restrict cy,
                          const double* __restrict cz, const double* __restrict cr, std::size_t m,
                          std::uint32_t* __restrict hit, double* __restrict hd2) {
  const __m256d x = _mm256_set1_pd(xi), y = _mm256_set1_pd(yi), z = _mm256_set1_pd(zi);
  const __m256d r = _mm256_set1_pd(ri), mg = _mm256_set1_pd(margin), zero = _mm256_setzero_pd();
  std::size_t k = 0;
  for (std::size_t b = 0; b < m; b += 4) {
    // Plain loads, up to 3 past m into the candidates' slack (see InReach); those lanes are not
    // kept. (Masked loads are slow on AMD Zen 1: docs/benchmarks.md, stop 86.)
    const __m256i live = live_lanes4(m - b);
    const __m256d dx = _mm256_sub_pd(_mm256_loadu_pd(cx + b), x);
    const __m256d dy = _mm256_sub_pd(_mm256_loadu_pd(cy + b), y);
    const __m256d dz = _mm256_sub_pd(_mm256_loadu_pd(cz + b), z);
    const __m256d e = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)),
                                    _mm256_mul_pd(dz, dz));
    const __m256d rj = _mm256_loadu_pd(cr + b);
    const __m256d smaller = _mm256_blendv_pd(r, rj, _mm256_cmp_pd(rj, r, _CMP_LT_OQ));  // rj < ri ? rj : ri
    const __m256d reach = _mm256_add_pd(_mm256_add_pd(r, rj), _mm256_mul_pd(mg, smaller));
    const int mask = _mm256_movemask_pd(_mm256_and_pd(
        _mm256_castsi256_pd(live), _mm256_and_pd(_mm256_cmp_pd(e, _mm256_mul_pd(reach, reach), _CMP_LT_OQ),
                                                 _mm256_cmp_pd(e, zero, _CMP_GT_OQ))));
    compress_store4(hd2 + k, e, mask);
    compress_store4(hit + k, lane_indices4(std::uint32_t(b)), mask);
    k += std::size_t(std::popcount(unsigned(mask)));
  }
  return k;
}
#endif

}  // namespace

GatherInBox gather_in_box(int lanes) {
#if SIMREEL_HAS_VECTOR_CLONES
  if (lanes >= 8) return &gather_in_box_avx512;
  if (lanes >= 4) return &gather_in_box_avx2;
#endif
  (void)lanes;
  return &gather_in_box_scalar;
}


InReach in_reach(int lanes) {
#if SIMREEL_HAS_VECTOR_CLONES
  if (lanes >= 8) return &in_reach_avx512;
  if (lanes >= 4) return &in_reach_avx2;
#endif
  (void)lanes;
  return nullptr;
}

}  // namespace simreel::sim::detail
