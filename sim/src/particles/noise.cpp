// Gradient (Perlin) noise with its analytic gradient and the curl-noise velocity built on it
// (Bridson et al. 2007).
#include "particles/noise.hpp"

#include <cmath>

#include "core/vector_clones.hpp"
#include "simreel/sim/random.hpp"

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
/// rows 12..15 repeating four of them. Each component is stored as 2 bits per row (value + 1)
/// in one constant, so the lookup is a shift by s = 2 h and a mask.
/// Rows: (1,1,0) (-1,1,0) (1,-1,0) (-1,-1,0) (1,0,1) (-1,0,1) (1,0,-1) (-1,0,-1) (0,1,1)
/// (0,-1,1) (0,1,-1) (0,-1,-1) (1,1,0) (-1,1,0) (0,-1,1) (0,-1,-1).
constexpr std::uint32_t kGradX = 0x52552222u, kGradY = 0x0A22550Au, kGradZ = 0x250A0A55u;
inline float grad_component(std::uint32_t s, std::uint32_t table) {
  return float(int((table >> s) & 3u) - 1);
}

/// The cell, fade and corner offsets of one point, shared by the three potentials.
struct Lattice {
  std::uint32_t x0, y0, z0;  ///< cell coordinates times the primes (corner 0)
  float f0, f1, f2;          ///< offset of the point in its cell, [0, 1)
};

/// One potential at one point: value, and gradient (g0, g1, g2) per unit of p. The quintic fade
/// 6t^5 - 15t^4 + 10t^3 is C2, so the curl is C1; the trilinear blend of the corner ramps and its
/// exact derivative follow Quilez ("gradient noise derivatives"). Straight-line float code (no
/// branches, no tables): inlined into the vectorised loop and into sample() alike, with
/// -ffp-contract=off, so both give the same bits.
__attribute__((always_inline)) inline float potential(std::uint32_t seed, const Lattice& l,
                                                      float& g0, float& g1, float& g2) {
  const float f0 = l.f0, f1 = l.f1, f2 = l.f2;
  const float x = f0 * f0 * f0 * (f0 * (f0 * 6.0f - 15.0f) + 10.0f);
  const float y = f1 * f1 * f1 * (f1 * (f1 * 6.0f - 15.0f) + 10.0f);
  const float z = f2 * f2 * f2 * (f2 * (f2 * 6.0f - 15.0f) + 10.0f);
  const float dux = 30.0f * f0 * f0 * (f0 * (f0 - 2.0f) + 1.0f);
  const float duy = 30.0f * f1 * f1 * (f1 * (f1 - 2.0f) + 1.0f);
  const float duz = 30.0f * f2 * f2 * (f2 * (f2 - 2.0f) + 1.0f);
  const std::uint32_t x0 = l.x0 ^ seed, x1 = (l.x0 + kPrimeX) ^ seed;
  const std::uint32_t y0 = l.y0, y1 = l.y0 + kPrimeY, z0 = l.z0, z1 = l.z0 + kPrimeZ;
  // Corners (cx, cy, cz): gradient and ramp value g . (f - c). Written out so the whole body is
  // one basic block.
#define SIMREEL_CORNER(name, hx, hy, hz, cx, cy, cz)                                     \
  const std::uint32_t h##name = (((hx ^ hy ^ hz) * kHashMul) >> 27) & 30u; /* 2 row */   \
  const float g##name##0 = grad_component(h##name, kGradX);                             \
  const float g##name##1 = grad_component(h##name, kGradY);                             \
  const float g##name##2 = grad_component(h##name, kGradZ);                             \
  const float v##name = g##name##0 * (f0 - cx) + g##name##1 * (f1 - cy) + g##name##2 * (f2 - cz);
  SIMREEL_CORNER(a, x0, y0, z0, 0.0f, 0.0f, 0.0f)
  SIMREEL_CORNER(b, x1, y0, z0, 1.0f, 0.0f, 0.0f)
  SIMREEL_CORNER(c, x0, y1, z0, 0.0f, 1.0f, 0.0f)
  SIMREEL_CORNER(d, x1, y1, z0, 1.0f, 1.0f, 0.0f)
  SIMREEL_CORNER(e, x0, y0, z1, 0.0f, 0.0f, 1.0f)
  SIMREEL_CORNER(f, x1, y0, z1, 1.0f, 0.0f, 1.0f)
  SIMREEL_CORNER(g, x0, y1, z1, 0.0f, 1.0f, 1.0f)
  SIMREEL_CORNER(h, x1, y1, z1, 1.0f, 1.0f, 1.0f)
#undef SIMREEL_CORNER
  // value = k0 + k1 u + k2 v + k3 w + k4 uv + k5 vw + k6 wu + k7 uvw (u, v, w: the fades).
  const float k1 = vb - va, k2 = vc - va, k3 = ve - va, k4 = va - vb - vc + vd,
              k5 = va - vc - ve + vg, k6 = va - vb - ve + vf,
              k7 = -va + vb + vc - vd + ve - vf - vg + vh;
  // The same trilinear blend of the corner gradients, as nested lerps.
  float out[3];
#define SIMREEL_BLEND(k)                                                                    \
  {                                                                                        \
    const float gx00 = ga##k + x * (gb##k - ga##k), gx10 = gc##k + x * (gd##k - gc##k);     \
    const float gx01 = ge##k + x * (gf##k - ge##k), gx11 = gg##k + x * (gh##k - gg##k);     \
    const float gy0 = gx00 + y * (gx10 - gx00), gy1 = gx01 + y * (gx11 - gx01);             \
    out[k] = gy0 + z * (gy1 - gy0);                                                        \
  }
  SIMREEL_BLEND(0)
  SIMREEL_BLEND(1)
  SIMREEL_BLEND(2)
#undef SIMREEL_BLEND
  g0 = out[0] + dux * (k1 + k4 * y + k6 * z + k7 * y * z);
  g1 = out[1] + duy * (k2 + k4 * x + k5 * z + k7 * x * z);
  g2 = out[2] + duz * (k3 + k5 * y + k6 * x + k7 * x * y);
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
/// ∂ψ2/∂x - ∂ψ1/∂y).
__attribute__((always_inline)) inline void curl_at(const std::uint32_t* seed, const Lattice& l,
                                                   float& ux, float& uy, float& uz) {
  float a0, a1, a2, b0, b1, b2, c0, c1, c2;
  potential(seed[0], l, a0, a1, a2);
  potential(seed[1], l, b0, b1, b2);
  potential(seed[2], l, c0, c1, c2);
  ux = c1 - b2;
  uy = a2 - c0;
  uz = b0 - a1;
}

/// std::floor(p) for |p| < 2^31, bit for bit (-0 stays -0), from a truncation the vector units
/// have (GCC vectorises std::floor itself only without -ftrapping-math).
inline double floor_lane(double p) {
  const double t = double(int(p));
  const double one = t > p ? 1.0 : 0.0;
  const double r = t - one;  // computed either way: selects, no branch
  return p == 0.0 ? p : r;
}

constexpr std::size_t kChunk = 64;  ///< points per pass of the two vectorised loops

/// curl() for up to kChunk points; false (and nothing written) when a coordinate is not below
/// 2^30 in magnitude (NaN included): the 32-bit cells would overflow, the caller takes the
/// scalar path. Two loops: the lattice in double (four lanes), the noise in float (eight).
SIMREEL_VECTOR_CLONES
bool curl_chunk(std::size_t n, const std::uint32_t* __restrict seed, const double* __restrict px,
                const double* __restrict py, const double* __restrict pz, double* __restrict ux,
                double* __restrict uy, double* __restrict uz) {
  constexpr double kLimit = 1073741824.0;  // 2^30
  alignas(64) std::uint32_t cx[kChunk], cy[kChunk], cz[kChunk];
  alignas(64) float fx[kChunk], fy[kChunk], fz[kChunk];
  alignas(64) float ox[kChunk], oy[kChunk], oz[kChunk];
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
  if (bad) return false;
  const std::uint32_t s0 = seed[0], s1 = seed[1], s2 = seed[2];
  const std::uint32_t s[3] = {s0, s1, s2};
  for (std::size_t k = 0; k < n; ++k) {
    const Lattice l{cx[k], cy[k], cz[k], fx[k], fy[k], fz[k]};
    curl_at(s, l, ox[k], oy[k], oz[k]);
  }
  for (std::size_t k = 0; k < n; ++k) {
    ux[k] = ox[k];
    uy[k] = oy[k];
    uz[k] = oz[k];
  }
  return true;
}

}  // namespace

double GradientNoise::sample(int c, const Vec3& p, Vec3& grad) const {
  float g0, g1, g2;
  const float v = potential(seed_[c], lattice_of(p), g0, g1, g2);
  grad = Vec3(g0, g1, g2);
  return v;
}

void GradientNoise::curl(std::size_t n, const double* px, const double* py, const double* pz,
                         double* ux, double* uy, double* uz) const {
  for (std::size_t b = 0; b < n; b += kChunk) {
    const std::size_t len = std::min(kChunk, n - b);
    if (curl_chunk(len, seed_, px + b, py + b, pz + b, ux + b, uy + b, uz + b)) continue;
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
