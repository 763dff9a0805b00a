#pragma once
/// @file handle.hpp
/// Generational, typed object handles (Coutinho §1.4.1: the engine names every object it
/// simulates by a handle; the renderer maps handles to its own drawables).

#include <cstdint>
#include <functional>

namespace simreel::sim {

/// What kind of object a handle names. Zero is never a valid kind. A collider of the scene format
/// is a static or kinematic body: `collider` and `body` are the same kind.
enum class ObjectKind : std::uint8_t {
  none = 0,
  body = 1,
  collider = body,
  particle_system = 2,
  cloth = 3,
  force_field = 4,
  attractor_spring = 5,
  joint = 6,
  body_spring = 7,
};

/// A small value naming one registered object: slot index + generation (Box2D v3's id pool). The
/// index names a slot of the world's table of that kind; the slot points into dense arrays that
/// are compacted by swap-remove, so a handle stays valid while others are removed. A
/// default-constructed handle is null (generation 0). Removing an object bumps its slot's
/// generation, so its handle is stale at once and stays stale when the slot is reused; World
/// rejects stale and null handles with std::out_of_range. Handles of a world without removals
/// are {registration index of that kind, generation 1}.
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

using BodyHandle = TypedHandle<ObjectKind::body>;
/// A collider is a static or kinematic body with one shape: the same handle type.
using ColliderHandle = BodyHandle;
using ParticleSystemHandle = TypedHandle<ObjectKind::particle_system>;
using ClothHandle = TypedHandle<ObjectKind::cloth>;
using ForceFieldHandle = TypedHandle<ObjectKind::force_field>;
using AttractorSpringHandle = TypedHandle<ObjectKind::attractor_spring>;
using JointHandle = TypedHandle<ObjectKind::joint>;
using BodySpringHandle = TypedHandle<ObjectKind::body_spring>;

}  // namespace simreel::sim
