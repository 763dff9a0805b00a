#pragma once
// Gust noise of the cloth's wind (private to cloth/): a hash of the lattice and 1D value noise.

#include <cmath>
#include <cstdint>

namespace simreel::sim::detail {

/// splitmix64 finaliser: a hash of the lattice coordinates for the gust noise.
inline std::uint64_t mix(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/// Smooth value noise in [-1, 1]: random values at integer tau, smoothstep between them (C1).
inline double value_noise(std::uint64_t key, double tau) {
  const double fl = std::floor(tau);
  const double f = tau - fl;
  const auto k = std::int64_t(fl);
  auto at = [key](std::int64_t i) {
    return double(mix(key ^ mix(std::uint64_t(i))) >> 11) * 0x1.0p-53 * 2.0 - 1.0;
  };
  const double s = f * f * (3.0 - 2.0 * f);
  return at(k) + (at(k + 1) - at(k)) * s;
}

}  // namespace simreel::sim::detail
