#pragma once
// Whether a run of values is one value repeated, bit for bit: the kernels that divide by a
// per-particle mass (or radius, or step) then divide once for the run, which gives every lane
// the bits of its own division (the same operation on the same operands).
#include <cstddef>
#include <cstdint>

namespace simreel::sim::detail {

/// True when p[0..len) all have the bits of p[0] (so -0 and +0, or two NaNs with different
/// payloads, differ); true for len = 0 (nothing is read then).
inline bool same_bits(const double* p, std::size_t len) {
  if (len == 0) return true;
  const std::uint64_t first = __builtin_bit_cast(std::uint64_t, p[0]);
  std::uint64_t diff = 0;
  for (std::size_t i = 1; i < len; ++i) diff |= __builtin_bit_cast(std::uint64_t, p[i]) ^ first;
  return diff == 0;
}

/// same_bits() for floats (the stored per-particle values).
inline bool same_bits(const float* p, std::size_t len) {
  if (len == 0) return true;
  const std::uint32_t first = __builtin_bit_cast(std::uint32_t, p[0]);
  std::uint32_t diff = 0;
  for (std::size_t i = 1; i < len; ++i) diff |= __builtin_bit_cast(std::uint32_t, p[i]) ^ first;
  return diff == 0;
}

}  // namespace simreel::sim::detail
