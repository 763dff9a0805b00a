// Row kernels (row_lanes.hpp). The compiler's vector clones of these loops spend most of their
// time taking the rows of three apart into x, y and z vectors and putting them back (perf
// annotate on the AMD EPYC: vperm2f128, vblendpd and vinsertf128 held most of the samples of
// the semi-implicit lanes). The AVX2 forms instead work on the rows as they lie: four particles
// are twelve doubles, three registers, and only the per-particle values (c, d, the drag
// factor, the curl) are spread over them, with single-source permutes.
#include "particles/row_lanes.hpp"

#include <type_traits>

#include "core/same_bits.hpp"
#include "core/vector_clones.hpp"

#if SIMREEL_HAS_VECTOR_CLONES
#include <immintrin.h>
#endif

namespace simreel::sim::detail {

namespace {

SIMREEL_VECTOR_CLONES
void semi_implicit_linear_clones(std::size_t len, double h, double drag, double g0, double g1,
                                 double g2, const double* __restrict m, double* __restrict x,
                                 double* __restrict v, const double* __restrict a) {
  for (std::size_t i = 0; i < len; ++i) {
    const double c = drag / m[i];
    const double damp = 1.0 / (1.0 + h * c);
    const double v0 = (v[3 * i] + h * a[3 * i]) * damp;
    const double v1 = (v[3 * i + 1] + h * a[3 * i + 1]) * damp;
    const double v2 = (v[3 * i + 2] + h * a[3 * i + 2]) * damp;
    v[3 * i] = v0;
    v[3 * i + 1] = v1;
    v[3 * i + 2] = v2;
    x[3 * i] += h * v0 - 0.5 * h * h * (g0 - c * v0) * damp * damp;
    x[3 * i + 1] += h * v1 - 0.5 * h * h * (g1 - c * v1) * damp * damp;
    x[3 * i + 2] += h * v2 - 0.5 * h * h * (g2 - c * v2) * damp * damp;
  }
}

SIMREEL_VECTOR_CLONES
void add_noise_drag_clones(std::size_t len, const double* __restrict w,
                           const double* __restrict ux, const double* __restrict uy,
                           const double* __restrict uz, const double* q, double amplitude,
                           double drag, const double* __restrict mass,
                           const double* __restrict v, double* __restrict a) {
  // The loop must be straight-line for the compiler to vectorise it (it ran one particle at a
  // time: a fifth of curl noise's step on an AVX-512 Xeon, where this form used to run): q read
  // once (through a plain pointer it might alias `a`), and v read whatever `in` says (a load
  // under the select is one the compiler may not speculate). The same arithmetic, so the same
  // bits.
  const double q0 = q[0], q1 = q[1], q2 = q[2], q3 = q[3], q4 = q[4], q5 = q[5], q6 = q[6],
               q7 = q[7], q8 = q[8];
  for (std::size_t k = 0; k < len; ++k) {
    const double u0 = amplitude * (q0 * ux[k] + q1 * uy[k] + q2 * uz[k]);
    const double u1 = amplitude * (q3 * ux[k] + q4 * uy[k] + q5 * uz[k]);
    const double u2 = amplitude * (q6 * ux[k] + q7 * uy[k] + q8 * uz[k]);
    const double s = w[k] * drag / mass[k];
    const bool in = w[k] != 0.0;
    const double v0 = v[3 * k], v1 = v[3 * k + 1], v2 = v[3 * k + 2];
    a[3 * k] += in ? s * (u0 - v0) : 0.0;
    a[3 * k + 1] += in ? s * (u1 - v1) : 0.0;
    a[3 * k + 2] += in ? s * (u2 - v2) : 0.0;
  }
}

SIMREEL_VECTOR_CLONES
void rows_to_columns_clones(const float* __restrict rows, std::size_t len, double* __restrict x,
                            double* __restrict y, double* __restrict z) {
  for (std::size_t k = 0; k < len; ++k) {
    x[k] = rows[3 * k];
    y[k] = rows[3 * k + 1];
    z[k] = rows[3 * k + 2];
  }
}

SIMREEL_VECTOR_CLONES
void rows_to_columns_clones(const float* __restrict rows, std::size_t len, float* __restrict x,
                            float* __restrict y, float* __restrict z) {
  for (std::size_t k = 0; k < len; ++k) {
    x[k] = rows[3 * k];
    y[k] = rows[3 * k + 1];
    z[k] = rows[3 * k + 2];
  }
}

SIMREEL_VECTOR_CLONES
void columns_to_rows_clones(const float* __restrict x, const float* __restrict y,
                            const float* __restrict z, std::size_t len, float* __restrict rows) {
  for (std::size_t k = 0; k < len; ++k) {
    rows[3 * k] = x[k];
    rows[3 * k + 1] = y[k];
    rows[3 * k + 2] = z[k];
  }
}

#if SIMREEL_HAS_VECTOR_CLONES

/// Four rows of three floats, (a0 a1 a2 a3) = (x0 y0 z0 x1), (b..) = (y1 z1 x2 y2),
/// (c..) = (z2 x3 y3 z3), to the columns (x0..x3), (y0..y3), (z0..z3): two blends gather each
/// column's floats into the lanes a permute then puts in order (each permute its own inverse,
/// which columns_to_rows_avx2() uses the other way). Column: float or double.
template <class Column>
__attribute__((target("avx2"))) void rows_to_columns_avx2(const float* __restrict rows,
                                                          std::size_t len, Column* __restrict x,
                                                          Column* __restrict y,
                                                          Column* __restrict z) {
  const auto store = [](Column* to, __m128 v) __attribute__((target("avx2"))) {
    if constexpr (std::is_same_v<Column, double>)
      _mm256_storeu_pd(to, _mm256_cvtps_pd(v));
    else
      _mm_storeu_ps(to, v);
  };
  std::size_t k = 0;
  for (; k + 4 <= len; k += 4) {
    const __m128 a = _mm_loadu_ps(rows + 3 * k), b = _mm_loadu_ps(rows + 3 * k + 4),
                 c = _mm_loadu_ps(rows + 3 * k + 8);
    const __m128 tx = _mm_blend_ps(_mm_blend_ps(a, b, 0x4), c, 0x2);  // a0 c1 b2 a3
    const __m128 ty = _mm_blend_ps(_mm_blend_ps(a, b, 0x9), c, 0x4);  // b0 a1 c2 b3
    const __m128 tz = _mm_blend_ps(_mm_blend_ps(a, b, 0x2), c, 0x9);  // c0 b1 a2 c3
    store(x + k, _mm_shuffle_ps(tx, tx, _MM_SHUFFLE(1, 2, 3, 0)));
    store(y + k, _mm_shuffle_ps(ty, ty, _MM_SHUFFLE(2, 3, 0, 1)));
    store(z + k, _mm_shuffle_ps(tz, tz, _MM_SHUFFLE(3, 0, 1, 2)));
  }
  if (k < len) rows_to_columns_clones(rows + 3 * k, len - k, x + k, y + k, z + k);
}

__attribute__((target("avx2"))) void columns_to_rows_avx2(const float* __restrict x,
                                                          const float* __restrict y,
                                                          const float* __restrict z,
                                                          std::size_t len,
                                                          float* __restrict rows) {
  std::size_t k = 0;
  for (; k + 4 <= len; k += 4) {
    const __m128 X = _mm_loadu_ps(x + k), Y = _mm_loadu_ps(y + k), Z = _mm_loadu_ps(z + k);
    const __m128 tx = _mm_shuffle_ps(X, X, _MM_SHUFFLE(1, 2, 3, 0));  // x0 x3 x2 x1
    const __m128 ty = _mm_shuffle_ps(Y, Y, _MM_SHUFFLE(2, 3, 0, 1));  // y1 y0 y3 y2
    const __m128 tz = _mm_shuffle_ps(Z, Z, _MM_SHUFFLE(3, 0, 1, 2));  // z2 z1 z0 z3
    _mm_storeu_ps(rows + 3 * k, _mm_blend_ps(_mm_blend_ps(tx, ty, 0x2), tz, 0x4));
    _mm_storeu_ps(rows + 3 * k + 4, _mm_blend_ps(_mm_blend_ps(ty, tz, 0x2), tx, 0x4));
    _mm_storeu_ps(rows + 3 * k + 8, _mm_blend_ps(_mm_blend_ps(tz, tx, 0x2), ty, 0x4));
  }
  if (k < len) columns_to_rows_clones(x + k, y + k, z + k, len - k, rows + 3 * k);
}

#define SIMREEL_AVX2 __attribute__((target("avx2"), always_inline)) inline

/// Particle values p0..p3 spread over four rows of three: (p0 p0 p0 p1), (p1 p1 p2 p2),
/// (p2 p3 p3 p3).
struct Spread3 {
  __m256d r0, r1, r2;
};
SIMREEL_AVX2 Spread3 spread3(__m256d p) {
  return {_mm256_permute4x64_pd(p, 0x40), _mm256_permute4x64_pd(p, 0xA5),
          _mm256_permute4x64_pd(p, 0xFE)};
}

/// Three per-axis vectors (a0..a3), (b0..b3), (c0..c3) as four rows: (a0 b0 c0 a1),
/// (b1 c1 a2 b2), (c2 a3 b3 c3).
SIMREEL_AVX2 Spread3 interleave3(__m256d a, __m256d b, __m256d c) {
  const __m256d r0 = _mm256_blend_pd(_mm256_blend_pd(_mm256_permute4x64_pd(a, 0x40),
                                                     _mm256_permute4x64_pd(b, 0x00), 0x2),
                                     _mm256_permute4x64_pd(c, 0x00), 0x4);
  const __m256d r1 = _mm256_blend_pd(_mm256_blend_pd(_mm256_permute4x64_pd(b, 0x95),
                                                     _mm256_permute4x64_pd(c, 0x55), 0x2),
                                     _mm256_permute4x64_pd(a, 0xAA), 0x4);
  const __m256d r2 = _mm256_blend_pd(_mm256_blend_pd(_mm256_permute4x64_pd(c, 0xEA),
                                                     _mm256_permute4x64_pd(a, 0xFF), 0x2),
                                     _mm256_permute4x64_pd(b, 0xFF), 0x4);
  return {r0, r1, r2};
}

/// One register of rows (four doubles at x, v, a) through the clone's two statements.
SIMREEL_AVX2 void semi_implicit_quad(double* x, double* v, const double* a, __m256d h,
                                     __m256d hh, __m256d g, __m256d c, __m256d d) {
  const __m256d vn = _mm256_mul_pd(_mm256_add_pd(_mm256_loadu_pd(v), _mm256_mul_pd(h, _mm256_loadu_pd(a))), d);
  _mm256_storeu_pd(v, vn);
  // h v' - ((((h² / 2) (g - c v')) d) d), grouped as the clone groups 0.5 * h * h * (...) * d * d
  const __m256d t = _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(hh, _mm256_sub_pd(g, _mm256_mul_pd(c, vn))), d), d);
  _mm256_storeu_pd(x, _mm256_add_pd(_mm256_loadu_pd(x), _mm256_sub_pd(_mm256_mul_pd(h, vn), t)));
}

__attribute__((target("avx2"))) void semi_implicit_linear_avx2(
    std::size_t len, double h, double drag, double g0, double g1, double g2,
    const double* __restrict m, double* __restrict x, double* __restrict v,
    const double* __restrict a) {
  const __m256d hv = _mm256_set1_pd(h), dv = _mm256_set1_pd(drag), one = _mm256_set1_pd(1.0);
  const __m256d hh = _mm256_set1_pd(0.5 * h * h);
  const __m256d gA = _mm256_setr_pd(g0, g1, g2, g0), gB = _mm256_setr_pd(g1, g2, g0, g1),
                gC = _mm256_setr_pd(g2, g0, g1, g2);
  // Where every particle has the first one's mass (bit for bit), c and d are the same for all:
  // the two divisions once, not every four particles (the same operations on the same values,
  // so the same bits; the divider is the loop's slowest unit on Zen 1).
  const bool same = same_bits(m, len);
  const __m256d c_same = _mm256_div_pd(dv, _mm256_set1_pd(len > 0 ? m[0] : 1.0));
  const __m256d d_same = _mm256_div_pd(one, _mm256_add_pd(one, _mm256_mul_pd(hv, c_same)));
  std::size_t i = 0;
  for (; i + 4 <= len; i += 4) {
    const __m256d c = same ? c_same : _mm256_div_pd(dv, _mm256_loadu_pd(m + i));
    const __m256d d = same ? d_same : _mm256_div_pd(one, _mm256_add_pd(one, _mm256_mul_pd(hv, c)));
    const Spread3 cs = spread3(c), ds = spread3(d);
    double *xi = x + 3 * i, *vi = v + 3 * i;
    const double* ai = a + 3 * i;
    semi_implicit_quad(xi, vi, ai, hv, hh, gA, cs.r0, ds.r0);
    semi_implicit_quad(xi + 4, vi + 4, ai + 4, hv, hh, gB, cs.r1, ds.r1);
    semi_implicit_quad(xi + 8, vi + 8, ai + 8, hv, hh, gC, cs.r2, ds.r2);
  }
  if (i < len) semi_implicit_linear_clones(len - i, h, drag, g0, g1, g2, m + i, x + 3 * i, v + 3 * i, a + 3 * i);
}

/// Row r of amplitude R u for four particles: amplitude ((q_r0 x + q_r1 y) + q_r2 z), grouped as
/// the clone groups it (q + r: the row's three entries, broadcast).
SIMREEL_AVX2 __m256d curl_row(const __m256d* q, int r, __m256d amp, __m256d x, __m256d y,
                              __m256d z) {
  return _mm256_mul_pd(amp, _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(q[r], x), _mm256_mul_pd(q[r + 1], y)),
                                          _mm256_mul_pd(q[r + 2], z)));
}

/// a += (in ? s (u - v) : +0) over one register of rows; `in` all ones or all zeros per lane.
SIMREEL_AVX2 void noise_drag_quad(double* a, const double* v, __m256d u, __m256d s, __m256d in) {
  const __m256d t = _mm256_and_pd(in, _mm256_mul_pd(s, _mm256_sub_pd(u, _mm256_loadu_pd(v))));
  _mm256_storeu_pd(a, _mm256_add_pd(_mm256_loadu_pd(a), t));
}

__attribute__((target("avx2"))) void add_noise_drag_avx2(
    std::size_t len, const double* __restrict w, const double* __restrict ux,
    const double* __restrict uy, const double* __restrict uz, const double* q, double amplitude,
    double drag, const double* __restrict mass, const double* __restrict v,
    double* __restrict a) {
  __m256d qv[9];
  for (int k = 0; k < 9; ++k) qv[k] = _mm256_set1_pd(q[k]);
  const __m256d amp = _mm256_set1_pd(amplitude), dv = _mm256_set1_pd(drag);
  // One weight and one mass for all (a field everywhere, one emitter's particles): the factor
  // w k / m once (as in semi_implicit_linear_avx2()).
  const bool same = same_bits(w, len) && same_bits(mass, len);
  const __m256d s_same = _mm256_div_pd(_mm256_mul_pd(_mm256_set1_pd(len > 0 ? w[0] : 0.0), dv),
                                       _mm256_set1_pd(len > 0 ? mass[0] : 1.0));
  std::size_t k = 0;
  for (; k + 4 <= len; k += 4) {
    const __m256d x = _mm256_loadu_pd(ux + k), y = _mm256_loadu_pd(uy + k), z = _mm256_loadu_pd(uz + k);
    const Spread3 u = interleave3(curl_row(qv, 0, amp, x, y, z), curl_row(qv, 3, amp, x, y, z),
                                   curl_row(qv, 6, amp, x, y, z));
    const __m256d wk = _mm256_loadu_pd(w + k);
    const Spread3 s = spread3(same ? s_same : _mm256_div_pd(_mm256_mul_pd(wk, dv), _mm256_loadu_pd(mass + k)));
    // w != 0 as all-ones lanes: where w = 0 the term is +0.0, the clone's select
    const Spread3 in = spread3(_mm256_cmp_pd(wk, _mm256_setzero_pd(), _CMP_NEQ_UQ));
    double* ak = a + 3 * k;
    const double* vk = v + 3 * k;
    noise_drag_quad(ak, vk, u.r0, s.r0, in.r0);
    noise_drag_quad(ak + 4, vk + 4, u.r1, s.r1, in.r1);
    noise_drag_quad(ak + 8, vk + 8, u.r2, s.r2, in.r2);
  }
  if (k < len)
    add_noise_drag_clones(len - k, w + k, ux + k, uy + k, uz + k, q, amplitude, drag, mass + k,
                          v + 3 * k, a + 3 * k);
}

#undef SIMREEL_AVX2

// The AVX-512 forms: eight particles are twenty-four doubles, three registers, and the
// per-particle values are spread over them by one full permute each.
#define SIMREEL_AVX512 __attribute__((target("avx512f"), always_inline)) inline

/// Particle values p0..p7 spread over eight rows of three: (p0 p0 p0 p1 p1 p1 p2 p2),
/// (p2 p3 p3 p3 p4 p4 p4 p5), (p5 p5 p6 p6 p6 p7 p7 p7).
struct Spread3x8 {
  __m512d r0, r1, r2;
};
SIMREEL_AVX512 Spread3x8 spread3x8(__m512d p) {
  // (the two-source permute with p twice: GCC 12's one-source form warns of an uninitialised
  // operand inside its own header)
  return {_mm512_permutex2var_pd(p, _mm512_setr_epi64(0, 0, 0, 1, 1, 1, 2, 2), p),
          _mm512_permutex2var_pd(p, _mm512_setr_epi64(2, 3, 3, 3, 4, 4, 4, 5), p),
          _mm512_permutex2var_pd(p, _mm512_setr_epi64(5, 5, 6, 6, 6, 7, 7, 7), p)};
}

/// Three per-axis vectors (a0..a7), (b0..b7), (c0..c7) as eight rows: (a0 b0 c0 a1 b1 c1 a2 b2),
/// (c2 a3 b3 c3 a4 b4 c4 a5), (b5 c5 a6 b6 c6 a7 b7 c7); a's and b's placed first (index i: a_i,
/// 8 + i: b_i), then c's.
SIMREEL_AVX512 Spread3x8 interleave3x8(__m512d a, __m512d b, __m512d c) {
  const __m512d t0 = _mm512_permutex2var_pd(a, _mm512_setr_epi64(0, 8, 0, 1, 9, 0, 2, 10), b);
  const __m512d t1 = _mm512_permutex2var_pd(a, _mm512_setr_epi64(0, 3, 11, 0, 4, 12, 0, 5), b);
  const __m512d t2 = _mm512_permutex2var_pd(a, _mm512_setr_epi64(13, 0, 6, 14, 0, 7, 15, 0), b);
  return {_mm512_permutex2var_pd(t0, _mm512_setr_epi64(0, 1, 8, 3, 4, 9, 6, 7), c),
          _mm512_permutex2var_pd(t1, _mm512_setr_epi64(10, 1, 2, 11, 4, 5, 12, 7), c),
          _mm512_permutex2var_pd(t2, _mm512_setr_epi64(0, 13, 2, 3, 14, 5, 6, 15), c)};
}

/// semi_implicit_quad() for one register of eight doubles.
SIMREEL_AVX512 void semi_implicit_oct(double* x, double* v, const double* a, __m512d h,
                                      __m512d hh, __m512d g, __m512d c, __m512d d) {
  const __m512d vn = _mm512_mul_pd(_mm512_add_pd(_mm512_loadu_pd(v), _mm512_mul_pd(h, _mm512_loadu_pd(a))), d);
  _mm512_storeu_pd(v, vn);
  const __m512d t = _mm512_mul_pd(_mm512_mul_pd(_mm512_mul_pd(hh, _mm512_sub_pd(g, _mm512_mul_pd(c, vn))), d), d);
  _mm512_storeu_pd(x, _mm512_add_pd(_mm512_loadu_pd(x), _mm512_sub_pd(_mm512_mul_pd(h, vn), t)));
}

__attribute__((target("avx512f"))) void semi_implicit_linear_avx512(
    std::size_t len, double h, double drag, double g0, double g1, double g2,
    const double* __restrict m, double* __restrict x, double* __restrict v,
    const double* __restrict a) {
  const __m512d hv = _mm512_set1_pd(h), dv = _mm512_set1_pd(drag), one = _mm512_set1_pd(1.0);
  const __m512d hh = _mm512_set1_pd(0.5 * h * h);
  const __m512d gA = _mm512_setr_pd(g0, g1, g2, g0, g1, g2, g0, g1),
                gB = _mm512_setr_pd(g2, g0, g1, g2, g0, g1, g2, g0),
                gC = _mm512_setr_pd(g1, g2, g0, g1, g2, g0, g1, g2);
  std::size_t i = 0;
  for (; i + 8 <= len; i += 8) {
    const __m512d c = _mm512_div_pd(dv, _mm512_loadu_pd(m + i));
    const __m512d d = _mm512_div_pd(one, _mm512_add_pd(one, _mm512_mul_pd(hv, c)));
    const Spread3x8 cs = spread3x8(c), ds = spread3x8(d);
    double *xi = x + 3 * i, *vi = v + 3 * i;
    const double* ai = a + 3 * i;
    semi_implicit_oct(xi, vi, ai, hv, hh, gA, cs.r0, ds.r0);
    semi_implicit_oct(xi + 8, vi + 8, ai + 8, hv, hh, gB, cs.r1, ds.r1);
    semi_implicit_oct(xi + 16, vi + 16, ai + 16, hv, hh, gC, cs.r2, ds.r2);
  }
  if (i < len) semi_implicit_linear_clones(len - i, h, drag, g0, g1, g2, m + i, x + 3 * i, v + 3 * i, a + 3 * i);
}

/// Row r of amplitude R u for eight particles, grouped as the clone groups it.
SIMREEL_AVX512 __m512d curl_row8(const __m512d* q, int r, __m512d amp, __m512d x, __m512d y,
                                 __m512d z) {
  return _mm512_mul_pd(amp, _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(q[r], x), _mm512_mul_pd(q[r + 1], y)),
                                          _mm512_mul_pd(q[r + 2], z)));
}

/// a += (in ? s (u - v) : +0) over one register of rows: lanes outside `in` add the +0.0 that
/// the zeroing multiply leaves, as the clone's select does.
SIMREEL_AVX512 void noise_drag_oct(double* a, const double* v, __m512d u, __m512d s, __mmask8 in) {
  const __m512d t = _mm512_maskz_mul_pd(in, s, _mm512_sub_pd(u, _mm512_loadu_pd(v)));
  _mm512_storeu_pd(a, _mm512_add_pd(_mm512_loadu_pd(a), t));
}

__attribute__((target("avx512f"))) void add_noise_drag_avx512(
    std::size_t len, const double* __restrict w, const double* __restrict ux,
    const double* __restrict uy, const double* __restrict uz, const double* q, double amplitude,
    double drag, const double* __restrict mass, const double* __restrict v,
    double* __restrict a) {
  __m512d qv[9];
  for (int k = 0; k < 9; ++k) qv[k] = _mm512_set1_pd(q[k]);
  const __m512d amp = _mm512_set1_pd(amplitude), dv = _mm512_set1_pd(drag);
  const __m512d zero = _mm512_setzero_pd(), one = _mm512_set1_pd(1.0);
  std::size_t k = 0;
  for (; k + 8 <= len; k += 8) {
    const __m512d x = _mm512_loadu_pd(ux + k), y = _mm512_loadu_pd(uy + k), z = _mm512_loadu_pd(uz + k);
    const Spread3x8 u = interleave3x8(curl_row8(qv, 0, amp, x, y, z), curl_row8(qv, 3, amp, x, y, z),
                                      curl_row8(qv, 6, amp, x, y, z));
    const __m512d wk = _mm512_loadu_pd(w + k);
    const Spread3x8 s = spread3x8(_mm512_div_pd(_mm512_mul_pd(wk, dv), _mm512_loadu_pd(mass + k)));
    // w != 0 (true for NaN, as in the clone) as 1.0 or 0.0 per particle, spread, then a mask
    // per register
    const Spread3x8 in = spread3x8(_mm512_mask_blend_pd(_mm512_cmp_pd_mask(wk, zero, _CMP_NEQ_UQ), zero, one));
    double* ak = a + 3 * k;
    const double* vk = v + 3 * k;
    noise_drag_oct(ak, vk, u.r0, s.r0, _mm512_cmp_pd_mask(in.r0, zero, _CMP_NEQ_OQ));
    noise_drag_oct(ak + 8, vk + 8, u.r1, s.r1, _mm512_cmp_pd_mask(in.r1, zero, _CMP_NEQ_OQ));
    noise_drag_oct(ak + 16, vk + 16, u.r2, s.r2, _mm512_cmp_pd_mask(in.r2, zero, _CMP_NEQ_OQ));
  }
  if (k < len)
    add_noise_drag_clones(len - k, w + k, ux + k, uy + k, uz + k, q, amplitude, drag, mass + k,
                          v + 3 * k, a + 3 * k);
}

#undef SIMREEL_AVX512

/// The rows-to-columns conversions' default: 4 where the AVX2 forms run by default (AVX2
/// without AVX-512), else 1 (on AVX-512 the clones were faster: ground_resting 2.22-2.45 against
/// 2.29-2.73 ms a step).
int default_row_lanes() {
  static const int w = !cpu_has_avx512vl() && row_lanes_avx2() ? 4 : 1;
  return w;
}

/// The semi-implicit lanes' and the curl drag's default: the widest hand-written rows the CPU
/// runs (8, 4), else the clones (1). On an AVX-512 Xeon the AVX-512 rows took 0.9x the time of
/// the clone and AVX2 rows in curl_noise/100000/1; its AVX-512 clone of the curl drag did not
/// vectorise at all before c363a60, and even vectorised it put its results back into rows a
/// double or two at a time.
int widest_row_lanes() {
  static const int w = row_lanes_avx512() ? 8 : row_lanes_avx2() ? 4 : 1;
  return w;
}

#endif

}  // namespace

bool row_lanes_avx2() {
#if SIMREEL_HAS_VECTOR_CLONES
  static const bool yes = cpu_has_avx2();
  return yes;
#else
  return false;
#endif
}

bool row_lanes_avx512() {
#if SIMREEL_HAS_VECTOR_CLONES
  static const bool yes = cpu_has_avx512f();
  return yes;
#else
  return false;
#endif
}

void semi_implicit_linear_rows(std::size_t len, double h, double drag, double g0, double g1,
                               double g2, const double* m, double* x, double* v, const double* a,
                               int lanes) {
#if SIMREEL_HAS_VECTOR_CLONES
  if (lanes == 0) lanes = widest_row_lanes();
  if (lanes == 8 && row_lanes_avx512()) return semi_implicit_linear_avx512(len, h, drag, g0, g1, g2, m, x, v, a);
  if (lanes >= 4 && row_lanes_avx2()) return semi_implicit_linear_avx2(len, h, drag, g0, g1, g2, m, x, v, a);
#else
  (void)lanes;
#endif
  semi_implicit_linear_clones(len, h, drag, g0, g1, g2, m, x, v, a);
}

void add_noise_drag_rows(std::size_t len, const double* w, const double* ux, const double* uy,
                         const double* uz, const double* q, double amplitude, double drag,
                         const double* mass, const double* v, double* a, int lanes) {
#if SIMREEL_HAS_VECTOR_CLONES
  if (lanes == 0) lanes = widest_row_lanes();
  if (lanes == 8 && row_lanes_avx512())
    return add_noise_drag_avx512(len, w, ux, uy, uz, q, amplitude, drag, mass, v, a);
  if (lanes >= 4 && row_lanes_avx2())
    return add_noise_drag_avx2(len, w, ux, uy, uz, q, amplitude, drag, mass, v, a);
#else
  (void)lanes;
#endif
  add_noise_drag_clones(len, w, ux, uy, uz, q, amplitude, drag, mass, v, a);
}

namespace {
template <class Column>
void rows_to_columns_any(const float* rows, std::size_t len, Column* x, Column* y, Column* z,
                         int lanes) {
#if SIMREEL_HAS_VECTOR_CLONES
  if (lanes == 0) lanes = default_row_lanes();
  if (lanes == 4 && row_lanes_avx2()) return rows_to_columns_avx2(rows, len, x, y, z);
#else
  (void)lanes;
#endif
  rows_to_columns_clones(rows, len, x, y, z);
}
}  // namespace

void rows_to_columns(const float* rows, std::size_t len, double* x, double* y, double* z,
                     int lanes) {
  rows_to_columns_any(rows, len, x, y, z, lanes);
}

void rows_to_columns(const float* rows, std::size_t len, float* x, float* y, float* z,
                     int lanes) {
  rows_to_columns_any(rows, len, x, y, z, lanes);
}

void columns_to_rows(const float* x, const float* y, const float* z, std::size_t len, float* rows,
                     int lanes) {
#if SIMREEL_HAS_VECTOR_CLONES
  if (lanes == 0) lanes = default_row_lanes();
  if (lanes == 4 && row_lanes_avx2()) return columns_to_rows_avx2(x, y, z, len, rows);
#else
  (void)lanes;
#endif
  columns_to_rows_clones(x, y, z, len, rows);
}

}  // namespace simreel::sim::detail
