#pragma once
// Private: the scene's render target: multisampled half-float colour + depth, resolved into a
// single-sample texture that the post pass reads; and a single-sample copy of the opaque depth
// that soft particles sample (a texture cannot be sampled while it is the depth attachment
// being tested against).

#include "simreel/render/gl_table.hpp"

namespace simreel::render::detail {

class SceneTarget {
 public:
  /// Creates the targets at width x height with `samples` (0: no multisampling, the resolve
  /// texture is then drawn into directly). @throws ContextError if one is incomplete.
  void create(const GlTable& gl, int width, int height, int samples);
  void destroy() noexcept;

  /// The framebuffer the scene is drawn into.
  [[nodiscard]] GLuint draw_fbo() const { return samples_ > 0 ? msaa_fbo_ : resolve_fbo_; }
  [[nodiscard]] GLuint resolve_texture() const { return resolve_tex_; }
  [[nodiscard]] GLuint depth_copy_texture() const { return depth_tex_; }
  [[nodiscard]] int samples() const { return samples_; }

  /// Fills the depth copy from the scene (or, with nothing opaque drawn, with the cleared
  /// depth), binds the scene framebuffer again and the copy on texture unit 3.
  void copy_depth(bool opaque);
  /// Resolves the multisampled colour into the resolve texture (nothing without MSAA).
  void resolve();
  /// Resolves the colour and binds the resolve target. Blended sprites are drawn there, one
  /// sample per pixel, after copy_depth: their light falls smoothly to zero at their rims, so
  /// multisampling only multiplied their blending work by the sample count (a third of the
  /// explosion demo's frame at 4 samples). After it the frame counts as resolved.
  void resolve_for_blending();

 private:
  const GlTable* gl_ = nullptr;
  int width_ = 0;
  int height_ = 0;
  int samples_ = 0;
  GLuint msaa_fbo_ = 0, msaa_color_ = 0, msaa_depth_ = 0;
  GLuint resolve_fbo_ = 0, resolve_tex_ = 0, resolve_depth_ = 0;
  GLuint depth_fbo_ = 0, depth_tex_ = 0;
  // depth_tex_ holds the cleared depth (1) everywhere: what a copy gives when no opaque object
  // was drawn, so such frames skip the copy (a multisample depth resolve) after the first.
  bool depth_copy_clear_ = false;
};

}  // namespace simreel::render::detail
