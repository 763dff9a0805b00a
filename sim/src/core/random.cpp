// Rng: xoshiro256** seeded through splitmix64, Box–Muller normal (see random.hpp).
#include "simreel/sim/random.hpp"

#include <cmath>
#include <numbers>

namespace simreel::sim {
namespace {

/// splitmix64 (Vigna): the seeding generator recommended for xoshiro, so that nearby seeds give
/// unrelated states.
std::uint64_t splitmix64(std::uint64_t& x) {
  std::uint64_t z = (x += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

constexpr std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

}  // namespace

Rng::Rng(std::uint64_t seed, std::uint64_t stream) {
  // Both inputs go through a full splitmix64 round before they meet, so (seed, stream) pairs that
  // differ in one bit still start far apart.
  std::uint64_t a = seed;
  std::uint64_t b = stream ^ 0x632BE59BD9B4E019ULL;
  std::uint64_t x = splitmix64(a) ^ rotl(splitmix64(b), 17);
  for (std::uint64_t& s : s_) s = splitmix64(x);
  if ((s_[0] | s_[1] | s_[2] | s_[3]) == 0) s_[0] = 1;  // the one state xoshiro cannot leave
}

std::uint64_t Rng::next_u64() {
  const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
  const std::uint64_t t = s_[1] << 17;
  s_[2] ^= s_[0];
  s_[3] ^= s_[1];
  s_[1] ^= s_[2];
  s_[0] ^= s_[3];
  s_[2] ^= t;
  s_[3] = rotl(s_[3], 45);
  return result;
}

double Rng::uniform() { return double(next_u64() >> 11) * 0x1.0p-53; }

double Rng::normal() {
  if (has_cached_) {
    has_cached_ = false;
    return cached_;
  }
  // 1 - u lies in (0, 1], so the logarithm is finite.
  const double u1 = 1.0 - uniform();
  const double u2 = uniform();
  const double r = std::sqrt(-2.0 * std::log(u1));
  const double phi = 2.0 * std::numbers::pi * u2;
  cached_ = r * std::sin(phi);
  has_cached_ = true;
  return r * std::cos(phi);
}

}  // namespace simreel::sim
