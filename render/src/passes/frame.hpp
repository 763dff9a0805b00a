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

/// Sphere sprites uploaded by ParticlePass: the vertex array, the number of particles and the
/// vertices per particle (3: one triangle each, drawn with glDrawArrays; 4: indexed quads, the
/// index buffer bound in the vertex array; kSpriteCornerGlsl).
struct QuadBatch {
  GLuint vao = 0;
  std::size_t count = 0;
  std::size_t vertices = 3;
  /// Sets kSpriteCornerGlsl's uniform of the bound program `p` and draws the batch.
  template <class ProgramT>
  void draw(const GlTable& gl, const ProgramT& p) const {
    p.set("u_sprite_vertices", int(vertices));
    gl.BindVertexArray(vao);
    if (vertices == 4) {
      gl.DrawElements(GL_TRIANGLES, GLsizei(6 * count), GL_UNSIGNED_INT, nullptr);
    } else {
      gl.DrawArrays(GL_TRIANGLES, 0, GLsizei(vertices * count));
    }
  }
};

}  // namespace simreel::render::detail
