#pragma once
// Private: the back-to-front order of soft particles, rebuilt every frame.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace simreel::render::detail {

/// Sorts particle indices by decreasing depth with reused buffers (no allocation once grown).
class BackToFrontSort {
 public:
  /// Indices 0..depth.size()-1 by decreasing depth, equal depths in their given order: the
  /// order std::stable_sort with `depth[a] > depth[b]` gives. Valid until the next call.
  const std::vector<std::uint32_t>& sort(const std::vector<float>& depth);

 private:
  std::vector<std::uint32_t> index_, scratch_;
  std::vector<std::uint32_t> key_, key_scratch_;
};

}  // namespace simreel::render::detail
