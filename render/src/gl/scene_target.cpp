// The scene's multisampled target, its resolve and the depth copy (gl/scene_target.hpp).
#include "scene_target.hpp"

#include <initializer_list>

#include "targets.hpp"

namespace simreel::render::detail {

void SceneTarget::create(const GlTable& gl, int width, int height, int samples) {
  gl_ = &gl;
  width_ = width;
  height_ = height;
  samples_ = samples;
  const int w = width;
  const int h = height;

  // Resolve target (also the scene target without multisampling).
  resolve_tex_ = make_texture_2d(gl, w, h, GL_RGBA16F, GL_RGBA, GL_FLOAT, GL_NEAREST);
  gl.GenFramebuffers(1, &resolve_fbo_);
  gl.BindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
  gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, resolve_tex_, 0);
  if (samples == 0) {
    gl.GenRenderbuffers(1, &resolve_depth_);
    gl.BindRenderbuffer(GL_RENDERBUFFER, resolve_depth_);
    gl.RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, resolve_depth_);
  }
  check_framebuffer(gl, "resolve", w, h);

  depth_tex_ = make_texture_2d(gl, w, h, GL_DEPTH_COMPONENT24, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT,
                               GL_NEAREST);
  gl.GenFramebuffers(1, &depth_fbo_);
  gl.BindFramebuffer(GL_FRAMEBUFFER, depth_fbo_);
  gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, depth_tex_, 0);
  gl.DrawBuffer(GL_NONE);
  gl.ReadBuffer(GL_NONE);
  check_framebuffer(gl, "scene depth copy", w, h);

  if (samples > 0) {
    gl.GenRenderbuffers(1, &msaa_color_);
    gl.BindRenderbuffer(GL_RENDERBUFFER, msaa_color_);
    gl.RenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA16F, w, h);
    gl.GenRenderbuffers(1, &msaa_depth_);
    gl.BindRenderbuffer(GL_RENDERBUFFER, msaa_depth_);
    gl.RenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, w, h);
    gl.GenFramebuffers(1, &msaa_fbo_);
    gl.BindFramebuffer(GL_FRAMEBUFFER, msaa_fbo_);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, msaa_color_);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, msaa_depth_);
    check_framebuffer(gl, "multisampled scene", w, h);
  }
}

void SceneTarget::destroy() noexcept {
  if (gl_ == nullptr) return;
  const GlTable& gl = *gl_;
  for (GLuint* fbo : {&msaa_fbo_, &resolve_fbo_, &depth_fbo_}) {
    if (*fbo != 0) gl.DeleteFramebuffers(1, fbo);
    *fbo = 0;
  }
  for (GLuint* rb : {&msaa_color_, &msaa_depth_, &resolve_depth_}) {
    if (*rb != 0) gl.DeleteRenderbuffers(1, rb);
    *rb = 0;
  }
  for (GLuint* tex : {&resolve_tex_, &depth_tex_}) {
    if (*tex != 0) gl.DeleteTextures(1, tex);
    *tex = 0;
  }
  depth_copy_clear_ = false;
}

void SceneTarget::copy_depth(bool opaque) {
  const GlTable& gl = *gl_;
  const GLuint scene_fbo = draw_fbo();
  if (opaque) {
    gl.BindFramebuffer(GL_READ_FRAMEBUFFER, scene_fbo);
    gl.BindFramebuffer(GL_DRAW_FRAMEBUFFER, depth_fbo_);
    gl.BlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_DEPTH_BUFFER_BIT, GL_NEAREST);
    depth_copy_clear_ = false;
  } else if (!depth_copy_clear_) {
    gl.BindFramebuffer(GL_FRAMEBUFFER, depth_fbo_);
    gl.DepthMask(GL_TRUE);
    gl.Clear(GL_DEPTH_BUFFER_BIT);  // the scene's clear depth, 1
    depth_copy_clear_ = true;
  }
  gl.BindFramebuffer(GL_FRAMEBUFFER, scene_fbo);
  gl.ActiveTexture(GL_TEXTURE3);
  gl.BindTexture(GL_TEXTURE_2D, depth_tex_);
}

void SceneTarget::resolve_for_blending() {
  resolve();
  gl_->BindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
}

void SceneTarget::resolve() {
  if (samples_ == 0) return;
  const GlTable& gl = *gl_;
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, msaa_fbo_);
  gl.BindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_fbo_);
  gl.BlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

}  // namespace simreel::render::detail
