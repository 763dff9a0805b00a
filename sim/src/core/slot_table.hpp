#pragma once
// Slot table (private): handle -> slot -> dense array with swap-remove (after Box2D v3's
// id_pool.h + body arrays). Inner loops run over the dense array; removing an element moves the
// last one into its place, so dense indices of other elements may change but handles stay valid.
// Each element also gets a registration serial: how many elements of the table were ever added
// before it (its dense index in a world without removals), the key of its random streams.

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/id_pool.hpp"
#include "simreel/sim/handle.hpp"

namespace simreel::sim::detail {

template <class T>
class SlotTable {
 public:
  explicit SlotTable(ObjectKind kind, const char* what) : kind_(kind), what_(what) {}

  /// What remove() did to the dense array: the element at `removed` was dropped and the one at
  /// `moved_from` (the old last index) now sits there; moved_from == removed when it was last.
  struct Removal {
    std::size_t removed = 0;
    std::size_t moved_from = 0;
  };

  /// The registration serial the next added element gets.
  [[nodiscard]] std::uint64_t next_serial() const { return serial_; }

  Handle add(T value) {
    const IdPool::Id id = pool_.alloc();
    if (slot_dense_.size() < pool_.slot_count()) slot_dense_.resize(pool_.slot_count());
    slot_dense_[id.index] = std::uint32_t(dense_.size());
    dense_.push_back(std::move(value));
    dense_slot_.push_back(id.index);
    dense_serial_.push_back(serial_++);
    return Handle{id.index, id.generation, kind_};
  }

  /// Dense index of a live handle of this table's kind.
  /// @throws std::out_of_range on a null, stale or foreign handle.
  [[nodiscard]] std::size_t index(const Handle& h) const {
    if (h.kind != kind_ || !pool_.valid(h.index, h.generation))
      throw std::out_of_range(std::string("simreel::sim::World: stale or invalid ") + what_ +
                              " handle");
    return slot_dense_[h.index];
  }
  [[nodiscard]] bool contains(const Handle& h) const {
    return h.kind == kind_ && pool_.valid(h.index, h.generation);
  }
  T& operator[](const Handle& h) { return dense_[index(h)]; }
  const T& operator[](const Handle& h) const { return dense_[index(h)]; }

  /// Swap-removes the element. @throws std::out_of_range like index().
  Removal remove(const Handle& h) {
    const std::size_t i = index(h);
    const std::size_t last = dense_.size() - 1;
    if (i != last) {
      dense_[i] = std::move(dense_[last]);
      dense_slot_[i] = dense_slot_[last];
      dense_serial_[i] = dense_serial_[last];
      slot_dense_[dense_slot_[i]] = std::uint32_t(i);
    }
    dense_.pop_back();
    dense_slot_.pop_back();
    dense_serial_.pop_back();
    pool_.free(h.index);
    return {i, last};
  }

  /// Handle of the element at dense index i.
  [[nodiscard]] Handle handle(std::size_t i) const {
    const std::uint32_t slot = dense_slot_[i];
    return Handle{slot, pool_.generation(slot), kind_};
  }
  [[nodiscard]] std::uint64_t serial(std::size_t i) const { return dense_serial_[i]; }

  [[nodiscard]] std::vector<T>& dense() { return dense_; }
  [[nodiscard]] const std::vector<T>& dense() const { return dense_; }
  [[nodiscard]] std::size_t size() const { return dense_.size(); }
  [[nodiscard]] bool empty() const { return dense_.empty(); }
  T& at(std::size_t i) { return dense_[i]; }
  const T& at(std::size_t i) const { return dense_[i]; }

 private:
  ObjectKind kind_;
  const char* what_;
  IdPool pool_;
  std::vector<std::uint32_t> slot_dense_;     ///< per slot: dense index (live slots only)
  std::vector<T> dense_;
  std::vector<std::uint32_t> dense_slot_;     ///< per dense element: its slot
  std::vector<std::uint64_t> dense_serial_;   ///< per dense element: its registration serial
  std::uint64_t serial_ = 0;
};

}  // namespace simreel::sim::detail
