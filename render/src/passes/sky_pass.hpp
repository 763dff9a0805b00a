#pragma once
// Private: the background. The sky gradient (or solid colour) is drawn once into a target like
// the scene's and copied into the scene target each frame: a same-format copy costs a fraction
// of shading the gradient again, and the samples are the very values the sky pass wrote (the
// settings never change).

#include "gl/program.hpp"
#include "simreel/render/renderer.hpp"

namespace simreel::render::detail {

class SkyPass {
 public:
  /// @throws ContextError if the program or the target cannot be made.
  void create(const GlTable& gl, const RenderSettings& settings, int samples);
  void destroy() noexcept;
  /// Fills `scene_fbo` (width x height, `samples` as given to create) with the sky; draws it
  /// first on the first call. Leaves the read/draw framebuffers bound to the sky and scene.
  void draw(GLuint scene_fbo, GLuint empty_vao);

 private:
  const GlTable* gl_ = nullptr;
  const RenderSettings* settings_ = nullptr;
  Program program_;
  GLuint fbo_ = 0, color_ = 0;
  bool drawn_ = false;
};

}  // namespace simreel::render::detail
