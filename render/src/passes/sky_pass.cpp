// The sky pass (passes/sky_pass.hpp).
#include "sky_pass.hpp"

#include "common_glsl.hpp"
#include "gl/targets.hpp"
#include "sky_shaders.hpp"

namespace simreel::render::detail {

void SkyPass::create(const GlTable& gl, const RenderSettings& settings, int samples) {
  gl_ = &gl;
  settings_ = &settings;
  program_ = Program(gl, "sky", glsl_source({kFullscreenVs}), glsl_source({kSkyGlsl, kSkyFs}));
  const int w = settings.width;
  const int h = settings.height;
  gl.GenRenderbuffers(1, &color_);
  gl.BindRenderbuffer(GL_RENDERBUFFER, color_);
  if (samples > 0) {
    gl.RenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA16F, w, h);
  } else {
    gl.RenderbufferStorage(GL_RENDERBUFFER, GL_RGBA16F, w, h);
  }
  gl.GenFramebuffers(1, &fbo_);
  gl.BindFramebuffer(GL_FRAMEBUFFER, fbo_);
  gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_);
  check_framebuffer(gl, "sky", w, h);
}

void SkyPass::destroy() noexcept {
  if (gl_ == nullptr) return;
  if (fbo_ != 0) gl_->DeleteFramebuffers(1, &fbo_);
  if (color_ != 0) gl_->DeleteRenderbuffers(1, &color_);
  fbo_ = color_ = 0;
  drawn_ = false;
  program_ = Program();
}

void SkyPass::draw(GLuint scene_fbo, GLuint empty_vao) {
  const GlTable& gl = *gl_;
  const RenderSettings& settings = *settings_;
  const int w = settings.width;
  const int h = settings.height;
  if (!drawn_) {
    gl.BindFramebuffer(GL_FRAMEBUFFER, fbo_);
    gl.Disable(GL_DEPTH_TEST);
    const bool solid = settings.background == Background::solid;
    program_.use();
    program_.set("u_sky_top", solid ? settings.background_color : settings.sky_top);
    program_.set("u_sky_bottom", solid ? settings.background_color : settings.sky_bottom);
    program_.set("u_viewport", float(w), float(h));
    gl.BindVertexArray(empty_vao);
    gl.DrawArrays(GL_TRIANGLES, 0, 3);
    drawn_ = true;
  }
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  gl.BindFramebuffer(GL_DRAW_FRAMEBUFFER, scene_fbo);
  gl.BlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

}  // namespace simreel::render::detail
