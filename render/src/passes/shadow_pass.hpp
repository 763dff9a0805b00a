#pragma once
// Private: the sun's shadow map. An orthographic sun view is fitted around every caster each
// frame (boxes, meshes and, with RenderSettings::particle_shadows, soft and droplet particles),
// and the casters' depth drawn into a 2048^2 map that the lit passes look up.

#include "drawables.hpp"
#include "frame.hpp"
#include "gl/program.hpp"

namespace simreel::render::detail {

inline constexpr int kShadowMapSize = 2048;  // texels per side

class ShadowPass {
 public:
  /// @throws ContextError if a program or the map cannot be made.
  void create(const GlTable& gl, const RenderSettings& settings);
  void destroy() noexcept;
  /// Fits the sun view and draws the casters; returns the fit (enabled false when nothing
  /// casts, then nothing is drawn). `cube` is the unit cube boxes are drawn with; `soft` and
  /// `droplets` the uploaded particle quads.
  const ShadowView& draw(const FrameView& frame, const DrawableTable& table, const GpuMesh& cube,
                  QuadBatch soft, QuadBatch droplets);

 private:
  const GlTable* gl_ = nullptr;
  Program depth_program_, particle_depth_program_;
  GLuint fbo_ = 0, texture_ = 0;
  ShadowView view_;
};

}  // namespace simreel::render::detail
