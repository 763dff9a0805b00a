#pragma once
// Id pool (private): hands out slot indices with a generation, recycles freed slots from a free
// list (last freed, first reused) and bumps the generation on every free, so a handle to a freed
// slot is stale at once and stays stale after the slot is reused (after Box2D v3's id_pool.h).
// Generation 0 is never handed out: it marks the null handle.

#include <cstdint>
#include <vector>

namespace simreel::sim::detail {

class IdPool {
 public:
  struct Id {
    std::uint32_t index = 0;
    std::uint16_t generation = 0;
  };

  /// A free slot (the last freed one first) or a new one; a new slot has generation 1.
  Id alloc() {
    if (!free_.empty()) {
      const std::uint32_t i = free_.back();
      free_.pop_back();
      live_[i] = 1;
      return {i, generation_[i]};
    }
    generation_.push_back(1);
    live_.push_back(1);
    return {std::uint32_t(generation_.size() - 1), 1};
  }

  /// Frees a live slot and bumps its generation (wrapping past 0, which is null).
  void free(std::uint32_t index) {
    live_[index] = 0;
    std::uint16_t& g = generation_[index];
    g = std::uint16_t(g + 1);
    if (g == 0) g = 1;
    free_.push_back(index);
  }

  /// A live slot with this generation (false for null, stale and out-of-range ids).
  [[nodiscard]] bool valid(std::uint32_t index, std::uint16_t generation) const {
    return generation != 0 && index < generation_.size() && live_[index] != 0 &&
           generation_[index] == generation;
  }

  /// Current generation of a slot (that of its live object, or the next one's when free).
  [[nodiscard]] std::uint16_t generation(std::uint32_t index) const { return generation_[index]; }

  [[nodiscard]] std::size_t slot_count() const { return generation_.size(); }

 private:
  std::vector<std::uint16_t> generation_;  ///< per slot: generation of the current/next object
  std::vector<std::uint8_t> live_;         ///< per slot: 1 while an object holds it
  std::vector<std::uint32_t> free_;        ///< freed slots, reused last-in first-out
};

}  // namespace simreel::sim::detail
