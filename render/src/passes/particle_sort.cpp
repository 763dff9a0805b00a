// Back-to-front particle order by radix sort (passes/particle_sort.hpp).
#include "particle_sort.hpp"

#include <algorithm>
#include <cstring>

namespace simreel::render::detail {

const std::vector<std::uint32_t>& BackToFrontSort::sort(const std::vector<float>& depth) {
  // The stable comparison sort's order, found by a least-significant-digit radix sort of the
  // depths' bits (four passes of 8 bits, stable), several times faster for 100k particles.
  // NaN depths (no strict weak order) keep the comparison sort.
  const std::size_t n = depth.size();
  index_.resize(n);
  for (std::size_t i = 0; i < n; ++i) index_[i] = std::uint32_t(i);
  bool has_nan = false;
  key_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float d = depth[i] + 0.f;  // -0 becomes +0: the comparison sees them equal
    has_nan |= d != d;
    std::uint32_t bits;
    std::memcpy(&bits, &d, sizeof bits);
    // Bits that increase with the float; inverted, so that far (large depth) comes first.
    const std::uint32_t ascending = (bits & 0x80000000u) != 0 ? ~bits : bits | 0x80000000u;
    key_[i] = ~ascending;
  }
  if (has_nan) {
    std::stable_sort(index_.begin(), index_.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return depth[a] > depth[b]; });
    return index_;
  }
  scratch_.resize(n);
  key_scratch_.resize(n);
  for (int shift = 0; shift < 32; shift += 8) {
    std::size_t start[257] = {};
    for (std::size_t i = 0; i < n; ++i) ++start[((key_[i] >> shift) & 0xffu) + 1];
    if (start[((key_[0] >> shift) & 0xffu) + 1] == n) continue;  // one bucket: no change
    for (int b = 0; b < 256; ++b) start[b + 1] += start[b];
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t at = start[(key_[i] >> shift) & 0xffu]++;
      scratch_[at] = index_[i];
      key_scratch_[at] = key_[i];
    }
    index_.swap(scratch_);
    key_.swap(key_scratch_);
  }
  return index_;
}

}  // namespace simreel::render::detail
