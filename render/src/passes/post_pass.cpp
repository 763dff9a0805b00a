// The post pass (passes/post_pass.hpp).
#include "post_pass.hpp"

#include <string>

#include "common_glsl.hpp"
#include "gl/targets.hpp"
#include "post_shaders.hpp"
#include "simreel/render/context.hpp"

namespace simreel::render::detail {

void PostPass::create(const GlTable& gl, const RenderSettings& settings, GLuint empty_vao) {
  gl_ = &gl;
  width_ = settings.width;
  height_ = settings.height;
  bloom_ = settings.bloom;
  transparent_ = settings.background == Background::transparent;
  if (bloom_.intensity > 0.f) bloom_pass_.create(gl, width_, height_);
  program_ = Program(gl, "tone map", glsl_source({kFullscreenVs}),
                     glsl_source({kPackingExtension, kPostFs}));

  gl.GenRenderbuffers(1, &color_);
  gl.BindRenderbuffer(GL_RENDERBUFFER, color_);
  gl.RenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width_, height_);
  gl.GenFramebuffers(1, &fbo_);
  gl.BindFramebuffer(GL_FRAMEBUFFER, fbo_);
  gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_);
  check_framebuffer(gl, "RGBA8 output", width_, height_);

  gl.GenTextures(1, &tone_lut_);
  gl.BindTexture(GL_TEXTURE_2D, tone_lut_);
  gl.TexImage2D(GL_TEXTURE_2D, 0, GL_R32F, 256, 256, 0, GL_RED, GL_FLOAT, nullptr);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  GLuint lut_fbo = 0;
  gl.GenFramebuffers(1, &lut_fbo);
  gl.BindFramebuffer(GL_FRAMEBUFFER, lut_fbo);
  gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tone_lut_, 0);
  const GLenum status = gl.CheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status == GL_FRAMEBUFFER_COMPLETE) {
    const Program lut(gl, "tone map table", glsl_source({kFullscreenVs}),
                      glsl_source({kPackingExtension, kToneMapGlsl, kToneLutFs}));
    lut.use();
    gl.Viewport(0, 0, 256, 256);
    gl.Disable(GL_DEPTH_TEST);
    gl.Disable(GL_BLEND);
    gl.BindVertexArray(empty_vao);
    gl.DrawArrays(GL_TRIANGLES, 0, 3);
    gl.BindVertexArray(0);
  }
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
  gl.DeleteFramebuffers(1, &lut_fbo);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    throw ContextError(std::string("renderer: the tone map table framebuffer is incomplete: ") +
                       framebuffer_status_name(status));
  }
}

void PostPass::destroy() noexcept {
  if (gl_ == nullptr) return;
  if (fbo_ != 0) gl_->DeleteFramebuffers(1, &fbo_);
  if (color_ != 0) gl_->DeleteRenderbuffers(1, &color_);
  if (tone_lut_ != 0) gl_->DeleteTextures(1, &tone_lut_);
  bloom_pass_.destroy();
  fbo_ = color_ = tone_lut_ = 0;
  program_ = Program();
}

void PostPass::draw(GLuint hdr_texture, GLuint empty_vao) {
  const GlTable& gl = *gl_;
  const bool bloom = bloom_.intensity > 0.f;
  if (bloom) bloom_pass_.draw(hdr_texture, bloom_.radius, empty_vao);
  gl.BindFramebuffer(GL_FRAMEBUFFER, fbo_);
  gl.Viewport(0, 0, width_, height_);
  gl.Disable(GL_DEPTH_TEST);
  gl.Disable(GL_BLEND);
  program_.use();
  program_.set("u_hdr", 0);
  program_.set("u_tone_lut", 4);
  program_.set("u_bloom", 5);
  program_.set("u_bloom_intensity", bloom ? bloom_.intensity : 0.f);
  program_.set("u_size", float(width_), float(height_));
  program_.set("u_transparent", transparent_ ? 1 : 0);
  gl.ActiveTexture(GL_TEXTURE5);
  gl.BindTexture(GL_TEXTURE_2D, bloom ? bloom_pass_.result() : 0);
  gl.ActiveTexture(GL_TEXTURE4);
  gl.BindTexture(GL_TEXTURE_2D, tone_lut_);
  gl.ActiveTexture(GL_TEXTURE0);
  gl.BindTexture(GL_TEXTURE_2D, hdr_texture);
  gl.BindVertexArray(empty_vao);
  gl.DrawArrays(GL_TRIANGLES, 0, 3);
  gl.BindVertexArray(0);
}

Image PostPass::read_back() const {
  const GlTable& gl = *gl_;
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  gl.ReadBuffer(GL_COLOR_ATTACHMENT0);
  gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  // The tone map pass wrote the rows upside down, so GL's bottom-to-top rows are the Image's
  // top-to-bottom ones: read straight into the image, no flip copy.
  Image image(width_, height_);
  gl.ReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, image.rgba.data());
  return image;
}

}  // namespace simreel::render::detail
