// The bloom chain (passes/bloom_pass.hpp).
#include "bloom_pass.hpp"

#include <algorithm>

#include "bloom_shaders.hpp"
#include "common_glsl.hpp"
#include "gl/targets.hpp"

namespace simreel::render::detail {

namespace {

constexpr int kMaxLevels = 6;  // 1280 x 720 -> 320 x 180 ... 10 x 6: the widest glow spans the frame
constexpr int kMinSize = 4;    // no level narrower than this

GLuint make_fbo(const GlTable& gl, GLuint texture, int w, int h) {
  GLuint fbo = 0;
  gl.GenFramebuffers(1, &fbo);
  gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
  gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture, 0);
  check_framebuffer(gl, "bloom level", w, h);
  return fbo;
}

}  // namespace

void BloomPass::create(const GlTable& gl, int width, int height) {
  gl_ = &gl;
  down_ = Program(gl, "bloom downsample", glsl_source({kFullscreenVs}), glsl_source({kBloomDownFs}));
  up_ = Program(gl, "bloom upsample", glsl_source({kFullscreenVs}), glsl_source({kBloomUpFs}));
  // The first level is a quarter of the frame's size (rounded up), the others halve it.
  int w = (width + 3) / 4, h = (height + 3) / 4;
  for (int i = 0; i < kMaxLevels; ++i) {
    if (i > 0) {
      w = (w + 1) / 2;
      h = (h + 1) / 2;
    }
    if (std::min(w, h) < kMinSize && !levels_.empty()) break;
    Level level;
    level.width = w;
    level.height = h;
    level.down = make_texture_2d(gl, w, h, GL_RGBA16F, GL_RGBA, GL_FLOAT, GL_LINEAR);
    levels_.push_back(level);  // pushed first: destroy() frees what was made if a check throws
    levels_.back().down_fbo = make_fbo(gl, level.down, w, h);
    levels_.back().up = make_texture_2d(gl, w, h, GL_RGBA16F, GL_RGBA, GL_FLOAT, GL_LINEAR);
    levels_.back().up_fbo = make_fbo(gl, levels_.back().up, w, h);
  }
}

void BloomPass::destroy() noexcept {
  if (gl_ == nullptr) return;
  for (Level& l : levels_) {
    for (GLuint* fbo : {&l.down_fbo, &l.up_fbo}) {
      if (*fbo != 0) gl_->DeleteFramebuffers(1, fbo);
    }
    for (GLuint* tex : {&l.down, &l.up}) {
      if (*tex != 0) gl_->DeleteTextures(1, tex);
    }
  }
  levels_.clear();
  down_ = Program();
  up_ = Program();
}

void BloomPass::draw(GLuint frame, float radius, GLuint empty_vao) {
  const GlTable& gl = *gl_;
  gl.Disable(GL_DEPTH_TEST);
  gl.Disable(GL_BLEND);
  gl.BindVertexArray(empty_vao);
  gl.ActiveTexture(GL_TEXTURE0);

  down_.use();
  down_.set("u_src", 0);
  GLuint src = frame;
  int src_w = 0, src_h = 0;
  for (std::size_t i = 0; i < levels_.size(); ++i) {
    const Level& l = levels_[i];
    if (i == 0) {
      src_w = 4 * l.width;  // the frame's texel (unused by the box)
      src_h = 4 * l.height;
    }
    gl.BindFramebuffer(GL_FRAMEBUFFER, l.down_fbo);
    gl.Viewport(0, 0, l.width, l.height);
    gl.BindTexture(GL_TEXTURE_2D, src);
    down_.set("u_src_texel", 1.f / float(src_w), 1.f / float(src_h));
    down_.set("u_dst_size", float(l.width), float(l.height));
    down_.set("u_box", i == 0 ? 1 : 0);
    gl.DrawArrays(GL_TRIANGLES, 0, 3);
    src = l.down;
    src_w = l.width;
    src_h = l.height;
  }

  up_.use();
  up_.set("u_coarse", 0);
  up_.set("u_down", 1);
  up_.set("u_radius", radius);
  // Every level, the first included, takes the coarser one through the tent: the post pass
  // magnifies the first four times, so it must be smooth.
  for (int i = int(levels_.size()) - 2; i >= 0; --i) {
    const Level& l = levels_[std::size_t(i)];
    const Level& coarse = levels_[std::size_t(i) + 1];
    // The coarsest level's "up" is its downsample.
    const GLuint coarse_tex = std::size_t(i) + 2 == levels_.size() ? coarse.down : coarse.up;
    gl.BindFramebuffer(GL_FRAMEBUFFER, l.up_fbo);
    gl.Viewport(0, 0, l.width, l.height);
    gl.ActiveTexture(GL_TEXTURE1);
    gl.BindTexture(GL_TEXTURE_2D, l.down);
    gl.ActiveTexture(GL_TEXTURE0);
    gl.BindTexture(GL_TEXTURE_2D, coarse_tex);
    up_.set("u_coarse_texel", 1.f / float(coarse.width), 1.f / float(coarse.height));
    up_.set("u_dst_size", float(l.width), float(l.height));
    gl.DrawArrays(GL_TRIANGLES, 0, 3);
  }
  gl.BindVertexArray(0);
}

}  // namespace simreel::render::detail
