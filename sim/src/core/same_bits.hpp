#pragma once
// Whether a run of values is one value repeated, bit for bit: the kernels that divide by a
// per-particle mass (or radius, or step) then divide once for the run, which gives every lane
// the bits of its own division (the same operation on the same operands).
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace simreel::sim::detail {

/// True when p[0..len) all have the bits of p[0] (so -0 and +0, or two NaNs with different
/// payloads, differ); true for len = 0 (nothing is read then). T: float or double.
template <class T>
inline bool same_bits(const T* p, std::size_t len) {
  static_assert(sizeof(T) == 4 || sizeof(T) == 8);
  using Bits = std::conditional_t<sizeof(T) == 8, std::uint64_t, std::uint32_t>;
  if (len == 0) return true;
  const Bits first = __builtin_bit_cast(Bits, p[0]);
  Bits diff = 0;
  for (std::size_t i = 1; i < len; ++i) diff |= __builtin_bit_cast(Bits, p[i]) ^ first;
  return diff == 0;
}

/// True when p[0..len) is one value repeated, bit for bit, or p is null (no such array: a
/// charge that all particles lack), looking at a first stretch of 64 before the whole run, so
/// that varied values cost a few reads. T: float or double.
template <class T>
inline bool one_value(const T* p, std::size_t len) {
  return p == nullptr || (same_bits(p, len < 64 ? len : 64) && same_bits(p, len));
}

}  // namespace simreel::sim::detail
