// Gradient (Perlin) noise with its analytic gradient and the curl-noise velocity built on it
// (Bridson et al. 2007).
#include "particles/noise.hpp"

#include <array>
#include <cmath>

#include "core/vector_clones.hpp"
#include "simreel/sim/random.hpp"

#if SIMREEL_HAS_VECTOR_CLONES
#include <immintrin.h>
#endif

namespace simreel::sim::detail {

GradientNoise::GradientNoise(std::uint64_t seed) {
  Rng rng(seed, 0xC0FFEE);
  for (std::uint32_t& s : seed_) s = std::uint32_t(rng.next_u64() >> 32);
}

namespace {

// Cell hash (as FastNoise2 does): the cell's coordinates times large odd primes, XORed with the
// potential's seed, times an odd multiplier; the top 4 bits of the product (the best mixed ones)
// pick the gradient. Unsigned 32-bit arithmetic: it wraps, so the lattice repeats every 2^32 cells.
constexpr std::uint32_t kPrimeX = 501125321u, kPrimeY = 1136930381u, kPrimeZ = 1720413743u;
constexpr std::uint32_t kHashMul = 0x27d4eb2du;

/// Gradient component of table row h (0..15): the 12 cube-edge directions of Perlin (2002),
/// rows 12..15 repeating four of them.
/// Rows: (1,1,0) (-1,1,0) (1,-1,0) (-1,-1,0) (1,0,1) (-1,0,1) (1,0,-1) (-1,0,-1) (0,1,1)
/// (0,-1,1) (0,1,-1) (0,-1,-1) (1,1,0) (-1,1,0) (0,-1,1) (0,-1,-1).
/// Written as value + 1, 2 bits a row, row h at bits 2h (the readable form, checked below).
constexpr std::uint32_t kGradX = 0x52552222u, kGradY = 0x0A22550Au, kGradZ = 0x250A0A55u;

/// The same table packed for the lookup: row h's component as a 2-bit two's complement number
/// (-1 is 11, 0 is 00, 1 is 01) at bits 31 - 2h and 30 - 2h, so that a shift left by s = 2h
/// brings it to the top, where those two bits read as a float's sign and exponent top bit are
/// -2.0f, +0.0f and 2.0f: a mask of the other 30 bits gives twice the component, two integer
/// instructions a component in the compiler's vector lanes and no int-to-float conversion (on
/// Zen 1 the conversions share one pipe with half the additions; the curl ran ~5 % faster).
constexpr std::uint32_t top_first(std::uint32_t plus_one) {
  std::uint32_t r = 0;
  for (std::uint32_t h = 0; h < 16; ++h)
    r |= ((((plus_one >> (2 * h)) & 3u) - 1u) & 3u) << (30 - 2 * h);
  return r;
}
constexpr std::uint32_t kTopX = top_first(kGradX), kTopY = top_first(kGradY),
                        kTopZ = top_first(kGradZ);
/// Twice row s / 2's component of `table` (-2, 0 or 2): see kTopX.
constexpr float grad_component2(std::uint32_t s, std::uint32_t table) {
  return __builtin_bit_cast(float, (table << s) & 0xC0000000u);
}
constexpr bool tables_agree() {
  for (std::uint32_t h = 0; h < 16; ++h)
    for (std::uint32_t t : {0u, 1u, 2u}) {
      const std::uint32_t plus_one = t == 0 ? kGradX : t == 1 ? kGradY : kGradZ;
      const std::uint32_t top = t == 0 ? kTopX : t == 1 ? kTopY : kTopZ;
      // -2, 0 and 2 come only from 11, 00 and 01: this also checks the two's complement form.
      if (grad_component2(2 * h, top) != float(2 * (std::int32_t((plus_one >> (2 * h)) & 3u) - 1)))
        return false;
    }
  return true;
}
static_assert(tables_agree(), "the packed gradient tables must hold the rows above");

/// The cell, fade and corner offsets of one point, shared by the three potentials.
struct Lattice {
  std::uint32_t x0, y0, z0;  ///< cell coordinates times the primes (corner 0)
  float f0, f1, f2;          ///< offset of the point in its cell, [0, 1)
};

/// Twice one potential at one point: value, and gradient (g0, g1, g2) per unit of p; the callers
/// halve them. The quintic fade 6t^5 - 15t^4 + 10t^3 is C2, so the curl is C1; the trilinear
/// blend of the corner ramps and its exact derivative follow Quilez ("gradient noise
/// derivatives"). Straight-line float code (no branches, no tables): inlined into the vectorised
/// loop and into sample() alike, with -ffp-contract=off, so both give the same bits.
/// Why twice: the corner gradients come doubled from grad_component2(), and every operation
/// below is a sum or difference of doubled values or a product of one doubled value with one
/// that is not, which doubles exactly; so the halved results are the bits of the undoubled
/// arithmetic, except where a product falls below 2^-126 (a point within ~1e-13 of a cell
/// face, or ~1e-7 of two), where the doubled form can keep one more bit of a subnormal: 5 of
/// 60,000 curl values near cell faces, each by 1.4e-45 (docs/benchmarks.md, stop 87).
__attribute__((always_inline)) inline float potential2(std::uint32_t seed, const Lattice& l,
                                                      float& g0, float& g1, float& g2) {
  // The statements run corner by corner, each sum and blend taken as far as the corners so far
  // allow, so that fewer values stay live at once (x86 GCC keeps the source's order up to
  // register allocation): with all 8 corners first, the AVX2 loop of curl_floats() read or wrote
  // the stack in 329 of its 982 instructions, now 226 of 979, and a curl takes ~6% less time.
  // Every expression is the one of the closed form in the comments, in the same order of
  // operations, so the values are its bits (SimForces.CurlNoiseKeepsItsRealisation).
  const float f0 = l.f0, f1 = l.f1, f2 = l.f2;
  const float x = f0 * f0 * f0 * (f0 * (f0 * 6.0f - 15.0f) + 10.0f);
  const std::uint32_t x0 = l.x0 ^ seed, x1 = (l.x0 + kPrimeX) ^ seed;
  const std::uint32_t y0 = l.y0, y1 = l.y0 + kPrimeY, z0 = l.z0, z1 = l.z0 + kPrimeZ;
  // hx ^ hy ^ hz as hx ^ (hy ^ hz) (the same bits): the four yz terms are the same for the three
  // potentials of a point, so the compiler computes them once.
  const std::uint32_t y0z0 = y0 ^ z0, y1z0 = y1 ^ z0, y0z1 = y0 ^ z1, y1z1 = y1 ^ z1;
  // Corners (cx, cy, cz): gradient and ramp value g . (f - c). Written out so the whole body is
  // one basic block.
#define SIMREEL_CORNER(name, hx, hyz, cx, cy, cz)                                        \
  const std::uint32_t h##name = (((hx ^ hyz) * kHashMul) >> 27) & 30u; /* 2 row */       \
  const float g##name##0 = grad_component2(h##name, kTopX);                             \
  const float g##name##1 = grad_component2(h##name, kTopY);                             \
  const float g##name##2 = grad_component2(h##name, kTopZ);                             \
  const float v##name = g##name##0 * (f0 - cx) + g##name##1 * (f1 - cy) + g##name##2 * (f2 - cz);
  // value = va + k1 u + k2 v + k3 w + k4 uv + k5 vw + k6 wu + k7 uvw (u, v, w: the fades x, y, z)
  // with k1 = vb - va, k2 = vc - va, k3 = ve - va, k4 = va - vb - vc + vd,
  // k5 = va - vc - ve + vg, k6 = va - vb - ve + vf, k7 = -va + vb + vc - vd + ve - vf - vg + vh;
  // the gradient adds the same trilinear blend of the corner gradients, as nested lerps:
  // gx00 = ga + x (gb - ga), gx10 = gc + x (gd - gc), gx01 = ge + x (gf - ge),
  // gx11 = gg + x (gh - gg), gy0 = gx00 + y (gx10 - gx00), gy1 = gx01 + y (gx11 - gx01),
  // out = gy0 + z (gy1 - gy0).
#define SIMREEL_LERP(out, name0, name1, t) \
  const float out##0 = g##name0##0 + t * (g##name1##0 - g##name0##0); \
  const float out##1 = g##name0##1 + t * (g##name1##1 - g##name0##1); \
  const float out##2 = g##name0##2 + t * (g##name1##2 - g##name0##2);
  SIMREEL_CORNER(a, x0, y0z0, 0.0f, 0.0f, 0.0f)
  SIMREEL_CORNER(b, x1, y0z0, 1.0f, 0.0f, 0.0f)
  const float k1 = vb - va;
  const float ab = va - vb;  // k4 and k6 begin with it
  float k7 = -va + vb;
  SIMREEL_LERP(gx00, a, b, x)
  SIMREEL_CORNER(c, x0, y1z0, 0.0f, 1.0f, 0.0f)
  const float k2 = vc - va;
  float k4 = ab - vc;
  float k5 = va - vc;
  k7 = k7 + vc;
  SIMREEL_CORNER(d, x1, y1z0, 1.0f, 1.0f, 0.0f)
  k4 = k4 + vd;
  k7 = k7 - vd;
  SIMREEL_LERP(gx10, c, d, x)
  const float y = f1 * f1 * f1 * (f1 * (f1 * 6.0f - 15.0f) + 10.0f);
  SIMREEL_LERP(gy0, x00, x10, y)
  SIMREEL_CORNER(e, x0, y0z1, 0.0f, 0.0f, 1.0f)
  const float k3 = ve - va;
  k5 = k5 - ve;
  float k6 = ab - ve;
  k7 = k7 + ve;
  SIMREEL_CORNER(f, x1, y0z1, 1.0f, 0.0f, 1.0f)
  k6 = k6 + vf;
  k7 = k7 - vf;
  SIMREEL_LERP(gx01, e, f, x)
  SIMREEL_CORNER(g, x0, y1z1, 0.0f, 1.0f, 1.0f)
  k5 = k5 + vg;
  k7 = k7 - vg;
  SIMREEL_CORNER(h, x1, y1z1, 1.0f, 1.0f, 1.0f)
  k7 = k7 + vh;
  SIMREEL_LERP(gx11, g, h, x)
  SIMREEL_LERP(gy1, x01, x11, y)
  const float z = f2 * f2 * f2 * (f2 * (f2 * 6.0f - 15.0f) + 10.0f);
  SIMREEL_LERP(out, y0, y1, z)
#undef SIMREEL_LERP
#undef SIMREEL_CORNER
  const float dux = 30.0f * f0 * f0 * (f0 * (f0 - 2.0f) + 1.0f);
  const float duy = 30.0f * f1 * f1 * (f1 * (f1 - 2.0f) + 1.0f);
  const float duz = 30.0f * f2 * f2 * (f2 * (f2 - 2.0f) + 1.0f);
  g0 = out0 + dux * (k1 + k4 * y + k6 * z + k7 * y * z);
  g1 = out1 + duy * (k2 + k4 * x + k5 * z + k7 * x * z);
  g2 = out2 + duz * (k3 + k5 * y + k6 * x + k7 * x * y);
  return va + k1 * x + k2 * y + k3 * z + k4 * x * y + k5 * y * z + k6 * z * x + k7 * x * y * z;
}

/// The lattice of p with 64-bit cells (any finite p; a non-finite coordinate takes cell 0),
/// wrapped to the 32 bits the hash uses.
Lattice lattice_of(const Vec3& p) {
  Lattice l;
  std::uint32_t* cell[3] = {&l.x0, &l.y0, &l.z0};
  float* frac[3] = {&l.f0, &l.f1, &l.f2};
  const std::uint32_t prime[3] = {kPrimeX, kPrimeY, kPrimeZ};
  for (int k = 0; k < 3; ++k) {
    const double fl = std::floor(p[k]);
    const bool ok = std::isfinite(fl) && std::abs(fl) < 9.0e18;
    *cell[k] = (ok ? std::uint32_t(std::uint64_t(std::int64_t(fl))) : 0u) * prime[k];
    *frac[k] = ok ? float(p[k] - fl) : 0.0f;
  }
  return l;
}

/// curl ψ from the three potentials' gradients: (∂ψ3/∂y - ∂ψ2/∂z, ∂ψ1/∂z - ∂ψ3/∂x,
/// ∂ψ2/∂x - ∂ψ1/∂y), each difference of potential2()'s doubled gradients halved (exact).
__attribute__((always_inline)) inline void curl_at(const std::uint32_t* seed, const Lattice& l,
                                                   float& ux, float& uy, float& uz) {
  float a0, a1, a2, b0, b1, b2, c0, c1, c2;
  potential2(seed[0], l, a0, a1, a2);
  potential2(seed[1], l, b0, b1, b2);
  potential2(seed[2], l, c0, c1, c2);
  ux = (c1 - b2) * 0.5f;
  uy = (a2 - c0) * 0.5f;
  uz = (b0 - a1) * 0.5f;
}

/// std::floor(p) for |p| < 2^31, bit for bit (-0 stays -0), from a truncation the vector units
/// have (GCC vectorises std::floor itself only without -ftrapping-math).
inline double floor_lane(double p) {
  const double t = double(int(p));
  const double one = t > p ? 1.0 : 0.0;
  const double r = t - one;  // computed either way: selects, no branch
  return p == 0.0 ? p : r;
}

constexpr std::size_t kChunk = 64;  ///< points per pass of the vectorised loops

/// The lattice of up to kChunk points (cells times the primes, offsets in float); false when a
/// coordinate is not below 2^30 in magnitude (NaN included): the 32-bit cells would overflow,
/// the caller takes the scalar path (what is written then goes unused). In double, four or eight
/// lanes.
SIMREEL_VECTOR_CLONES
bool lattice_chunk(std::size_t n, const double* __restrict px, const double* __restrict py,
                   const double* __restrict pz, std::uint32_t* __restrict cx,
                   std::uint32_t* __restrict cy, std::uint32_t* __restrict cz,
                   float* __restrict fx, float* __restrict fy, float* __restrict fz) {
  constexpr double kLimit = 1073741824.0;  // 2^30
  int bad = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double x = px[k], y = py[k], z = pz[k];
    bad |= int(!(std::abs(x) < kLimit)) | int(!(std::abs(y) < kLimit)) | int(!(std::abs(z) < kLimit));
    // Clamped only so that the conversions stay defined; such a chunk is discarded.
    const double xs = std::abs(x) < kLimit ? x : 0.0, ys = std::abs(y) < kLimit ? y : 0.0,
                 zs = std::abs(z) < kLimit ? z : 0.0;
    const double flx = floor_lane(xs), fly = floor_lane(ys), flz = floor_lane(zs);
    cx[k] = std::uint32_t(int(flx)) * kPrimeX;
    cy[k] = std::uint32_t(int(fly)) * kPrimeY;
    cz[k] = std::uint32_t(int(flz)) * kPrimeZ;
    fx[k] = float(xs - flx);
    fy[k] = float(ys - fly);
    fz[k] = float(zs - flz);
  }
  return bad == 0;
}

/// curl_at() of kChunk-or-fewer lattice points into ux, uy, uz (widened to double), in float
/// lanes the compiler vectorises (eight).
SIMREEL_VECTOR_CLONES
void curl_floats(std::size_t n, const std::uint32_t* __restrict seed,
                 const std::uint32_t* __restrict cx, const std::uint32_t* __restrict cy,
                 const std::uint32_t* __restrict cz, const float* __restrict fx,
                 const float* __restrict fy, const float* __restrict fz, double* __restrict ux,
                 double* __restrict uy, double* __restrict uz) {
  alignas(64) float ox[kChunk], oy[kChunk], oz[kChunk];
  const std::uint32_t s[3] = {seed[0], seed[1], seed[2]};
  for (std::size_t k = 0; k < n; ++k) {
    const Lattice l{cx[k], cy[k], cz[k], fx[k], fy[k], fz[k]};
    curl_at(s, l, ox[k], oy[k], oz[k]);
  }
  for (std::size_t k = 0; k < n; ++k) {
    ux[k] = ox[k];
    uy[k] = oy[k];
    uz[k] = oz[k];
  }
}

#if SIMREEL_HAS_VECTOR_CLONES
/// Table of twice a gradient component by row (0..15), as floats: the rows of kGradX, kGradY or
/// kGradZ doubled, as grad_component2() gives them.
constexpr std::array<float, 16> component_row(std::uint32_t table) {
  std::array<float, 16> r{};
  for (std::uint32_t h = 0; h < 16; ++h) r[h] = float(2 * (int((table >> (2 * h)) & 3u) - 1));
  return r;
}
constexpr std::array<float, 16> kRowX = component_row(kGradX), kRowY = component_row(kGradY),
                                kRowZ = component_row(kGradZ);

#define SIMREEL_AVX512 __attribute__((target("avx512f"), always_inline)) inline
SIMREEL_AVX512 __m512 mul(__m512 a, __m512 b) { return _mm512_mul_ps(a, b); }
SIMREEL_AVX512 __m512 add(__m512 a, __m512 b) { return _mm512_add_ps(a, b); }
SIMREEL_AVX512 __m512 sub(__m512 a, __m512 b) { return _mm512_sub_ps(a, b); }

/// One corner of a cell in sixteen lanes: its gradient (g0, g1, g2) and ramp value v.
struct Corner16 {
  __m512 g0, g1, g2, v;
};

/// The corner with hashed coordinates (hx, hy, hz) and offsets (ox, oy, oz) = f - c: its row the
/// top 4 bits of ((hx ^ hy ^ hz) kHashMul), the ramp g . (f - c) in potential2()'s order.
SIMREEL_AVX512 Corner16 corner16(__m512i hx, __m512i hy, __m512i hz, __m512 ox, __m512 oy,
                                 __m512 oz, __m512 tx, __m512 ty, __m512 tz) {
  // (The masked forms with every lane set: GCC 12's unmasked ones pass an undefined register
  // through and warn that it may be used uninitialized.)
  constexpr __mmask16 kAll = 0xffff;
  const __m512i hash = _mm512_mullo_epi32(_mm512_xor_si512(_mm512_xor_si512(hx, hy), hz),
                                          _mm512_set1_epi32(int(kHashMul)));
  const __m512i row = _mm512_mask_srli_epi32(hash, kAll, hash, 28);
  Corner16 c;
  c.g0 = _mm512_mask_permutexvar_ps(tx, kAll, row, tx);
  c.g1 = _mm512_mask_permutexvar_ps(ty, kAll, row, ty);
  c.g2 = _mm512_mask_permutexvar_ps(tz, kAll, row, tz);
  c.v = add(add(mul(c.g0, ox), mul(c.g1, oy)), mul(c.g2, oz));
  return c;
}

/// potential2()'s trilinear blend of one gradient component over the corners a..h.
SIMREEL_AVX512 __m512 blend16(__m512 x, __m512 y, __m512 z, __m512 ga, __m512 gb, __m512 gc,
                              __m512 gd, __m512 ge, __m512 gf, __m512 gg, __m512 gh) {
  const __m512 gx00 = add(ga, mul(x, sub(gb, ga))), gx10 = add(gc, mul(x, sub(gd, gc)));
  const __m512 gx01 = add(ge, mul(x, sub(gf, ge))), gx11 = add(gg, mul(x, sub(gh, gg)));
  const __m512 gy0 = add(gx00, mul(y, sub(gx10, gx00))), gy1 = add(gx01, mul(y, sub(gx11, gx01)));
  return add(gy0, mul(z, sub(gy1, gy0)));
}

/// The lower (half 0) or upper (half 1) eight floats of v. (The masked extract: GCC 12's plain
/// one, and the cast that uses it, pass an undefined register through and warn that it may be
/// used uninitialized.)
template <int kHalf>
SIMREEL_AVX512 __m256 half8(__m512 v) {
  return _mm256_castpd_ps(_mm512_maskz_extractf64x4_pd(0xf, _mm512_castps_pd(v), kHalf));
}

/// potential2() for sixteen points in AVX-512 lanes: the same float operations in the same order
/// (no contraction), each corner's row the top 4 bits of its hash (what potential2()'s 2-bit
/// shift of bits 27-31 selects) and its gradient components three permutes of 16-entry tables
/// (the scalar form's variable shift and mask, three times a corner), of doubled components.
SIMREEL_AVX512 void potential16(
    __m512i seed, __m512i lx0, __m512i ly0, __m512i lz0, __m512 f0, __m512 f1, __m512 f2,
    __m512 tx, __m512 ty, __m512 tz, __m512& g0, __m512& g1, __m512& g2) {
  const __m512 c6 = _mm512_set1_ps(6.0f), c15 = _mm512_set1_ps(15.0f), c10 = _mm512_set1_ps(10.0f);
  const __m512 c30 = _mm512_set1_ps(30.0f), c2 = _mm512_set1_ps(2.0f), one = _mm512_set1_ps(1.0f);
  // x = f0 f0 f0 (f0 (f0 6 - 15) + 10); dux = 30 f0 f0 (f0 (f0 - 2) + 1)
  const __m512 x = mul(mul(mul(f0, f0), f0), add(mul(f0, sub(mul(f0, c6), c15)), c10));
  const __m512 y = mul(mul(mul(f1, f1), f1), add(mul(f1, sub(mul(f1, c6), c15)), c10));
  const __m512 z = mul(mul(mul(f2, f2), f2), add(mul(f2, sub(mul(f2, c6), c15)), c10));
  const __m512 dux = mul(mul(mul(c30, f0), f0), add(mul(f0, sub(f0, c2)), one));
  const __m512 duy = mul(mul(mul(c30, f1), f1), add(mul(f1, sub(f1, c2)), one));
  const __m512 duz = mul(mul(mul(c30, f2), f2), add(mul(f2, sub(f2, c2)), one));
  const __m512i x0 = _mm512_xor_si512(lx0, seed),
                x1 = _mm512_xor_si512(_mm512_add_epi32(lx0, _mm512_set1_epi32(int(kPrimeX))), seed);
  const __m512i y0 = ly0, y1 = _mm512_add_epi32(ly0, _mm512_set1_epi32(int(kPrimeY)));
  const __m512i z0 = lz0, z1 = _mm512_add_epi32(lz0, _mm512_set1_epi32(int(kPrimeZ)));
  const __m512 fm0 = sub(f0, one), fm1 = sub(f1, one), fm2 = sub(f2, one);
  const Corner16 a = corner16(x0, y0, z0, f0, f1, f2, tx, ty, tz),
                 b = corner16(x1, y0, z0, fm0, f1, f2, tx, ty, tz),
                 c = corner16(x0, y1, z0, f0, fm1, f2, tx, ty, tz),
                 d = corner16(x1, y1, z0, fm0, fm1, f2, tx, ty, tz),
                 e = corner16(x0, y0, z1, f0, f1, fm2, tx, ty, tz),
                 f = corner16(x1, y0, z1, fm0, f1, fm2, tx, ty, tz),
                 g = corner16(x0, y1, z1, f0, fm1, fm2, tx, ty, tz),
                 h = corner16(x1, y1, z1, fm0, fm1, fm2, tx, ty, tz);
  const __m512 k1 = sub(b.v, a.v), k2 = sub(c.v, a.v), k3 = sub(e.v, a.v);
  const __m512 k4 = add(sub(sub(a.v, b.v), c.v), d.v), k5 = add(sub(sub(a.v, c.v), e.v), g.v),
               k6 = add(sub(sub(a.v, b.v), e.v), f.v);
  const __m512 neg_a = _mm512_castsi512_ps(
      _mm512_xor_si512(_mm512_castps_si512(a.v), _mm512_set1_epi32(int(0x80000000u))));
  const __m512 k7 =
      add(sub(sub(add(sub(add(add(neg_a, b.v), c.v), d.v), e.v), f.v), g.v), h.v);
  const __m512 out0 = blend16(x, y, z, a.g0, b.g0, c.g0, d.g0, e.g0, f.g0, g.g0, h.g0);
  const __m512 out1 = blend16(x, y, z, a.g1, b.g1, c.g1, d.g1, e.g1, f.g1, g.g1, h.g1);
  const __m512 out2 = blend16(x, y, z, a.g2, b.g2, c.g2, d.g2, e.g2, f.g2, g.g2, h.g2);
  g0 = add(out0, mul(dux, add(add(add(k1, mul(k4, y)), mul(k6, z)), mul(mul(k7, y), z))));
  g1 = add(out1, mul(duy, add(add(add(k2, mul(k4, x)), mul(k5, z)), mul(mul(k7, x), z))));
  g2 = add(out2, mul(duz, add(add(add(k3, mul(k5, y)), mul(k6, x)), mul(mul(k7, x), y))));
}

/// curl_floats() sixteen points at a time in AVX-512 (potential16()), the last ones under a
/// mask; the same bits.
__attribute__((target("avx512f")))
void curl_floats_avx512(std::size_t n, const std::uint32_t* __restrict seed,
                        const std::uint32_t* __restrict cx, const std::uint32_t* __restrict cy,
                        const std::uint32_t* __restrict cz, const float* __restrict fx,
                        const float* __restrict fy, const float* __restrict fz,
                        double* __restrict ux, double* __restrict uy, double* __restrict uz) {
  const __m512 tx = _mm512_loadu_ps(kRowX.data()), ty = _mm512_loadu_ps(kRowY.data()),
               tz = _mm512_loadu_ps(kRowZ.data());
  const __m512i s0 = _mm512_set1_epi32(int(seed[0])), s1 = _mm512_set1_epi32(int(seed[1])),
                s2 = _mm512_set1_epi32(int(seed[2]));
  for (std::size_t k = 0; k < n; k += 16) {
    const __mmask16 m = n - k >= 16 ? __mmask16(0xffff) : __mmask16((1u << (n - k)) - 1u);
    const __m512i lx = _mm512_maskz_loadu_epi32(m, cx + k), ly = _mm512_maskz_loadu_epi32(m, cy + k),
                  lz = _mm512_maskz_loadu_epi32(m, cz + k);
    const __m512 f0 = _mm512_maskz_loadu_ps(m, fx + k), f1 = _mm512_maskz_loadu_ps(m, fy + k),
                 f2 = _mm512_maskz_loadu_ps(m, fz + k);
    __m512 a0, a1, a2, b0, b1, b2, c0, c1, c2;
    potential16(s0, lx, ly, lz, f0, f1, f2, tx, ty, tz, a0, a1, a2);
    potential16(s1, lx, ly, lz, f0, f1, f2, tx, ty, tz, b0, b1, b2);
    potential16(s2, lx, ly, lz, f0, f1, f2, tx, ty, tz, c0, c1, c2);
    const __m512 half = _mm512_set1_ps(0.5f);
    const __m512 vx = mul(sub(c1, b2), half), vy = mul(sub(a2, c0), half),
                 vz = mul(sub(b0, a1), half);
    const __mmask8 lo = __mmask8(m & 0xff), hi = __mmask8(m >> 8);
    _mm512_mask_storeu_pd(ux + k, lo, _mm512_maskz_cvtps_pd(0xff, half8<0>(vx)));
    _mm512_mask_storeu_pd(uy + k, lo, _mm512_maskz_cvtps_pd(0xff, half8<0>(vy)));
    _mm512_mask_storeu_pd(uz + k, lo, _mm512_maskz_cvtps_pd(0xff, half8<0>(vz)));
    if (hi != 0) {
      _mm512_mask_storeu_pd(ux + k + 8, hi, _mm512_maskz_cvtps_pd(0xff, half8<1>(vx)));
      _mm512_mask_storeu_pd(uy + k + 8, hi, _mm512_maskz_cvtps_pd(0xff, half8<1>(vy)));
      _mm512_mask_storeu_pd(uz + k + 8, hi, _mm512_maskz_cvtps_pd(0xff, half8<1>(vz)));
    }
  }
}

#undef SIMREEL_AVX512

/// The CPU runs curl_floats_avx512() (checked once).
bool has_avx512f() {
  static const bool yes = cpu_has_avx512f();
  return yes;
}
#endif

}  // namespace

double GradientNoise::sample(int c, const Vec3& p, Vec3& grad) const {
  float g0, g1, g2;
  const float v = potential2(seed_[c], lattice_of(p), g0, g1, g2);
  grad = Vec3(g0 * 0.5f, g1 * 0.5f, g2 * 0.5f);
  return v * 0.5f;
}

void GradientNoise::curl(std::size_t n, const double* px, const double* py, const double* pz,
                         double* ux, double* uy, double* uz, int lanes) const {
#if SIMREEL_HAS_VECTOR_CLONES
  const bool wide = lanes >= 16 && has_avx512f();
#else
  (void)lanes;
#endif
  alignas(64) std::uint32_t cx[kChunk], cy[kChunk], cz[kChunk];
  alignas(64) float fx[kChunk], fy[kChunk], fz[kChunk];
  for (std::size_t b = 0; b < n; b += kChunk) {
    const std::size_t len = std::min(kChunk, n - b);
    if (lattice_chunk(len, px + b, py + b, pz + b, cx, cy, cz, fx, fy, fz)) {
#if SIMREEL_HAS_VECTOR_CLONES
      if (wide) {
        curl_floats_avx512(len, seed_, cx, cy, cz, fx, fy, fz, ux + b, uy + b, uz + b);
        continue;
      }
#endif
      curl_floats(len, seed_, cx, cy, cz, fx, fy, fz, ux + b, uy + b, uz + b);
      continue;
    }
    for (std::size_t k = b; k < b + len; ++k) {
      float x, y, z;
      curl_at(seed_, lattice_of(Vec3(px[k], py[k], pz[k])), x, y, z);
      ux[k] = x;
      uy[k] = y;
      uz[k] = z;
    }
  }
}

Vec3 curl_noise(const GradientNoise& noise, const Vec3& p) {
  double u[3];
  noise.curl(1, &p.x(), &p.y(), &p.z(), &u[0], &u[1], &u[2]);
  return {u[0], u[1], u[2]};
}

}  // namespace simreel::sim::detail
