// Gradient (Perlin) noise with its analytic gradient and the curl-noise velocity built on it
// (Bridson et al. 2007).
#include "particles/noise.hpp"

#include <cmath>

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
}

namespace {

/// The 12 edge directions of a cube (Perlin 2002), picked by the low bits of the hash.
Vec3 gradient_of(int h) {
  static const double g[16][3] = {{1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0},
                                  {1, 0, 1}, {-1, 0, 1}, {1, 0, -1}, {-1, 0, -1},
                                  {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1},
                                  {1, 1, 0}, {-1, 1, 0}, {0, -1, 1}, {0, -1, -1}};
  const double* r = g[h & 15];
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

Vec3 curl_noise(const GradientNoise& noise, const Vec3& p) {
  // Offsets far apart relative to the noise's correlation length (1) decorrelate the components.
  static const Vec3 o1(31.416, -47.853, 12.793), o2(-93.989, 26.433, 83.279);
  Vec3 g1, g2, g3;
  noise.sample(p, g1);
  noise.sample(p + o1, g2);
  noise.sample(p + o2, g3);
  // curl (ψ1, ψ2, ψ3) = (∂ψ3/∂y - ∂ψ2/∂z, ∂ψ1/∂z - ∂ψ3/∂x, ∂ψ2/∂x - ∂ψ1/∂y)
  return {g3.y() - g2.z(), g1.z() - g3.x(), g2.x() - g1.y()};
}

}  // namespace simreel::sim::detail
