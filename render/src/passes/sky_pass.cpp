// The sky pass (passes/sky_pass.hpp).
#include "sky_pass.hpp"

#include <algorithm>

#include "common_glsl.hpp"
#include "gl/targets.hpp"
#include "sky_shaders.hpp"
#include "transforms.hpp"

namespace simreel::render::detail {

const Drawable* find_ground(const DrawableTable& table) {
  const Drawable* ground = nullptr;
  table.for_each([&](const Drawable& d) {
    if (ground != nullptr || d.kind != DrawableKind::plane) return;
    const Vec3f n = (d.rotation * d.plane.normal).normalized();
    if (n.z() > 0.999f) ground = &d;
  });
  return ground;
}

float fog_distance(const Camera& camera) {
  return std::max(5.f * (camera.target - camera.position).norm(), 1e-3f);
}

void set_sky_uniforms(const Program& p, const RenderSettings& settings, const Light& light) {
  const bool solid = settings.background == Background::solid;
  p.set("u_sky_mode", solid ? 1 : settings.background == Background::transparent ? 2 : 0);
  p.set("u_sky_top", solid ? settings.background_color : settings.sky_top);
  p.set("u_sky_bottom", solid ? settings.background_color : settings.sky_bottom);
  const Vec3f dir = light.direction.squaredNorm() > 0.f ? Vec3f(light.direction.normalized())
                                                        : Vec3f(0.f, 0.f, -1.f);
  p.set("u_sun_dir", Vec3f(-dir));
  p.set("u_sun_color", light.color);
  p.set("u_light_dir", dir);
  p.set("u_light_color", light.color);
  p.set("u_ambient", light.ambient);
}

void SkyPass::create(const GlTable& gl, const RenderSettings& settings, int samples) {
  gl_ = &gl;
  settings_ = &settings;
  program_ = Program(gl, "sky", glsl_source({kFullscreenVs}), glsl_source({kAmbientGlsl, kSkyGlsl, kSkyFs}));
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

void SkyPass::draw(const FrameView& frame, const DrawableTable& table, GLuint scene_fbo,
                   GLuint empty_vao) {
  const GlTable& gl = *gl_;
  const RenderSettings& settings = *settings_;
  const int w = settings.width;
  const int h = settings.height;
  const Drawable* ground = find_ground(table);
  const Mat4f inv_view_proj = (frame.proj * frame.view).inverse();
  const Light& light = frame.light;
  const float ground_z = ground != nullptr ? (ground->rotation * ground->plane.point + ground->translation).z() : 0.f;
  // Everything the shading reads, to skip it when nothing changed.
  std::vector<float> inputs(inv_view_proj.data(), inv_view_proj.data() + 16);
  for (const Vec3f& v : {frame.camera.position, light.direction, light.color, light.ambient}) {
    inputs.insert(inputs.end(), v.data(), v.data() + 3);
  }
  inputs.push_back(fog_distance(frame.camera));
  inputs.push_back(ground != nullptr ? 1.f : 0.f);
  inputs.push_back(ground_z);
  if (ground != nullptr) inputs.insert(inputs.end(), ground->plane.color.data(), ground->plane.color.data() + 3);
  if (!drawn_ || inputs != last_) {
    gl.BindFramebuffer(GL_FRAMEBUFFER, fbo_);
    gl.Disable(GL_DEPTH_TEST);
    gl.Disable(GL_BLEND);
    program_.use();
    set_sky_uniforms(program_, settings, light);
    program_.set("u_inv_view_proj", inv_view_proj);
    program_.set("u_eye", frame.camera.position);
    program_.set("u_viewport", float(w), float(h));
    program_.set("u_ground", ground != nullptr ? 1 : 0);
    program_.set("u_ground_z", ground_z);
    program_.set("u_ground_albedo", ground != nullptr ? Vec3f(ground->plane.color.head<3>()) : Vec3f::Zero());
    program_.set("u_fog_distance", fog_distance(frame.camera));
    gl.BindVertexArray(empty_vao);
    gl.DrawArrays(GL_TRIANGLES, 0, 3);
    drawn_ = true;
    last_ = std::move(inputs);
  }
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  gl.BindFramebuffer(GL_DRAW_FRAMEBUFFER, scene_fbo);
  gl.BlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

}  // namespace simreel::render::detail
