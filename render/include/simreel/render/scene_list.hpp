#pragma once
/// @file scene_list.hpp
/// What the renderer is told about one frame, as plain data with no GL in it (MuJoCo's mjvScene,
/// Box2D's moved-body events): drawables added, moved and removed by key, the particle batches
/// and the deformable meshes' new vertices. The program (demos/ ScenePlayer) fills it from the
/// engine's output for a frame; Renderer::apply() consumes it. The glue can thus be tested
/// without a GL context. Keys are opaque (the program passes sim::Handle::packed()).
/// Coutinho §1.4.1: the simulation engine hands the rendering engine {handle, transform} pairs.

#include <cstdint>
#include <optional>
#include <span>
#include <variant>
#include <vector>

#include "simreel/render/mesh.hpp"
#include "simreel/render/renderer.hpp"

namespace simreel::render {

struct SceneList {
  /// A new drawable, placed at `translation`/`rotation` (x_world = R x_local + t). A plane's
  /// PlaneDesc is already in the world frame and keeps the identity transform.
  struct Added {
    ObjectKey key = 0;
    std::variant<PlaneDesc, BoxDesc, MeshDesc> desc;
    Vec3f translation = Vec3f::Zero();
    Mat3f rotation = Mat3f::Identity();
    bool has_transform = true;  ///< false for planes (no set_transform call)
  };
  /// A drawable whose pose changed since the last list.
  struct Moved {
    ObjectKey key = 0;
    Vec3f translation = Vec3f::Zero();  ///< (m) world frame
    Mat3f rotation = Mat3f::Identity();  ///< local-to-world
  };
  /// A particle batch (the pointers view engine memory: valid until the engine advances).
  struct Particles {
    ObjectKey key = 0;
    ParticleBatch batch;
  };
  /// New vertex positions (n x 3, m) and normals (n x 3) of a dynamic mesh (cloth); views.
  struct MeshVertices {
    ObjectKey key = 0;
    std::span<const float> positions;
    std::span<const float> normals;
  };

  std::vector<Added> added;            ///< applied first, in order
  std::vector<Moved> moved;            ///< then poses, in order
  std::vector<ObjectKey> removed;      ///< then removals (the drawable is dropped)
  std::vector<Particles> particles;    ///< then particle batches, in order
  std::vector<MeshVertices> meshes;    ///< then mesh vertices, in order
  std::optional<Camera> camera;        ///< set when the camera moves

  /// Empties every list (keeps capacity) so one SceneList serves a whole run without allocating.
  void clear() {
    added.clear();
    moved.clear();
    removed.clear();
    particles.clear();
    meshes.clear();
    camera.reset();
  }
};

}  // namespace simreel::render
