#pragma once
/// @file renderer.hpp
/// The offscreen renderer. It keeps its own table `key -> drawable` (a hash map), applies
/// transforms and particle data the program hands it, and never includes an engine header:
/// keys are opaque 64-bit values (the program passes sim::Handle::packed()).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include <Eigen/Core>

#include "simreel/render/context.hpp"
#include "simreel/render/image.hpp"
#include "simreel/render/mesh.hpp"

namespace simreel::render {

using ObjectKey = std::uint64_t;
using Vec3f = Eigen::Vector3f;
using Vec4f = Eigen::Vector4f;
using Mat3f = Eigen::Matrix3f;

/// Pinhole camera. World frame is z up.
struct Camera {
  Vec3f position{6.f, -6.f, 3.f};  ///< (m)
  Vec3f target{0.f, 0.f, 0.5f};    ///< (m) point looked at
  Vec3f up{0.f, 0.f, 1.f};
  float fov_deg = 40.f;            ///< vertical field of view (degrees), in (0, 180)
  float near_m = 0.05f;            ///< near clip distance (m)
  float far_m = 500.f;             ///< far clip distance (m)
};

/// Directional sun plus hemisphere sky light. Boxes and meshes (and particles, if
/// RenderSettings::particle_shadows) cast soft sun shadows through a shadow map fitted to the
/// casters each frame, onto everything.
struct Light {
  Vec3f direction{-0.4f, 0.3f, -1.f};  ///< direction the light travels (from the sun), world frame
  Vec3f color{1.f, 0.97f, 0.92f};      ///< linear RGB intensity
  /// Sky light: linear RGB reaching a surface facing straight up (+z). A surface facing
  /// straight down gets `ground_ambient` (light bounced off the ground); in between the two
  /// mix with (1 + n_z) / 2 (hemisphere lighting).
  Vec3f ambient{0.30f, 0.33f, 0.38f};
  Vec3f ground_ambient{0.17f, 0.17f, 0.17f};  ///< linear RGB from below (ground bounce)
};

/// What is drawn behind everything; meshes fog towards it with distance.
enum class Background {
  /// The sky along each pixel's view direction: RenderSettings::sky_bottom at the horizon,
  /// sky_top overhead, the sun (disk and haze) where Light::direction comes from; below the
  /// horizon the ground plane (the first horizontal plane) continues into aerial perspective.
  sky_gradient,
  solid,         ///< RenderSettings::background_color everywhere
  /// Nothing behind the scene: alpha 0 where nothing is drawn (PNG with alpha, WebM VP9 with
  /// alpha); meshes fog towards the sky gradient's colour and fade out in alpha with the fog.
  transparent,
};

/// HDR bloom (Jimenez, "Next generation post processing in Call of Duty: Advanced Warfare",
/// SIGGRAPH 2014): the linear frame is downsampled into a chain of half-size levels with a
/// 13-tap filter, the levels are added back up with a 3x3 tent, and the result is mixed into
/// the frame: frame' = (1 - intensity) frame + intensity blur. No threshold, so the sum of the
/// image is kept (within the filters' edge clamp) and only what is brighter than its
/// surroundings visibly glows; bright HDR values (fire, sparks, the sun's highlights) spread
/// far more light than the 8-bit tone map can show.
struct Bloom {
  float intensity = 0.04f;  ///< [0, 1] weight of the blurred image; 0 disables the pass
  /// [0, 1] how much each coarser (wider) level adds to the one above it when the chain is
  /// added back up: 0 keeps the glow tight, 1 spreads it over the frame.
  float radius = 0.7f;
};

/// Output size and background. All colours in the renderer's inputs are linear RGB; shading
/// and blending happen in linear half-float, then the frame is tone-mapped (unchanged up to
/// 0.8, a soft shoulder towards 1 above), sRGB-encoded and dithered by half a level.
struct RenderSettings {
  int width = 1280;        ///< (pixels) >= 1
  int height = 720;        ///< (pixels) >= 1
  int msaa_samples = 4;    ///< 0 or 1 disables multisampling
  Background background = Background::sky_gradient;
  Vec3f sky_top{0.32f, 0.50f, 0.78f};     ///< sky overhead, the zenith (linear RGB)
  Vec3f sky_bottom{0.80f, 0.86f, 0.93f};  ///< sky at the horizon, the fog colour of far things
  Vec3f background_color{0.05f, 0.05f, 0.06f};  ///< linear RGB of Background::solid
  /// Soft and droplet particles cast sun shadows: discs facing the sun in the shadow map,
  /// translucent ones in proportion to their opacity (each keeps that fraction of its
  /// shadow-map texels, by a fixed hash; the filtered lookups average them). Smoke then shades
  /// itself: particles behind others as seen from the sun are darker.
  bool particle_shadows = false;
  Bloom bloom;  ///< HDR bloom post-pass; bloom.intensity 0 turns it off
  /// Camera shutter angle (degrees, [0, 360]): moving meshes and the camera are drawn at
  /// `shutter_samples` evenly spaced instants over the last shutter_deg / 360 of the frame
  /// interval (between the previous frame's transforms and this frame's) and averaged. 0: off.
  /// Particles read it for their own streaks.
  float shutter_deg = 0.f;
  int shutter_samples = 8;  ///< sub-frame instants per frame with motion blur, [2, 64]
};

/// A finite, drawn piece of an infinite ground plane, centred on the plane's origin. Its
/// checker (cells aligned with the world x/y axes when the normal is z) fades with distance,
/// and everything fogs towards the sky's horizon colour with distance. Towards its edge the
/// square turns into the unshadowed plain plane that the sky pass continues to the horizon when
/// it is the ground (the first plane facing +z); any other plane fades into the fog there.
struct PlaneDesc {
  Vec3f point{0.f, 0.f, 0.f};   ///< (m) the plane's origin, world frame
  Vec3f normal{0.f, 0.f, 1.f};
  float half_size = 20.f;       ///< (m) drawn square extends +-half_size around point
  Vec4f color{0.55f, 0.57f, 0.6f, 1.f};
  float checker_m = 1.f;        ///< (m) checker cell size; 0 draws a plain color
};

struct BoxDesc {
  Vec3f half_extents{0.5f, 0.5f, 0.5f};  ///< (m) along local axes
  Vec4f color{0.8f, 0.45f, 0.2f, 1.f};
};

/// How particles are drawn.
enum class ParticleStyle {
  /// Camera-facing sprites standing for translucent spheres (smoke, spray): opacity follows
  /// Beer-Lambert through the sphere, 1 - (1 - alpha)^tau with the chord's optical depth
  /// tau = h (1 - (1 - alpha) r^2) (h = chord / diameter at r radii from the centre: a density
  /// blending uniform, weight alpha, with 1 - r^2, weight 1 - alpha, whose chords give h and
  /// h^3), so the centre has the given alpha and the rim fades to 0 — crisply for dense
  /// droplets, softly for thin smoke; lit from the sun with a sphere normal (the far
  /// side darker); faded where the sphere dips into opaque geometry (soft particles); alpha
  /// blended back to front over all soft batches.
  soft,
  additive,  ///< soft glow added to the frame (fire, sparks); also depth-faded
  /// Velocity-stretched capsules (rain): from the particle's position back along its screen
  /// velocity, length |velocity| x streak_s, width 2 x radius; head brighter than the tail.
  streak,
  /// Small lit opaque spheres (droplets of a sprinkler or jet): sun, shadow, highlight; drawn
  /// with the opaque geometry, so they need no sorting. Alpha is ignored.
  droplet,
};

/// What a sprite is textured with. Both textures come from one seeded, tileable 3-D noise made
/// once when the renderer starts (no image files): each particle reads its own slice, turned by
/// its own angle, so no two puffs look alike and none pops as it ages.
enum class ParticleTexture {
  none,   ///< plain sphere (the styles as documented above)
  /// Soft: a smoke puff. The noise modulates the opacity, the puff turns slowly and dissolves
  /// from its thin parts as it ages (age / lifetime), and dense parts on the side away from
  /// the sun are darker (a cheap self-shadow).
  smoke,
  /// Additive: a flame. The colour is a blackbody-like ramp of the particle's temperature,
  /// falling with age (white-yellow core -> orange -> red -> dark), flickering per particle;
  /// the noise breaks the glow into tongues. The particle's own RGB is ignored, its alpha kept.
  flame,
};

/// A batch of particles, structure-of-arrays; copied during set_particles().
struct ParticleBatch {
  std::size_t count = 0;
  const float* position = nullptr;  ///< (count x 3) world frame (m)
  const float* color = nullptr;     ///< (count x 4) linear RGBA in [0, 1]
  const float* radius = nullptr;    ///< (count) (m): the sprite's world-space radius
  ParticleStyle style = ParticleStyle::soft;
  /// (count x 3) world frame (m/s); optional, read by `streak` only (null: round sprites).
  const float* velocity = nullptr;
  float streak_s = 0.02f;  ///< (s) streak length per unit speed: a streak covers velocity x streak_s
  /// (count) age (s) and lifetime (s); optional (null: age 0), read by the textures.
  const float* age = nullptr;
  const float* lifetime = nullptr;
  /// (count) stable particle ids; optional (null: the index): each particle's own noise slice,
  /// angle and flicker follow it for its whole life.
  const std::uint64_t* id = nullptr;
  /// (s) additive only, with `velocity`: the sprite is drawn as a glowing streak from the
  /// particle back along velocity x trail_s (a fading trail, or the camera's exposure time for
  /// motion blur: the program adds shutter_deg / 360 / fps). The streak carries the energy of
  /// the sprite it replaces (its summed brightness does not change with its length). 0: a dot.
  float trail_s = 0.f;
  /// Additive only: multiplies the colour; above 1 the frame holds values over 1 (HDR) where
  /// the particle glows, which the bloom post-pass spreads.
  float emissive = 1.f;
  /// (Hz) additive only: each particle flashes on and off this many times per second of its
  /// age (glitter, crackle): lit while fract(age x strobe_hz + r) < strobe_duty, r its own
  /// random number (from `id`), dark otherwise. 0: steady.
  float strobe_hz = 0.f;
  float strobe_duty = 0.5f;  ///< in (0, 1]: the lit fraction of each period
  ParticleTexture texture = ParticleTexture::none;
};

struct SceneList;  // scene_list.hpp

class Renderer {
 public:
  /// The context must be current on this thread and outlive the renderer. @throws ContextError
  /// if the framebuffer or a shader cannot be created (message names the stage and the GL log);
  /// std::invalid_argument if width or height < 1. msaa_samples is clamped to GL_MAX_SAMPLES.
  Renderer(Context& context, const RenderSettings& settings);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// @throws std::invalid_argument unless 0 < fov_deg < 180, 0 < near_m < far_m and
  ///         target != position.
  void set_camera(const Camera& camera);
  void set_light(const Light& light);

  /// Adds drawables under a key, at the identity transform. @throws std::invalid_argument if the
  /// key is already used, half_size <= 0, the normal is zero, or a half extent is <= 0.
  void add_plane(ObjectKey key, const PlaneDesc& desc);
  void add_box(ObjectKey key, const BoxDesc& desc);
  /// Adds a triangle mesh (static, or dynamic for cloth) with its material; loads the texture.
  /// @throws std::invalid_argument if the key is used, positions are not n x 3 with n >= 1,
  ///         normals or uvs have the wrong size, indices are not m x 3 or reach >= n, the
  ///         parts do not tile the triangles in order, or an in-memory texture's size does not
  ///         match; render::IoError if a texture_path cannot be read.
  void add_mesh(ObjectKey key, const MeshDesc& desc);
  /// Replaces the vertex positions (n x 3, local frame, m) of a mesh, and its normals (n x 3);
  /// empty normals are recomputed with compute_vertex_normals. n must stay the same.
  /// @throws std::out_of_range if the key is unknown; std::invalid_argument if it is not a mesh
  ///         or a size differs.
  void update_mesh(ObjectKey key, std::span<const float> positions, std::span<const float> normals = {});
  /// Moves a mesh drawable (box, plane or mesh): x_world = rotation * x_local + translation,
  /// where a plane's local frame is the world frame its PlaneDesc was given in.
  /// @throws std::out_of_range if the key is unknown; std::invalid_argument if it holds particles.
  void set_transform(ObjectKey key, const Vec3f& translation, const Mat3f& rotation);
  /// Replaces the particles drawn under `key` (creates the drawable on first use). The arrays
  /// are copied. Soft particles of all keys are sorted back to front together every frame.
  /// @throws std::invalid_argument if count > 0 and an array is null, streak_s or trail_s < 0,
  ///         emissive < 0, age is given without lifetime, or the key holds a mesh.
  void set_particles(ObjectKey key, const ParticleBatch& batch);
  void remove(ObjectKey key);  ///< unknown keys are ignored
  /// Applies one frame's SceneList (scene_list.hpp) in its order: added (add_* and
  /// set_transform), moved (set_transform), removed (remove), particles (set_particles), meshes
  /// (update_mesh), camera (set_camera). @throws what those calls throw.
  void apply(const SceneList& list);

  /// Draws the frame and reads it back: RGBA8, rows top to bottom, alpha 255 (with
  /// Background::transparent: the coverage, 0 where nothing is drawn, colours not premultiplied).
  /// With shutter_deg > 0, what moved since the previous render() is blurred along its motion.
  /// @throws ContextError if OpenGL reports an error.
  [[nodiscard]] Image render();

  [[nodiscard]] const RenderSettings& settings() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace simreel::render
