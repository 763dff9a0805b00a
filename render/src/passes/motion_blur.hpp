#pragma once
// Private: the camera shutter (RenderSettings::shutter_deg). The renderer draws the opaque
// scene (sky, meshes) at shutter_samples instants spread evenly over the open shutter and
// adds each resolved sub-frame, weighted 1 / samples, into a float accumulation target; the
// average replaces the scene's colour before the particles are drawn. Everything runs in a fixed
// order on fixed data: the same bytes every run.

#include "gl/program.hpp"

namespace simreel::render::detail {

class MotionBlur {
 public:
  /// Makes the accumulation target (RGBA32F) and the copy program.
  /// @throws ContextError if the framebuffer is incomplete.
  void create(const GlTable& gl, int width, int height);
  void destroy() noexcept;
  /// Clears the accumulation.
  void begin();
  /// Adds `weight` x `resolved` (a width x height texture) into the accumulation.
  void add(GLuint resolved, float weight, GLuint empty_vao);
  /// Writes the accumulation into the colour of `scene_fbo` (every sample), leaving its depth
  /// as the last sub-frame drew it; binds `scene_fbo` again.
  void end(GLuint scene_fbo, GLuint empty_vao);

 private:
  const GlTable* gl_ = nullptr;
  int width_ = 0, height_ = 0;
  Program copy_;
  GLuint accum_ = 0, accum_fbo_ = 0;
};

}  // namespace simreel::render::detail
