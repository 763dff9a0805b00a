#pragma once
/// @file handle.hpp
/// Generational, typed object handles (Coutinho §1.4.1: the engine names every object it
/// simulates by a handle; the renderer maps handles to its own drawables).

#include <cstdint>
#include <functional>

namespace simreel::sim {

/// What kind of object a handle names. Zero is never a valid kind.
enum class ObjectKind : std::uint8_t { none = 0, collider = 1, particle_system = 2, cloth = 3 };

/// A small value naming one registered object: slot index + generation. A default-constructed
/// handle is null (generation 0). Stale handles (the slot was reused) are rejected by World.
struct Handle {
  std::uint32_t index = 0;       ///< slot index in the world's table of that kind
  std::uint16_t generation = 0;  ///< incremented each time the slot is reused; 0 = null
  ObjectKind kind = ObjectKind::none;

  [[nodiscard]] constexpr bool is_null() const { return generation == 0; }
  /// Packs the handle into one 64-bit key (kind << 48 | generation << 32 | index): what the
  /// program hands to the renderer, which never sees engine types.
  [[nodiscard]] constexpr std::uint64_t packed() const {
    return (std::uint64_t(kind) << 48) | (std::uint64_t(generation) << 32) | index;
  }
  friend constexpr bool operator==(const Handle&, const Handle&) = default;
};

/// Typed wrapper so a collider handle cannot be passed where a particle-system handle is expected.
template <ObjectKind K>
struct TypedHandle {
  Handle id;
  [[nodiscard]] constexpr bool is_null() const { return id.is_null(); }
  friend constexpr bool operator==(const TypedHandle&, const TypedHandle&) = default;
};

using ColliderHandle = TypedHandle<ObjectKind::collider>;
using ParticleSystemHandle = TypedHandle<ObjectKind::particle_system>;
using ClothHandle = TypedHandle<ObjectKind::cloth>;

}  // namespace simreel::sim
