#pragma once
// Gradient noise and curl noise (private): the divergence-free turbulence of the curl-noise force
// field (Bridson, Hourihan & Nordenstam 2007), beyond the book.

#include <cstddef>
#include <cstdint>

#include "simreel/sim/types.hpp"

namespace simreel::sim::detail {

/// Three decorrelated 3D gradient (Perlin) noises on one integer lattice, with analytic
/// gradients: Perlin's 12 cube-edge gradients and quintic fade (Perlin 2002), the corner
/// gradient picked by a multiplicative hash of the cell and a per-potential seed (the seeds come
/// from the project's Rng, so the field is fixed by the scene seed). Values lie roughly in
/// [-1, 1]. Evaluated in single precision: the three potentials share the cell, the fade and
/// the corner offsets, and eight lanes fit an AVX2 register.
class GradientNoise {
 public:
  explicit GradientNoise(std::uint64_t seed = 0);
  /// Potential c's (0, 1 or 2) value at p; its gradient (per unit of p) goes to `grad`.
  double sample(int c, const Vec3& p, Vec3& grad) const;
  /// Curl-noise velocities at n points (px, py, pz: n each) into ux, uy, uz (Bridson et al.
  /// 2007): u = curl ψ with ψ = (N0(p), N1(p), N2(p)), all derivatives analytic, so div u = 0
  /// up to rounding. Bit for bit the curl of sample()'s gradients, in a loop the compiler
  /// vectorises; per unit of p (the caller scales by amplitude).
  /// `lanes`: the widest form to run, as the CPU allows: 16 (AVX-512F: sixteen points a
  /// register, each corner's gradient picked by three permutes), else the compiler's clones
  /// (AVX2 or AVX-512 eight lanes, or scalar); every form gives the same bits (the tests compare
  /// them).
  void curl(std::size_t n, const double* px, const double* py, const double* pz, double* ux,
            double* uy, double* uz, int lanes = 16) const;

 private:
  std::uint32_t seed_[3];
};

/// curl() at one point.
Vec3 curl_noise(const GradientNoise& noise, const Vec3& p);

}  // namespace simreel::sim::detail
