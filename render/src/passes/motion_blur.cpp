// The shutter's accumulation (passes/motion_blur.hpp).
#include "motion_blur.hpp"

#include "common_glsl.hpp"
#include "gl/targets.hpp"

namespace simreel::render::detail {

namespace {

inline constexpr char kScaledCopyFs[] = R"(
uniform sampler2D u_src;
uniform float u_weight;
out vec4 o_color;
void main() { o_color = u_weight * texelFetch(u_src, ivec2(gl_FragCoord.xy), 0); }
)";

}  // namespace

void MotionBlur::create(const GlTable& gl, int width, int height) {
  gl_ = &gl;
  width_ = width;
  height_ = height;
  copy_ = Program(gl, "shutter accumulation", glsl_source({kFullscreenVs}), glsl_source({kScaledCopyFs}));
  accum_ = make_texture_2d(gl, width, height, GL_RGBA32F, GL_RGBA, GL_FLOAT, GL_NEAREST);
  gl.GenFramebuffers(1, &accum_fbo_);
  gl.BindFramebuffer(GL_FRAMEBUFFER, accum_fbo_);
  gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, accum_, 0);
  check_framebuffer(gl, "shutter accumulation", width, height);
}

void MotionBlur::destroy() noexcept {
  if (gl_ == nullptr) return;
  if (accum_fbo_ != 0) gl_->DeleteFramebuffers(1, &accum_fbo_);
  if (accum_ != 0) gl_->DeleteTextures(1, &accum_);
  accum_fbo_ = accum_ = 0;
  copy_ = Program();
}

void MotionBlur::begin() {
  const GlTable& gl = *gl_;
  gl.BindFramebuffer(GL_FRAMEBUFFER, accum_fbo_);
  gl.ClearColor(0.f, 0.f, 0.f, 0.f);
  gl.Clear(GL_COLOR_BUFFER_BIT);
}

void MotionBlur::add(GLuint resolved, float weight, GLuint empty_vao) {
  const GlTable& gl = *gl_;
  gl.BindFramebuffer(GL_FRAMEBUFFER, accum_fbo_);
  gl.Viewport(0, 0, width_, height_);
  gl.Disable(GL_DEPTH_TEST);
  gl.Enable(GL_BLEND);
  gl.BlendFunc(GL_ONE, GL_ONE);
  copy_.use();
  copy_.set("u_src", 0);
  copy_.set("u_weight", weight);
  gl.ActiveTexture(GL_TEXTURE0);
  gl.BindTexture(GL_TEXTURE_2D, resolved);
  gl.BindVertexArray(empty_vao);
  gl.DrawArrays(GL_TRIANGLES, 0, 3);
  gl.BindVertexArray(0);
  gl.Disable(GL_BLEND);
}

void MotionBlur::end(GLuint scene_fbo, GLuint empty_vao) {
  const GlTable& gl = *gl_;
  gl.BindFramebuffer(GL_FRAMEBUFFER, scene_fbo);
  gl.Viewport(0, 0, width_, height_);
  gl.Disable(GL_DEPTH_TEST);
  gl.Disable(GL_BLEND);
  gl.DepthMask(GL_FALSE);
  copy_.use();
  copy_.set("u_src", 0);
  copy_.set("u_weight", 1.f);
  gl.ActiveTexture(GL_TEXTURE0);
  gl.BindTexture(GL_TEXTURE_2D, accum_);
  gl.BindVertexArray(empty_vao);
  gl.DrawArrays(GL_TRIANGLES, 0, 3);
  gl.BindVertexArray(0);
  gl.DepthMask(GL_TRUE);
}

}  // namespace simreel::render::detail
