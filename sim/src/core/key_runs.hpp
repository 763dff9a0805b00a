#pragma once
// A cursor over sorted cell keys, for the neighbour-grid searches that walk the occupied cells in
// key order (the particle-particle pairs, the pair forces). Private.

#include <cstddef>
#include <cstdint>

namespace simreel::sim::detail {

/// keys[0, count): sorted and distinct. Moves `cur` forward to the first key >= lo (where it is
/// past that already, it stays) and returns the end of the keys in [cur, hi], which holds at most
/// three (hi - lo <= 2: a column of three cells). The same as the two loops
///   while (cur < count && keys[cur] < lo) ++cur;  end = cur;
///   while (end < count && keys[end] <= hi) ++end;
/// but by counts of compares: the loops' exits, after 0, 1, 2 ... steps as the cells fall, are
/// what the branch predictor misses (the 100k cloud's pair search ~6 % faster).
inline std::size_t key_run(const std::uint64_t* keys, std::size_t count, std::size_t& cur,
                           std::uint64_t lo, std::uint64_t hi) {
  if (cur + 4 <= count) {
    // Those below lo are a prefix of the four.
    const std::size_t step = std::size_t(keys[cur] < lo) + std::size_t(keys[cur + 1] < lo) +
                             std::size_t(keys[cur + 2] < lo) + std::size_t(keys[cur + 3] < lo);
    cur += step;
    if (step == 4)  // rare: four or more keys passed
      while (cur < count && keys[cur] < lo) ++cur;
  } else {
    while (cur < count && keys[cur] < lo) ++cur;
  }
  if (cur + 3 <= count)
    return cur + std::size_t(keys[cur] <= hi) + std::size_t(keys[cur + 1] <= hi) +
           std::size_t(keys[cur + 2] <= hi);
  std::size_t end = cur;
  while (end < count && keys[end] <= hi) ++end;
  return end;
}

}  // namespace simreel::sim::detail
