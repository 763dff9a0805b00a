#pragma once
// Private: the post pass. The resolved linear half-float frame is tone-mapped (through a table
// of every half-float value, made once), sRGB-encoded and dithered into an RGBA8 target, which
// is read back as the Image. HDR bloom (bloom_pass.hpp) is mixed in before the tone map.

#include "bloom_pass.hpp"
#include "gl/program.hpp"
#include "simreel/render/image.hpp"
#include "simreel/render/renderer.hpp"

namespace simreel::render::detail {

class PostPass {
 public:
  /// Makes the program, the RGBA8 output and the tone map table (drawn here with
  /// `empty_vao`). @throws ContextError if one cannot be made.
  void create(const GlTable& gl, const RenderSettings& settings, GLuint empty_vao);
  void destroy() noexcept;
  /// Runs the bloom chain on `hdr_texture` (when RenderSettings::bloom.intensity > 0), mixes it
  /// in and tone-maps the result (frame on unit 0, table on unit 4, bloom on unit 5) into the
  /// output.
  void draw(GLuint hdr_texture, GLuint empty_vao);
  /// The output as RGBA8, rows top to bottom.
  [[nodiscard]] Image read_back() const;

 private:
  const GlTable* gl_ = nullptr;
  int width_ = 0;
  int height_ = 0;
  Bloom bloom_;
  bool transparent_ = false;
  BloomPass bloom_pass_;
  Program program_;
  GLuint fbo_ = 0, color_ = 0;
  // The tone map for every half-float value (kToneLutFs), 256 x 256 floats.
  GLuint tone_lut_ = 0;
};

}  // namespace simreel::render::detail
