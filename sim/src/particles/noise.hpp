#pragma once
// Gradient noise and curl noise (private): the divergence-free turbulence of the curl-noise force
// field (Bridson, Hourihan & Nordenstam 2007), beyond the book.

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

 private:
  std::uint8_t perm_[512];
};

/// Curl-noise velocity (Bridson et al. 2007): u = curl ψ with ψ = (N(p), N(p + o1), N(p + o2)),
/// three decorrelated copies of one noise, all derivatives analytic, so div u = 0 exactly (up to
/// rounding). Per unit of p; the caller scales by amplitude.
Vec3 curl_noise(const GradientNoise& noise, const Vec3& p);

}  // namespace simreel::sim::detail
