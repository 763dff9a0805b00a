// The shadow pass (passes/shadow_pass.hpp).
#include "shadow_pass.hpp"

#include <initializer_list>
#include <algorithm>

#include "common_glsl.hpp"
#include "gl/targets.hpp"
#include "shadow_shaders.hpp"
#include "transforms.hpp"

namespace simreel::render::detail {

void ShadowPass::create(const GlTable& gl, const RenderSettings& settings) {
  gl_ = &gl;
  depth_program_ = Program(gl, "shadow depth", glsl_source({kDepthVs}), glsl_source({kDepthFs}));
  particle_depth_program_ = Program(gl, "particle shadow depth", glsl_source({kSpriteCornerGlsl, kParticleDepthVs}),
                                    glsl_source({kParticleDepthFs}));
  gl.GenTextures(1, &texture_);
  gl.BindTexture(GL_TEXTURE_2D, texture_);
  gl.TexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, kShadowMapSize, kShadowMapSize, 0,
                GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  gl.GenFramebuffers(1, &fbo_);
  gl.BindFramebuffer(GL_FRAMEBUFFER, fbo_);
  gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, texture_, 0);
  gl.DrawBuffer(GL_NONE);
  gl.ReadBuffer(GL_NONE);
  // The message gives the frame size, as for every target.
  check_framebuffer(gl, "shadow map", settings.width, settings.height);
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
}

void ShadowPass::destroy() noexcept {
  if (gl_ == nullptr) return;
  if (fbo_ != 0) gl_->DeleteFramebuffers(1, &fbo_);
  if (texture_ != 0) gl_->DeleteTextures(1, &texture_);
  fbo_ = texture_ = 0;
  depth_program_ = Program();
  particle_depth_program_ = Program();
}

const ShadowView& ShadowPass::draw(const FrameView& frame, const DrawableTable& table, const GpuMesh& cube,
                                     QuadBatch soft, QuadBatch droplets) {
  const GlTable& gl = *gl_;
  const RenderSettings& settings = frame.settings;
  // Updated in place: with no caster the previous fit's values stay, as uploaded before.
  ShadowView& shadow = view_;
  shadow.texture = texture_;
  // Fit an orthographic sun view around every caster: boxes, meshes and, if asked, particles.
  Eigen::AlignedBox3f bounds;
  table.for_each([&](const Drawable& d) {
    if (d.kind == DrawableKind::box) {
      for (int c = 0; c < 8; ++c) {
        const Vec3f corner((c & 1) ? 1.f : -1.f, (c & 2) ? 1.f : -1.f, (c & 4) ? 1.f : -1.f);
        bounds.extend(d.rotation * corner.cwiseProduct(d.half_extents) + d.translation);
      }
    } else if (d.kind == DrawableKind::mesh && !d.local_bounds.isEmpty()) {
      for (int c = 0; c < 8; ++c) {
        bounds.extend(d.rotation * d.local_bounds.corner(Eigen::AlignedBox3f::CornerType(c)) +
                      d.translation);
      }
    } else if (d.kind == DrawableKind::particles && settings.particle_shadows &&
               (d.style == ParticleStyle::soft || d.style == ParticleStyle::droplet)) {
      for (std::size_t i = 0; i < d.instances.size(); i += kInstanceFloats) {
        const Vec3f c(d.instances[i], d.instances[i + 1], d.instances[i + 2]);
        const float r = d.instances[i + 3];
        bounds.extend(c - Vec3f::Constant(r));
        bounds.extend(c + Vec3f::Constant(r));
      }
    }
  });
  shadow.enabled = !bounds.isEmpty() && bounds.diagonal().allFinite();
  if (!shadow.enabled) return shadow;

  const Vec3f center = bounds.center();
  const float radius = std::max(0.5f * bounds.diagonal().norm() * 1.05f, 1e-3f);
  Vec3f dir = frame.light.direction;
  dir = dir.squaredNorm() > 0.f ? dir.normalized() : Vec3f(0.f, 0.f, -1.f);
  const Vec3f eye = center - dir * (2.f * radius);
  const float far_m = 4.f * radius;
  const Mat4f light_view = look_at(eye, center, any_perpendicular(dir));
  shadow.light_view_proj = ortho(radius, radius, 0.f, far_m) * light_view;
  shadow.light_right = light_view.block<1, 3>(0, 0).transpose();
  shadow.light_up = light_view.block<1, 3>(1, 0).transpose();
  const float texel_m = 2.f * radius / float(kShadowMapSize);
  shadow.offset = 1.5f * texel_m;
  shadow.bias = 1.5f * texel_m / far_m;
  // A soft-edged sun: about 2 cm of penumbra at this scale, never sharper than two texels
  // (five with particle casters, whose stochastic texels the lookup must average away).
  const float min_texels = settings.particle_shadows ? 5.f : 2.f;
  shadow.radius = std::max(min_texels / float(kShadowMapSize), 0.02f / (2.f * radius));

  gl.BindFramebuffer(GL_FRAMEBUFFER, fbo_);
  gl.Viewport(0, 0, kShadowMapSize, kShadowMapSize);
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_LESS);
  gl.DepthMask(GL_TRUE);
  gl.Clear(GL_DEPTH_BUFFER_BIT);
  gl.Enable(GL_POLYGON_OFFSET_FILL);
  gl.PolygonOffset(1.5f, 2.f);
  depth_program_.use();
  depth_program_.set("u_light_view_proj", shadow.light_view_proj);
  table.for_each([&](const Drawable& d) {
    if (d.kind == DrawableKind::box) {
      depth_program_.set("u_model", affine(d.rotation * d.half_extents.asDiagonal(), d.translation));
      gl.BindVertexArray(cube.vao);
      gl.DrawElements(GL_TRIANGLES, cube.index_count, GL_UNSIGNED_INT, nullptr);
    } else if (d.kind == DrawableKind::mesh) {
      depth_program_.set("u_model", affine(d.rotation, d.translation));
      gl.BindVertexArray(d.mesh.vao);
      gl.DrawElements(GL_TRIANGLES, d.mesh.index_count, GL_UNSIGNED_INT, nullptr);
    }
  });
  if (settings.particle_shadows) {
    const Program& p = particle_depth_program_;
    p.use();
    p.set("u_light_view_proj", shadow.light_view_proj);
    p.set("u_light_right", shadow.light_right);
    p.set("u_light_up", shadow.light_up);
    for (const QuadBatch* batch : {&soft, &droplets}) {
      if (batch->count == 0) continue;
      p.set("u_opaque", batch == &droplets ? 1 : 0);
      batch->draw(gl, p);
    }
  }
  gl.Disable(GL_POLYGON_OFFSET_FILL);
  return shadow;
}

}  // namespace simreel::render::detail
