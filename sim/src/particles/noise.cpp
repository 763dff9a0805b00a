// Gradient (Perlin) noise with its analytic gradient and the curl-noise velocity built on it
// (Bridson et al. 2007).
#include "particles/noise.hpp"

#include <cmath>

#include "core/vector_clones.hpp"
#include "simreel/sim/random.hpp"

namespace simreel::sim::detail {

// ---------------------------------------------------------------------------------------------
// Gradient noise

GradientNoise::GradientNoise(std::uint64_t seed) {
  Rng rng(seed, 0xC0FFEE);
  for (int i = 0; i < 256; ++i) perm_[i] = std::uint8_t(i);
  for (int i = 255; i > 0; --i) {  // Fisher–Yates with the project's generator
    const int j = int(rng.next_u64() % std::uint64_t(i + 1));
    std::swap(perm_[i], perm_[j]);
  }
  for (int i = 0; i < 256; ++i) perm_[256 + i] = perm_[i];
  for (int i = 0; i < 512; ++i) perm32_[i] = perm_[i];
}

namespace {

/// The 12 edge directions of a cube (Perlin 2002), picked by the low bits of the hash.
constexpr double kGrad[16][3] = {{1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0},
                                 {1, 0, 1}, {-1, 0, 1}, {1, 0, -1}, {-1, 0, -1},
                                 {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1},
                                 {1, 1, 0}, {-1, 1, 0}, {0, -1, 1}, {0, -1, -1}};

Vec3 gradient_of(int h) {
  const double* r = kGrad[h & 15];
  return {r[0], r[1], r[2]};
}

}  // namespace

double GradientNoise::sample(const Vec3& p, Vec3& grad) const {
  const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const int ix = int(std::int64_t(fx) & 255), iy = int(std::int64_t(fy) & 255),
            iz = int(std::int64_t(fz) & 255);
  const Vec3 f(p.x() - fx, p.y() - fy, p.z() - fz);
  // Quintic fade 6t^5 - 15t^4 + 10t^3 and its derivative: C2, so the curl is C1.
  Vec3 u, du;
  for (int k = 0; k < 3; ++k) {
    const double t = f[k];
    u[k] = t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    du[k] = 30.0 * t * t * (t * (t - 2.0) + 1.0);
  }
  auto corner = [&](int cx, int cy, int cz, double& value) {
    const int h = perm_[perm_[perm_[ix + cx] + iy + cy] + iz + cz];
    const Vec3 g = gradient_of(h);
    value = g.dot(f - Vec3(cx, cy, cz));
    return g;
  };
  double va, vb, vc, vd, ve, vf, vg, vh;
  const Vec3 ga = corner(0, 0, 0, va), gb = corner(1, 0, 0, vb), gc = corner(0, 1, 0, vc),
             gd = corner(1, 1, 0, vd), ge = corner(0, 0, 1, ve), gf = corner(1, 0, 1, vf),
             gg = corner(0, 1, 1, vg), gh = corner(1, 1, 1, vh);
  // Trilinear blend of the corner ramps and its exact derivative (Quilez, "gradient noise
  // derivatives"): value = k0 + k1 u + k2 v + k3 w + k4 uv + k5 vw + k6 wu + k7 uvw.
  const double k1 = vb - va, k2 = vc - va, k3 = ve - va, k4 = va - vb - vc + vd,
               k5 = va - vc - ve + vg, k6 = va - vb - ve + vf,
               k7 = -va + vb + vc - vd + ve - vf - vg + vh;
  const double x = u.x(), y = u.y(), z = u.z();
  const double value = va + k1 * x + k2 * y + k3 * z + k4 * x * y + k5 * y * z + k6 * z * x +
                       k7 * x * y * z;
  // The same trilinear blend of the corner gradients, written as nested lerps (cheaper than
  // the expanded form and algebraically equal).
  const Vec3 gx00 = ga + x * (gb - ga), gx10 = gc + x * (gd - gc);
  const Vec3 gx01 = ge + x * (gf - ge), gx11 = gg + x * (gh - gg);
  const Vec3 gy0 = gx00 + y * (gx10 - gx00), gy1 = gx01 + y * (gx11 - gx01);
  grad = gy0 + z * (gy1 - gy0);
  grad.x() += du.x() * (k1 + k4 * y + k6 * z + k7 * y * z);
  grad.y() += du.y() * (k2 + k4 * x + k5 * z + k7 * x * z);
  grad.z() += du.z() * (k3 + k5 * y + k6 * x + k7 * x * y);
  return value;
}

namespace {

/// std::floor(p) for |p| < 2^31, bit for bit (-0 stays -0), from a truncation the vector units
/// have (GCC vectorises std::floor itself only without -ftrapping-math).
inline double floor_lane(double p) {
  const double t = double(int(p));
  const double one = t > p ? 1.0 : 0.0;
  const double r = t - one;  // computed either way: selects, no branch
  return p == 0.0 ? p : r;
}

/// gradients() for lanes whose coordinates fit in 32-bit cells: every expression below is the
/// one in sample() (same operands, same order; the build has -ffp-contract=off), written per
/// component so the loop vectorises. The permutation lookups become gathers; the gradient table
/// kGrad becomes bit masks per component (bit h: row h's component is non-zero; is negative),
/// selected with shifts: component = nonzero - 2 negative, exactly 1, -1 or +0 as in kGrad.
SIMREEL_VECTOR_CLONES
void gradients_lanes(std::size_t n, const std::int32_t* __restrict perm, const double* __restrict px,
                     const double* __restrict py, const double* __restrict pz,
                     double* __restrict gx, double* __restrict gy, double* __restrict gz) {
  for (std::size_t k = 0; k < n; ++k) {
    const double fx = floor_lane(px[k]), fy = floor_lane(py[k]), fz = floor_lane(pz[k]);
    const int ix = int(fx) & 255, iy = int(fy) & 255, iz = int(fz) & 255;
    const double f0 = px[k] - fx, f1 = py[k] - fy, f2 = pz[k] - fz;
    const double x = f0 * f0 * f0 * (f0 * (f0 * 6.0 - 15.0) + 10.0);
    const double y = f1 * f1 * f1 * (f1 * (f1 * 6.0 - 15.0) + 10.0);
    const double z = f2 * f2 * f2 * (f2 * (f2 * 6.0 - 15.0) + 10.0);
    const double dux = 30.0 * f0 * f0 * (f0 * (f0 - 2.0) + 1.0);
    const double duy = 30.0 * f1 * f1 * (f1 * (f1 - 2.0) + 1.0);
    const double duz = 30.0 * f2 * f2 * (f2 * (f2 - 2.0) + 1.0);
    const int a = perm[ix], b = perm[ix + 1];
    const int aa = perm[a + iy], ab = perm[a + iy + 1], ba = perm[b + iy], bb = perm[b + iy + 1];
    // Corners (cx, cy, cz): hash, gradient, ramp value g . (f - c). Written out (no inner
    // loops) so the whole body is one basic block.
#define SIMREEL_CORNER(name, hash, cx, cy, cz)                                               \
  const int h##name = (hash) & 15;                                                          \
  const double g##name##0 = double(((0x30FF >> h##name) & 1) - 2 * ((0x20AA >> h##name) & 1)); \
  const double g##name##1 = double(((0xFF0F >> h##name) & 1) - 2 * ((0xCA0C >> h##name) & 1)); \
  const double g##name##2 = double(((0xCFF0 >> h##name) & 1) - 2 * ((0x8CC0 >> h##name) & 1)); \
  const double v##name = g##name##0 * (f0 - cx) + g##name##1 * (f1 - cy) + g##name##2 * (f2 - cz);
    SIMREEL_CORNER(a, perm[aa + iz], 0.0, 0.0, 0.0)
    SIMREEL_CORNER(b, perm[ba + iz], 1.0, 0.0, 0.0)
    SIMREEL_CORNER(c, perm[ab + iz], 0.0, 1.0, 0.0)
    SIMREEL_CORNER(d, perm[bb + iz], 1.0, 1.0, 0.0)
    SIMREEL_CORNER(e, perm[aa + iz + 1], 0.0, 0.0, 1.0)
    SIMREEL_CORNER(f, perm[ba + iz + 1], 1.0, 0.0, 1.0)
    SIMREEL_CORNER(g, perm[ab + iz + 1], 0.0, 1.0, 1.0)
    SIMREEL_CORNER(h, perm[bb + iz + 1], 1.0, 1.0, 1.0)
#undef SIMREEL_CORNER
    const double k1 = vb - va, k2 = vc - va, k3 = ve - va, k4 = va - vb - vc + vd,
                 k5 = va - vc - ve + vg, k6 = va - vb - ve + vf,
                 k7 = -va + vb + vc - vd + ve - vf - vg + vh;
    double out[3];
#define SIMREEL_BLEND(d)                                                                   \
  {                                                                                       \
    const double gx00 = ga##d + x * (gb##d - ga##d), gx10 = gc##d + x * (gd##d - gc##d);   \
    const double gx01 = ge##d + x * (gf##d - ge##d), gx11 = gg##d + x * (gh##d - gg##d);   \
    const double gy0 = gx00 + y * (gx10 - gx00), gy1 = gx01 + y * (gx11 - gx01);           \
    out[d] = gy0 + z * (gy1 - gy0);                                                       \
  }
    SIMREEL_BLEND(0)
    SIMREEL_BLEND(1)
    SIMREEL_BLEND(2)
#undef SIMREEL_BLEND
    gx[k] = out[0] + dux * (k1 + k4 * y + k6 * z + k7 * y * z);
    gy[k] = out[1] + duy * (k2 + k4 * x + k5 * z + k7 * x * z);
    gz[k] = out[2] + duz * (k3 + k5 * y + k6 * x + k7 * x * y);
  }
}

}  // namespace

void GradientNoise::gradients(std::size_t n, const double* px, const double* py,
                              const double* pz, double* gx, double* gy, double* gz) const {
  // 32-bit cell indices give the same low 8 bits as sample()'s 64-bit ones while |p| < 2^31.
  constexpr double kLimit = 1073741824.0;  // 2^30
  bool fits = true;
  for (std::size_t k = 0; k < n; ++k)
    fits = fits && std::abs(px[k]) < kLimit && std::abs(py[k]) < kLimit && std::abs(pz[k]) < kLimit;
  if (fits) {
    gradients_lanes(n, perm32_, px, py, pz, gx, gy, gz);
    return;
  }
  for (std::size_t k = 0; k < n; ++k) {
    Vec3 g;
    sample(Vec3(px[k], py[k], pz[k]), g);
    gx[k] = g.x();
    gy[k] = g.y();
    gz[k] = g.z();
  }
}

// Offsets far apart relative to the noise's correlation length (1) decorrelate the components.
const Vec3 kCurlOffset1(31.416, -47.853, 12.793), kCurlOffset2(-93.989, 26.433, 83.279);

Vec3 curl_noise(const GradientNoise& noise, const Vec3& p) {
  Vec3 g1, g2, g3;
  noise.sample(p, g1);
  noise.sample(p + kCurlOffset1, g2);
  noise.sample(p + kCurlOffset2, g3);
  // curl (ψ1, ψ2, ψ3) = (∂ψ3/∂y - ∂ψ2/∂z, ∂ψ1/∂z - ∂ψ3/∂x, ∂ψ2/∂x - ∂ψ1/∂y)
  return {g3.y() - g2.z(), g1.z() - g3.x(), g2.x() - g1.y()};
}

}  // namespace simreel::sim::detail
