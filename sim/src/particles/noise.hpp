#pragma once
// Gradient noise and curl noise (private): the divergence-free turbulence of the curl-noise force
// field (Bridson, Hourihan & Nordenstam 2007), beyond the book.

#include <cstddef>
#include <cstdint>

#include "simreel/sim/types.hpp"

namespace simreel::sim::detail {

/// 3D gradient (Perlin) noise with its analytic gradient, from a permutation shuffled with the
/// project's Rng (so the field is fixed by the scene seed). Values lie roughly in [-1, 1].
class GradientNoise {
 public:
  explicit GradientNoise(std::uint64_t seed = 0);
  /// Noise value at p; its gradient (per unit of p) goes to `grad`.
  double sample(const Vec3& p, Vec3& grad) const;
  /// Gradients at n points (px, py, pz: n each) into gx, gy, gz: bit for bit what sample()
  /// gives, lane by lane in a loop the compiler vectorises (the curl needs three per particle).
  /// Points with a coordinate beyond +-2^30 go through sample() itself.
  void gradients(std::size_t n, const double* px, const double* py, const double* pz, double* gx,
                 double* gy, double* gz) const;

 private:
  std::uint8_t perm_[512];
  std::int32_t perm32_[512];  ///< perm_ widened (32-bit gathers)
};

/// Curl-noise velocity (Bridson et al. 2007): u = curl ψ with ψ = (N(p), N(p + o1), N(p + o2)),
/// three decorrelated copies of one noise, all derivatives analytic, so div u = 0 exactly (up to
/// rounding). Per unit of p; the caller scales by amplitude.
Vec3 curl_noise(const GradientNoise& noise, const Vec3& p);

/// The offsets of the second and third potentials of curl_noise() (in units of p).
extern const Vec3 kCurlOffset1, kCurlOffset2;

}  // namespace simreel::sim::detail
