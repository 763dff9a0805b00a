#pragma once
// Private: the background: the sky along each pixel's view direction (horizon to zenith
// gradient, haze and disk of the sun) and, below the horizon, the far ground continuing the
// ground plane (the first horizontal plane drawable) into aerial perspective, so there is no
// edge where the drawn ground square ends. Drawn into a target like the scene's when the
// camera, light or ground change, and copied into the scene target each frame (a same-format
// copy costs a fraction of shading it again).

#include "drawables.hpp"
#include "gl/program.hpp"
#include "passes/frame.hpp"
#include "simreel/render/renderer.hpp"

namespace simreel::render::detail {

/// The ground plane: the first plane drawable (key order) whose world normal is within ~2.5
/// degrees of +z; null if none.
const Drawable* find_ground(const DrawableTable& table);

/// Fog distance (m) of the mesh pass and the far ground: it scales with how far the camera
/// stands from what it looks at, so it reads the same in a tabletop scene and a field.
float fog_distance(const Camera& camera);

/// The sky's uniforms (kSkyGlsl) on `p`, for the frame's settings and light.
void set_sky_uniforms(const Program& p, const RenderSettings& settings, const Light& light);

class SkyPass {
 public:
  /// @throws ContextError if the program or the target cannot be made.
  void create(const GlTable& gl, const RenderSettings& settings, int samples);
  void destroy() noexcept;
  /// Fills `scene_fbo` (width x height, `samples` as given to create) with the sky; shades it
  /// again when the view, light or ground differ from the last call. Leaves the read/draw
  /// framebuffers bound to the sky and scene.
  void draw(const FrameView& frame, const DrawableTable& table, GLuint scene_fbo, GLuint empty_vao);

 private:
  const GlTable* gl_ = nullptr;
  const RenderSettings* settings_ = nullptr;
  Program program_;
  GLuint fbo_ = 0, color_ = 0;
  bool drawn_ = false;
  std::vector<float> last_;  // the inputs the target was shaded with
};

}  // namespace simreel::render::detail
