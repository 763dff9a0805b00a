// A std::vector whose resize() leaves new elements default-initialised (for the trivial types
// it is meant for: not written), for working arrays whose every element a pass writes before
// any is read. A value-initialising resize() zero-fills in one serial memset, which on a first
// step also takes every page's first-touch fault on one thread; left to the pass that fills
// the array, the faults fall where it runs (split over the threads for a large system).
#pragma once

#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

namespace simreel::sim::detail {

/// std::allocator<T> whose construct() with no arguments default-initialises (`new (p) U`, no
/// zeroing); with arguments it constructs as usual.
template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  using std::allocator<T>::allocator;
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    std::allocator_traits<std::allocator<T>>::construct(static_cast<std::allocator<T>&>(*this), p,
                                                        std::forward<Args>(args)...);
  }
};

/// A vector of trivially default-constructible T whose resize() writes nothing to new elements.
template <class T>
  requires std::is_trivially_default_constructible_v<T>
using RawVector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace simreel::sim::detail
