// The particle passes (passes/particle_pass.hpp).
#include "particle_pass.hpp"

#include <initializer_list>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <string>

#include "common_glsl.hpp"
#include "particle_shaders.hpp"
#include "shadow_shaders.hpp"

namespace simreel::render::detail {
namespace {

constexpr int kNoiseSize = 128;      // texels along each side of the tileable noise
constexpr std::uint32_t kNoiseSeed = 0x5eed5eedu;

// Lattice value in [0, 1) at integer (x, y) of octave `o`, wrapped to `period` cells so the
// texture tiles (a 32-bit integer hash: the same bytes on every machine).
float lattice(int x, int y, int period, int o) {
  std::uint32_t h = kNoiseSeed ^ std::uint32_t(o) * 0x27d4eb2du;
  h ^= std::uint32_t((x % period + period) % period) * 0x85ebca6bu;
  h = (h ^ (h >> 15)) * 0x2c1b3c6du;
  h ^= std::uint32_t((y % period + period) % period) * 0xc2b2ae35u;
  h = (h ^ (h >> 13)) * 0x297a2d39u;
  h ^= h >> 16;
  return float(h >> 8) * (1.f / 16777216.f);
}

// Tileable fractal value noise (five octaves, periods 4..64 cells over the tile), stretched to
// [0, 255]: the puffs' and flames' texture. Made once, from a fixed seed, with integer hashes
// and float arithmetic in a fixed order, so every run and machine uploads the same bytes.
std::vector<std::uint8_t> make_noise() {
  std::vector<float> v(std::size_t(kNoiseSize) * kNoiseSize, 0.f);
  float amplitude = 1.f;
  for (int o = 0; o < 5; ++o, amplitude *= 0.55f) {
    const int period = 4 << o;
    const float cell = float(kNoiseSize) / float(period);
    for (int y = 0; y < kNoiseSize; ++y) {
      for (int x = 0; x < kNoiseSize; ++x) {
        const float fx = float(x) / cell, fy = float(y) / cell;
        const int ix = int(fx), iy = int(fy);
        float tx = fx - float(ix), ty = fy - float(iy);
        tx = tx * tx * (3.f - 2.f * tx);
        ty = ty * ty * (3.f - 2.f * ty);
        const float a = lattice(ix, iy, period, o), b = lattice(ix + 1, iy, period, o);
        const float c = lattice(ix, iy + 1, period, o), d = lattice(ix + 1, iy + 1, period, o);
        v[std::size_t(y) * kNoiseSize + x] += amplitude * ((a + tx * (b - a)) + ty * ((c + tx * (d - c)) - (a + tx * (b - a))));
      }
    }
  }
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  const float low = *lo, scale = 255.f / std::max(*hi - *lo, 1e-6f);
  std::vector<std::uint8_t> bytes(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) bytes[i] = std::uint8_t(std::lround((v[i] - low) * scale));
  return bytes;
}

}  // namespace

void ParticlePass::create(const GlTable& gl) {
  gl_ = &gl;
  // Particles are not instanced (llvmpipe runs an instanced draw as one small draw per
  // instance, several times slower for 100k sprites): every vertex carries its particle's data.
  // Sphere sprites are one triangle each (kSpriteCornerGlsl), streaks and trails indexed quads
  // sharing one index buffer.
  gl.GenBuffers(1, &quad_ebo_);
  streaks_.floats = kStreakFloats;
  trails_.floats = kStreakFloats;
  for (Stream* stream : {&soft_, &additive_, &droplets_, &streaks_, &trails_}) {
    gl.GenVertexArrays(1, &stream->vao);
    gl.BindVertexArray(stream->vao);
    gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, quad_ebo_);
    gl.GenBuffers(1, &stream->instances);
    gl.BindBuffer(GL_ARRAY_BUFFER, stream->instances);
    const GLsizei stride = GLsizei(stream->floats * sizeof(float));
    for (GLuint attribute = 1; 4 * (attribute - 1) < stream->floats; ++attribute) {
      const std::size_t first = 4 * (attribute - 1);
      gl.EnableVertexAttribArray(attribute);
      gl.VertexAttribPointer(attribute, GLint(std::min<std::size_t>(4, stream->floats - first)), GL_FLOAT,
                             GL_FALSE, stride, reinterpret_cast<const void*>(first * sizeof(float)));
    }
  }
  gl.BindVertexArray(0);
  gl.BindBuffer(GL_ARRAY_BUFFER, 0);

  const std::vector<std::uint8_t> noise = make_noise();
  gl.GenTextures(1, &noise_);
  gl.ActiveTexture(GL_TEXTURE5);
  gl.BindTexture(GL_TEXTURE_2D, noise_);
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  gl.TexImage2D(GL_TEXTURE_2D, 0, GL_R8, kNoiseSize, kNoiseSize, 0, GL_RED, GL_UNSIGNED_BYTE, noise.data());
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
  gl.GenerateMipmap(GL_TEXTURE_2D);  // small puffs read a blurred level: no sparkle
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
  gl.BindTexture(GL_TEXTURE_2D, 0);
  gl.ActiveTexture(GL_TEXTURE0);
}

void ParticlePass::destroy() noexcept {
  if (gl_ == nullptr) return;
  const GlTable& gl = *gl_;
  if (noise_ != 0) gl.DeleteTextures(1, &noise_);
  noise_ = 0;
  for (Stream* stream : {&soft_, &additive_, &droplets_, &streaks_, &trails_}) {
    if (stream->vao != 0) gl.DeleteVertexArrays(1, &stream->vao);
    if (stream->instances != 0) gl.DeleteBuffers(1, &stream->instances);
    *stream = Stream{};
  }
  if (quad_ebo_ != 0) gl.DeleteBuffers(1, &quad_ebo_);
  quad_ebo_ = 0;
  quad_capacity_ = 0;
  for (auto& by_taps : programs_) {
    for (Program& p : by_taps) p = Program();
  }
}

std::size_t ParticlePass::sprite_vertices(const Stream& stream, const Camera& camera, float pixels_per_unit) {
  // A triangle saves a triangle's set-up per sprite and costs 30 % more fragments (3 sqrt(3)
  // against 4 radii squared): the mean squared radius on screen (pixels^2) decides, so a few
  // big puffs among many sparks (the explosion's fireball) count by their area. At the
  // 100k-sprite benchmark's 1-2 px one triangle costs about 0.7 of a quad, at ~30 px smoke puffs
  // about 1.2 (bench/render); the two break even near 4 px.
  constexpr double kQuadFromPx2 = 16.0;
  const std::size_t n = stream.staging.size() / stream.floats;
  if (n == 0) return 3;
  const Vec3f forward = (camera.target - camera.position).normalized();
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const float* c = &stream.staging[i * stream.floats];
    const float depth = (Vec3f(c[0], c[1], c[2]) - camera.position).dot(forward);
    const double px = double(c[3]) / double(std::max(depth, camera.near_m)) * double(pixels_per_unit);
    sum += px * px;
  }
  return sum / double(n) >= kQuadFromPx2 ? 4 : 3;
}

void ParticlePass::gather(const DrawableTable& table, const Camera& camera, int height_px) {
  // Soft particles of every batch are merged and sorted back to front, so two overlapping
  // batches blend correctly; additive ones, droplets (opaque) and thin streaks need no order.
  soft_.staging.clear();  // unsorted; upload() takes the particles in sorted order
  additive_.staging.clear();
  droplets_.staging.clear();
  streaks_.staging.clear();
  trails_.staging.clear();
  smoke_ = flame_ = false;
  table.for_each([&](const Drawable& d) {
    if (d.kind != DrawableKind::particles) return;
    std::vector<float>* dst = &soft_.staging;
    if (d.style == ParticleStyle::additive) dst = d.trail ? &trails_.staging : &additive_.staging;
    if (d.style == ParticleStyle::droplet) dst = &droplets_.staging;
    if (d.style == ParticleStyle::streak) dst = &streaks_.staging;
    if (d.instances.empty()) return;
    smoke_ |= d.style == ParticleStyle::soft && d.particle_texture == ParticleTexture::smoke;
    flame_ |= d.style == ParticleStyle::additive && !d.trail && d.particle_texture == ParticleTexture::flame;
    dst->insert(dst->end(), d.instances.begin(), d.instances.end());
  });

  const std::size_t n = soft_.staging.size() / kInstanceFloats;
  const std::uint32_t* order = nullptr;
  if (n > 0) {
    const Vec3f forward = (camera.target - camera.position).normalized();
    sort_depth_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const float* c = &soft_.staging[i * kInstanceFloats];
      sort_depth_[i] = (Vec3f(c[0], c[1], c[2]) - camera.position).dot(forward);
    }
    order = sort_.sort(sort_depth_).data();
  }
  const float pixels_per_unit =
      0.5f * float(height_px) / std::tan(0.5f * camera.fov_deg * std::numbers::pi_v<float> / 180.f);
  for (Stream* stream : {&soft_, &additive_, &droplets_}) {
    stream->vertices = sprite_vertices(*stream, camera, pixels_per_unit);
  }
  upload(soft_, order);
  for (Stream* stream : {&additive_, &droplets_, &streaks_, &trails_}) upload(*stream);
}

void ParticlePass::upload(Stream& stream, const std::uint32_t* order) {
  const GlTable& gl = *gl_;
  stream.count = stream.staging.size() / stream.floats;
  if (stream.count == 0) return;
  const bool quads = stream.vertices == 4;
  if (quads && stream.count > quad_capacity_) {
    quad_capacity_ = std::max(stream.count, quad_capacity_ + quad_capacity_ / 2);
    std::vector<GLuint> indices(6 * quad_capacity_);
    for (std::size_t i = 0; i < quad_capacity_; ++i) {
      const auto base = GLuint(4 * i);
      const GLuint quad[6] = {base, base + 1, base + 2, base + 2, base + 1, base + 3};
      std::memcpy(&indices[6 * i], quad, sizeof quad);
    }
    gl.BindBuffer(GL_COPY_WRITE_BUFFER, quad_ebo_);
    gl.BufferData(GL_COPY_WRITE_BUFFER, GLsizeiptr(indices.size() * sizeof(GLuint)), indices.data(),
                  GL_STATIC_DRAW);
  }
  // A copy of each particle's data per corner (the shader derives the corner from gl_VertexID).
  const std::size_t f = stream.floats, v = stream.vertices;
  stream.expanded.resize(v * stream.staging.size());
  float* dst = stream.expanded.data();
  for (std::size_t i = 0; i < stream.count; ++i) {
    const float* src = &stream.staging[(order != nullptr ? order[i] : i) * f];
    for (std::size_t k = 0; k < v; ++k, dst += f) std::memcpy(dst, src, f * sizeof(float));
  }
  gl.BindBuffer(GL_ARRAY_BUFFER, stream.instances);
  const GLsizeiptr bytes = GLsizeiptr(stream.expanded.size() * sizeof(float));
  // Counted in vertices: a stream that switches from triangles to quads needs more room for the
  // same particles.
  if (v * stream.count > stream.capacity) {
    stream.capacity = std::max(v * stream.count, stream.capacity + stream.capacity / 2);
    gl.BufferData(GL_ARRAY_BUFFER, GLsizeiptr(stream.capacity * f * sizeof(float)), nullptr,
                  GL_STREAM_DRAW);
  }
  gl.BufferSubData(GL_ARRAY_BUFFER, 0, bytes, stream.expanded.data());
}

void ParticlePass::set_uniforms(const Program& p, const FrameView& frame,
                                const ShadowView& shadow) const {
  const RenderSettings& settings = frame.settings;
  const Light& light = frame.light;
  const Eigen::Matrix4f& view = frame.view;
  const Eigen::Matrix4f& proj = frame.proj;
  const Vec3f to_sun = light.direction.squaredNorm() > 0.f ? Vec3f(-light.direction.normalized())
                                                           : Vec3f(0.f, 0.f, 1.f);
  const Mat3f view_rotation = view.block<3, 3>(0, 0);
  const Vec3f to_sun_view = view_rotation * to_sun;
  p.use();
  p.set("u_view", view);
  p.set("u_proj", proj);
  p.set("u_up_view", Vec3f(view_rotation * Vec3f::UnitZ()));
  p.set("u_pixels_per_unit", proj(1, 1) * 0.5f * float(settings.height));
  p.set("u_viewport", float(settings.width), float(settings.height));
  p.set("u_near", frame.camera.near_m);
  p.set("u_light_view", to_sun_view);
  const Vec3f half = to_sun_view + Vec3f::UnitZ();  // zero only with the sun dead behind
  p.set("u_half_view", half.squaredNorm() > 1e-12f ? Vec3f(half.normalized()) : Vec3f::UnitZ());
  p.set("u_light_color", light.color);
  p.set("u_ambient", light.ambient);
  p.set("u_ground_ambient", light.ground_ambient);
  p.set("u_to_sun", to_sun);
  p.set("u_sun_offset", settings.particle_shadows ? 1.5f : 0.f);
  p.set("u_opaque", 0);
  p.set("u_shadow_map", 1);
  p.set("u_scene_depth", 3);
  p.set("u_noise", 5);
  p.set("u_depth_params", proj(2, 2), proj(2, 3));
  p.set("u_shadow_enabled", shadow.enabled ? 1 : 0);
  p.set("u_light_view_proj", shadow.light_view_proj);
  p.set("u_shadow_bias", shadow.bias);
  p.set("u_shadow_offset", 0.f);
  p.set("u_shadow_radius", shadow.radius);
}

const Program& ParticlePass::program(Style style, const RenderSettings& settings,
                                     const ShadowView& shadow) {
  const int variant = !shadow.enabled ? 0 : settings.particle_shadows ? 2 : 1;
  Program& p = programs_[style][variant];
  if (!p.valid()) {
    const GlTable& gl = *gl_;
    // The fragment stages see SUN_TAPS too: without a shadow map v_sun is the constant 1.
    const char* taps = variant == 0 ? "#define SUN_TAPS 0\n" : variant == 1 ? "#define SUN_TAPS 1\n"
                                                                         : "#define SUN_TAPS 4\n";
    static constexpr const char* kNames[] = {"soft particle",  "additive particle", "droplet particle",
                                             "streak particle", "trail particle",   "smoke particle",
                                             "flame particle"};
    static constexpr const char* kSphereFs[] = {kParticleSoftFs, kParticleAddFs, kParticleDropletFs, "", "",
                                                kParticleSoftFs, kParticleAddFs};
    const bool streak = style == streak_style || style == trail_style;
    const char* textured =
        style == smoke_style || style == flame_style ? "#define TEXTURED 1\n" : "#define TEXTURED 0\n";
    const char* additive = style == trail_style ? "#define ADDITIVE 1\n" : "#define ADDITIVE 0\n";
    const char* spark = style == additive_style || style == flame_style ? "#define SPARK 1\n" : "#define SPARK 0\n";
    const std::string vs =
        glsl_source({taps, textured, additive, spark, kShadowGlsl, kSpriteCornerGlsl, streak ? kStreakVs : kParticleVs});
    // Sprites stand for spheres and take their depth; a streak is a flat capsule.
    const std::string fs =
        streak ? glsl_source({taps, kAmbientGlsl, kSceneDepthGlsl, style == trail_style ? kTrailFs : kStreakFs})
               : glsl_source({taps, textured, kAmbientGlsl, kSceneDepthGlsl, kSphereDepthGlsl, kSphereFs[style]});
    p = Program(gl, kNames[style], vs, fs);
  }
  return p;
}

void ParticlePass::draw_droplets(const FrameView& frame, const ShadowView& shadow, int samples) {
  if (droplets_.count == 0) return;
  const GlTable& gl = *gl_;
  // Opaque: drawn before the scene depth is copied, so soft particles fade against them too.
  const Program& p = program(droplet_style, frame.settings, shadow);
  set_uniforms(p, frame, shadow);
  p.set("u_opaque", 1);
  if (samples > 0) gl.Enable(GL_SAMPLE_ALPHA_TO_COVERAGE);
  batch(droplets_).draw(gl, p);
  gl.Disable(GL_SAMPLE_ALPHA_TO_COVERAGE);
}

bool ParticlePass::draw_blended(const FrameView& frame, const ShadowView& shadow,
                                SceneTarget& target, bool opaque_drawables) {
  if (soft_.count == 0 && additive_.count == 0 && streaks_.count == 0 && trails_.count == 0) return false;
  const GlTable& gl = *gl_;
  target.copy_depth(opaque_drawables || droplets_.count > 0);
  gl.ActiveTexture(GL_TEXTURE5);
  gl.BindTexture(GL_TEXTURE_2D, noise_);
  gl.ActiveTexture(GL_TEXTURE0);
  gl.Enable(GL_BLEND);
  gl.DepthMask(GL_FALSE);
  const RenderSettings& s = frame.settings;
  auto draw = [&](const Stream& stream, const Program& program, bool premultiplied) {
    if (stream.count == 0) return;
    set_uniforms(program, frame, shadow);
    if (premultiplied) {
      gl.BlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    } else {
      gl.BlendFunc(GL_ONE, GL_ONE);
    }
    batch(stream).draw(gl, program);
  };
  // Everything blended is drawn after the resolve at one sample per pixel. Multisampling would
  // give each pixel's covered samples the one value its shader takes at the pixel centre, and
  // every one of these shaders brings its light smoothly to zero at the rim of its shape (a
  // rain streak: 1 - smoothstep(0.35, 1) across a half-width of at least 0.75 px), so the
  // resolve would give back the same pixel after four times the blending.
  // Each sprite's shader fades it by the scene depth copy (visible_fraction, the trails'
  // fade), which is 0 wherever the hardware test would have rejected the fragment.
  target.resolve_for_blending();
  gl.Disable(GL_DEPTH_TEST);
  draw(streaks_, program(streak_style, s, shadow), true);
  draw(soft_, program(smoke_ ? smoke_style : soft_style, s, shadow), true);
  draw(trails_, program(trail_style, s, shadow), false);
  draw(additive_, program(flame_ ? flame_style : additive_style, s, shadow), false);
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthMask(GL_TRUE);
  gl.Disable(GL_BLEND);
  return true;
}

}  // namespace simreel::render::detail
