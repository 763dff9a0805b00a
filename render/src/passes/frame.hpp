#pragma once
// Private: what every pass of one frame reads: settings, camera, light and their matrices, and
// the sun's shadow map as the shadow pass fitted it.

#include <cstddef>

#include <Eigen/Core>

#include "simreel/render/gl_table.hpp"
#include "simreel/render/renderer.hpp"

namespace simreel::render::detail {

struct FrameView {
  const RenderSettings& settings;
  const Camera& camera;
  const Light& light;
  Eigen::Matrix4f view = Eigen::Matrix4f::Identity();  ///< world -> view
  Eigen::Matrix4f proj = Eigen::Matrix4f::Identity();  ///< view -> clip
};

/// The shadow map's fit for this frame (ShadowPass::draw); the lit passes upload it.
struct ShadowView {
  bool enabled = false;  ///< false: nothing casts, no lookups
  Eigen::Matrix4f light_view_proj = Eigen::Matrix4f::Identity();
  Eigen::Vector3f light_right = Eigen::Vector3f::UnitX();  ///< sun view axes, world frame
  Eigen::Vector3f light_up = Eigen::Vector3f::UnitY();
  float bias = 0.f;    ///< light-depth units
  float offset = 0.f;  ///< (m) normal offset against acne
  float radius = 0.f;  ///< shadow-map uv units, penumbra width
  GLuint texture = 0;  ///< the depth map (compare mode), bound on unit 1 by the renderer
};

/// Vertices per sphere sprite: one triangle around the unit disc (kSpriteCornerGlsl).
inline constexpr std::size_t kSpriteVertices = 3;

/// Sphere sprites uploaded as one triangle each (kSpriteVertices vertices, ParticlePass), drawn
/// with glDrawArrays: the vertex array and the number of particles.
struct QuadBatch {
  GLuint vao = 0;
  std::size_t count = 0;
};

}  // namespace simreel::render::detail
