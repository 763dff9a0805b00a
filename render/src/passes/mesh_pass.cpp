// The mesh pass (passes/mesh_pass.hpp).
#include "mesh_pass.hpp"

#include <initializer_list>
#include <algorithm>
#include <cstdint>
#include <vector>

#include "common_glsl.hpp"
#include "mesh_shaders.hpp"
#include "shadow_shaders.hpp"
#include "sky_pass.hpp"
#include "sky_shaders.hpp"
#include "transforms.hpp"

namespace simreel::render::detail {

namespace {

/// Unit cube [-1, 1]^3 with one normal per face (24 vertices), scaled per box by the model
/// matrix; axis-aligned scaling leaves face normals unchanged.
void unit_cube(std::vector<Vertex>& vertices, std::vector<GLuint>& indices) {
  for (int axis = 0; axis < 3; ++axis) {
    for (const float sign : {-1.f, 1.f}) {
      const int a = (axis + 1) % 3;
      const int b = (axis + 2) % 3;
      const GLuint base = GLuint(vertices.size());
      // Corners ordered so the face is counter-clockwise seen from outside.
      const float corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
      for (const auto& c : corners) {
        Vertex v{};
        v.p[axis] = sign;
        v.p[a] = c[0];
        v.p[b] = sign > 0 ? c[1] : -c[1];
        v.n[axis] = sign;
        vertices.push_back(v);
      }
      for (const GLuint i : {0u, 1u, 2u, 0u, 2u, 3u}) indices.push_back(base + i);
    }
  }
}

}  // namespace

void MeshPass::create(const GlTable& gl) {
  gl_ = &gl;
  program_ = Program(gl, "lit mesh", glsl_source({kLitVs}),
                     glsl_source({kAmbientGlsl, kSkyGlsl, kShadowGlsl, kLitFs}));
  std::vector<Vertex> vertices;
  std::vector<GLuint> indices;
  unit_cube(vertices, indices);
  cube_ = upload_mesh(gl, vertices, indices);
}

void MeshPass::destroy() noexcept {
  if (gl_ == nullptr) return;
  destroy_mesh(*gl_, cube_);
  program_ = Program();
}

void MeshPass::draw(const FrameView& frame, const ShadowView& shadow, const DrawableTable& table) {
  const GlTable& gl = *gl_;
  const RenderSettings& settings = frame.settings;
  const Camera& camera = frame.camera;
  const Light& light = frame.light;
  const Program& p = program_;
  p.use();
  p.set("u_view_proj", Mat4f(frame.proj * frame.view));
  p.set("u_eye", camera.position);
  set_sky_uniforms(p, settings, light);  // also the light's direction, colour and ambient
  p.set("u_ground_ambient", light.ground_ambient);
  p.set("u_fog_distance", fog_distance(camera));
  const Drawable* ground = find_ground(table);
  p.set("u_ground_plane", 0);
  p.set("u_shadow_map", 1);
  p.set("u_texture", 2);
  p.set("u_shadow_enabled", shadow.enabled ? 1 : 0);
  p.set("u_light_view_proj", shadow.light_view_proj);
  p.set("u_shadow_bias", shadow.bias);
  p.set("u_shadow_offset", shadow.offset);
  p.set("u_shadow_radius", shadow.radius);
  p.set("u_has_texture", 0);

  table.for_each([&](const Drawable& d) {
    if (d.kind == DrawableKind::plane) {
      p.set("u_model", affine(d.rotation, d.translation));
      p.set("u_normal_matrix", d.rotation);
      p.set("u_color", d.plane.color);
      p.set("u_specular", 0.06f);
      p.set("u_checker_m", std::max(d.plane.checker_m, 0.f));
      p.set("u_half_size", std::max(d.plane.half_size, 1e-6f));
      p.set("u_ground_plane", &d == ground ? 1 : 0);
      gl.BindVertexArray(d.mesh.vao);
      gl.DrawElements(GL_TRIANGLES, d.mesh.index_count, GL_UNSIGNED_INT, nullptr);
      p.set("u_ground_plane", 0);
    } else if (d.kind == DrawableKind::box) {
      p.set("u_model", affine(d.rotation * d.half_extents.asDiagonal(), d.translation));
      p.set("u_normal_matrix", d.rotation);
      p.set("u_color", d.color);
      p.set("u_specular", 0.25f);
      p.set("u_checker_m", 0.f);
      p.set("u_half_size", 0.f);
      gl.BindVertexArray(cube_.vao);
      gl.DrawElements(GL_TRIANGLES, cube_.index_count, GL_UNSIGNED_INT, nullptr);
    } else if (d.kind == DrawableKind::mesh) {
      p.set("u_model", affine(d.rotation, d.translation));
      p.set("u_normal_matrix", d.rotation);
      p.set("u_half_size", 0.f);
      gl.BindVertexArray(d.mesh.vao);
      for (const Drawable::Part& part : d.parts) {
        const Material& m = part.material;
        p.set("u_color", m.base_color);
        p.set("u_specular", std::clamp(m.specular, 0.f, 1.f));
        p.set("u_checker_m", std::max(m.checker_m, 0.f));
        p.set("u_has_texture", part.texture != 0 ? 1 : 0);
        if (part.texture != 0) {
          gl.ActiveTexture(GL_TEXTURE2);
          gl.BindTexture(GL_TEXTURE_2D, part.texture);
        }
        if (!m.double_sided) gl.Enable(GL_CULL_FACE);
        gl.DrawElements(GL_TRIANGLES, part.index_count, GL_UNSIGNED_INT,
                        reinterpret_cast<const void*>(std::uintptr_t(part.first_index) * sizeof(std::uint32_t)));
        gl.Disable(GL_CULL_FACE);
      }
      p.set("u_has_texture", 0);
    }
  });
}

}  // namespace simreel::render::detail
