#pragma once
// Private: the renderer's own table `key -> drawable` (renderer.hpp), read by the passes.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>

#include "gl/buffers.hpp"
#include "simreel/render/mesh.hpp"
#include "simreel/render/renderer.hpp"

namespace simreel::render::detail {

// Particle instances as the particle shaders read them.
// The texture parameter packs a textured particle's age / lifetime (integer part, 0..1023) and
// its own random number (fraction, in 1/4096); -1 marks an untextured particle.
inline constexpr std::size_t kInstanceFloats = 9;   // centre xyz, radius, colour rgba, texture parameter
inline constexpr std::size_t kStreakFloats = 12;    // centre xyz, radius, colour rgba, head-to-tail offset xyz, texture parameter

enum class DrawableKind { plane, box, mesh, particles };

struct Drawable {
  DrawableKind kind = DrawableKind::box;
  Vec3f translation = Vec3f::Zero();
  Mat3f rotation = Mat3f::Identity();
  // The transform the last rendered frame showed (motion blur interpolates from it).
  Vec3f shown_translation = Vec3f::Zero();
  Mat3f shown_rotation = Mat3f::Identity();
  bool shown = false;
  Vec4f color = Vec4f::Ones();
  Vec3f half_extents = Vec3f::Ones();  // box
  PlaneDesc plane;                     // plane
  GpuMesh mesh;                        // plane and mesh (boxes share the unit cube)
  // Mesh: its parts (one when the MeshDesc had none), vertex data kept for update_mesh, local
  // bounds for the shadow fit.
  struct Part {
    GLsizei first_index = 0;
    GLsizei index_count = 0;
    Material material;  // texture_rgba dropped once uploaded
    GLuint texture = 0;
  };
  std::vector<Part> parts;
  std::vector<Vertex> vertices;  // CPU copy for update_mesh (keeps the UVs)
  std::vector<std::uint32_t> indices;
  Eigen::AlignedBox3f local_bounds;
  bool dynamic = false;
  std::vector<float> instances;  // particles, kInstanceFloats (kStreakFloats for streaks) each
  ParticleStyle style = ParticleStyle::soft;
  ParticleTexture particle_texture = ParticleTexture::none;
  bool trail = false;  // additive streaks (kStreakFloats per particle)
};

struct DrawableTable {
  std::unordered_map<ObjectKey, Drawable> by_key;
  // Keys in increasing order, so drawing (and merging particle batches) is deterministic.
  std::vector<ObjectKey> order;

  /// A new drawable of `kind`. @throws std::invalid_argument if the key is used.
  Drawable& add(ObjectKey key, DrawableKind kind) {
    auto [it, inserted] = by_key.try_emplace(key);
    if (!inserted) {
      throw std::invalid_argument("renderer: key " + std::to_string(key) + " is already used");
    }
    it->second.kind = kind;
    order.insert(std::lower_bound(order.begin(), order.end(), key), key);
    return it->second;
  }

  /// Calls f(drawable) for every drawable in key order.
  template <class F>
  void for_each(F&& f) const {
    for (const ObjectKey key : order) f(by_key.at(key));
  }
};

}  // namespace simreel::render::detail
