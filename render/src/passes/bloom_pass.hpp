#pragma once
// Private: the HDR bloom chain (RenderSettings::Bloom). The linear frame is downsampled into
// levels 1..N, a 4 x 4 box into level 1 (a quarter of the frame's size), then halving with the
// 13-tap filter of Jimenez, "Next generation post processing in Call of Duty: Advanced
// Warfare", SIGGRAPH 2014), then added back up with a 3 x 3 tent: up_N = down_N,
// up_i = (1 - radius) down_i + radius tent(up_{i+1}). Every filter's weights sum to 1 and every
// level shrinks both sizes alike, so each level keeps the frame's mean: up_1 (quarter size)
// holds the frame's light blurred, and the post pass mixes it in (bilinear),
// (1 - intensity) frame + intensity up_1, which keeps the image's sum (energy) and needs no
// threshold.

#include <vector>

#include "gl/program.hpp"

namespace simreel::render::detail {

class BloomPass {
 public:
  /// Makes the programs and the level textures for a width x height frame.
  /// @throws ContextError if a framebuffer is incomplete.
  void create(const GlTable& gl, int width, int height);
  void destroy() noexcept;
  /// Runs the chain on `frame` (a width x height RGBA16F texture, read with texelFetch only).
  /// Leaves the viewport at the last level's size.
  void draw(GLuint frame, float radius, GLuint empty_vao);
  /// up_1 after draw(): RGBA16F, a quarter of the frame's size (rounded up), linear filtering.
  [[nodiscard]] GLuint result() const {
    return levels_.empty() ? 0 : levels_.size() == 1 ? levels_[0].down : levels_[0].up;
  }
  [[nodiscard]] int result_width() const { return levels_.empty() ? 0 : levels_[0].width; }
  [[nodiscard]] int result_height() const { return levels_.empty() ? 0 : levels_[0].height; }
  [[nodiscard]] int level_count() const { return int(levels_.size()); }

 private:
  struct Level {
    int width = 0, height = 0;
    GLuint down = 0, down_fbo = 0;  // the downsampled frame
    GLuint up = 0, up_fbo = 0;      // the chain added back up to this level (not the last)
  };
  const GlTable* gl_ = nullptr;
  Program down_, up_;
  std::vector<Level> levels_;
};

}  // namespace simreel::render::detail
