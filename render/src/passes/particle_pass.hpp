#pragma once
// Private: the particle passes. Every batch's particles are merged by style into one stream
// each (soft ones sorted back to front across batches, so overlapping batches blend correctly)
// and drawn as one triangle per sphere sprite (indexed quads for streaks): droplets with the opaque geometry, then soft, streak and additive
// sprites (dots and trails) blended over it, faded against a copy of the opaque depth. Smoke and
// flame textures read one seeded, tileable noise texture made in create().

#include <cstddef>
#include <cstdint>
#include <vector>

#include "drawables.hpp"
#include "frame.hpp"
#include "gl/program.hpp"
#include "gl/scene_target.hpp"
#include "particle_sort.hpp"

namespace simreel::render::detail {

class ParticlePass {
 public:
  /// Creates the streaks' quad index buffer and one vertex array per stream.
  void create(const GlTable& gl);
  void destroy() noexcept;

  /// Merges the particle drawables of `table` by style (in key order), sorts the soft ones back
  /// to front as seen from `camera` and uploads all five streams (`height_px`: the frame's
  /// height, for the sprites' size on screen).
  void gather(const DrawableTable& table, const Camera& camera, int height_px);
  /// The uploaded soft and droplet particles (the shadow pass draws them as casters).
  [[nodiscard]] QuadBatch soft() const { return batch(soft_); }
  [[nodiscard]] QuadBatch droplets() const { return batch(droplets_); }

  /// Draws the droplets (opaque lit spheres) into the bound scene framebuffer; `samples` > 0
  /// turns on alpha-to-coverage.
  void draw_droplets(const FrameView& frame, const ShadowView& shadow, int samples);
  /// Draws the blended particles: copies the scene depth (`opaque_drawables`: a plane, box or
  /// mesh was drawn), resolves the multisampled target (SceneTarget::resolve_for_blending) and
  /// draws rain streaks, soft, trail and additive sprites into the resolved target, their depth
  /// test in their shaders against the copy. @return false when there was nothing to draw (then
  /// no GL call: the caller resolves the target).
  [[nodiscard]] bool draw_blended(const FrameView& frame, const ShadowView& shadow, SceneTarget& target,
                                  bool opaque_drawables);

 private:
  /// One particle stream: a growing vertex buffer, `vertices` per particle (an indexed quad for
  /// streaks and trails; sphere sprites choose per frame, see sprite_vertices()).
  struct Stream {
    std::size_t floats = kInstanceFloats;  // per instance
    std::size_t vertices = 4;
    GLuint vao = 0;
    GLuint instances = 0;
    std::size_t capacity = 0;     // vertices the GL buffer holds
    std::vector<float> staging;   // per particle
    std::vector<float> expanded;  // per vertex: `vertices` copies of each particle
    std::size_t count = 0;
  };
  // Particle programs by style and by sun taps per vertex (0: no shadow map this frame, 1, or
  // 4 with particle casters), compiled on first use: llvmpipe runs a vertex shader's texture
  // lookups even when a uniform branch skips them, so each variant samples only what it needs.
  // The textured variants are used for a whole stream in frames where one of its batches is
  // textured (untextured particles in it carry parameter -1): frames without textures pay
  // nothing for them.
  enum Style {
    soft_style, additive_style, droplet_style, streak_style, trail_style, smoke_style, flame_style,
    style_count
  };

  void upload(Stream& stream, const std::uint32_t* order = nullptr);
  /// 3 (one triangle each) when the stream's sprites are small on screen, 4 (quads) when big.
  [[nodiscard]] static std::size_t sprite_vertices(const Stream& stream, const Camera& camera,
                                                   float pixels_per_unit);
  [[nodiscard]] static QuadBatch batch(const Stream& s) { return {s.vao, s.count, s.vertices}; }
  const Program& program(Style style, const RenderSettings& settings, const ShadowView& shadow);
  void set_uniforms(const Program& p, const FrameView& frame, const ShadowView& shadow) const;

  const GlTable* gl_ = nullptr;
  GLuint quad_ebo_ = 0;
  std::size_t quad_capacity_ = 0;  // particles quad_ebo_ indexes
  Stream soft_, additive_, droplets_, streaks_, trails_;
  bool smoke_ = false, flame_ = false;  // this frame's soft / additive stream holds a textured batch
  GLuint noise_ = 0;                    // the noise texture (texture unit 5)
  Program programs_[style_count][3];
  std::vector<float> sort_depth_;
  BackToFrontSort sort_;
};

}  // namespace simreel::render::detail
