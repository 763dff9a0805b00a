// The renderer's orchestration: the drawable table (add, move, remove, particle and mesh
// updates, SceneList), and render() calling the passes in order: shadow, sky, meshes,
// droplets, blended particles, resolve, post.
#include "simreel/render/renderer.hpp"
#include "simreel/render/scene_list.hpp"

#include <initializer_list>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <numbers>
#include <stdexcept>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "drawables.hpp"
#include "gl/buffers.hpp"
#include "gl/scene_target.hpp"
#include "gl/targets.hpp"
#include "passes/frame.hpp"
#include "passes/mesh_pass.hpp"
#include "passes/motion_blur.hpp"
#include "passes/particle_look.hpp"
#include "passes/particle_pass.hpp"
#include "passes/post_pass.hpp"
#include "passes/shadow_pass.hpp"
#include "passes/sky_pass.hpp"
#include "transforms.hpp"

namespace simreel::render {

using detail::Drawable;
using detail::DrawableKind;
using detail::Vertex;

struct Renderer::Impl {
  Impl(Context& context, const RenderSettings& s) : gl(context.gl()), settings(s) {
    if (s.width < 1 || s.height < 1) {
      throw std::invalid_argument("render size must be at least 1x1, got " +
                                  std::to_string(s.width) + "x" + std::to_string(s.height));
    }
    try {
      create();
    } catch (...) {
      destroy();
      throw;
    }
  }
  ~Impl() { destroy(); }

  void create();
  void destroy() noexcept;
  void destroy_drawable(Drawable& d) noexcept;
  Drawable& find(ObjectKey key);

  const GlTable& gl;
  RenderSettings settings;
  Camera camera;
  Light light;
  detail::DrawableTable table;

  detail::SceneTarget target;
  GLuint empty_vao = 0;  // core profile draws nothing without a bound vertex array
  detail::SkyPass sky;
  detail::ShadowPass shadow;
  detail::MeshPass meshes;
  detail::ParticlePass particles;
  detail::PostPass post;
  detail::MotionBlur blur;  // made when settings.shutter_deg > 0
  Camera shown_camera;      // the camera of the last rendered frame
  bool camera_shown = false;

  void draw_opaque(const detail::FrameView& frame, const detail::ShadowView& shadow);
};

void Renderer::Impl::create() {
  while (gl.GetError() != GL_NO_ERROR) {
  }
  GLint max_samples = 0;
  gl.GetIntegerv(GL_MAX_SAMPLES, &max_samples);
  int samples = settings.msaa_samples > 1 ? std::min(settings.msaa_samples, int(max_samples)) : 0;
  if (samples < 2) samples = 0;

  target.create(gl, settings.width, settings.height, samples);
  sky.create(gl, settings, samples);
  shadow.create(gl, settings);
  gl.GenVertexArrays(1, &empty_vao);
  meshes.create(gl);
  particles.create(gl);
  post.create(gl, settings, empty_vao);
  if (settings.shutter_deg > 0.f) blur.create(gl, settings.width, settings.height);
  detail::check_error(gl, "creating the renderer's framebuffers and buffers");
}

void Renderer::Impl::destroy_drawable(Drawable& d) noexcept {
  detail::destroy_mesh(gl, d.mesh);
  for (Drawable::Part& part : d.parts) {
    if (part.texture != 0) gl.DeleteTextures(1, &part.texture);
    part.texture = 0;
  }
}

void Renderer::Impl::destroy() noexcept {
  for (auto& [key, d] : table.by_key) destroy_drawable(d);
  table.by_key.clear();
  table.order.clear();
  blur.destroy();
  post.destroy();
  particles.destroy();
  meshes.destroy();
  shadow.destroy();
  sky.destroy();
  if (empty_vao != 0) gl.DeleteVertexArrays(1, &empty_vao);
  empty_vao = 0;
  target.destroy();
}

Drawable& Renderer::Impl::find(ObjectKey key) {
  auto it = table.by_key.find(key);
  if (it == table.by_key.end()) {
    throw std::out_of_range("renderer: no drawable under key " + std::to_string(key));
  }
  return it->second;
}

// ---------------------------------------------------------------------------------------------
// Frame

/// Sky, then the meshes (planes, boxes, meshes, cloth) into the scene target with depth.
void Renderer::Impl::draw_opaque(const detail::FrameView& frame, const detail::ShadowView& shadow) {
  gl.Viewport(0, 0, settings.width, settings.height);
  sky.draw(frame, table, target.draw_fbo(), empty_vao);
  gl.BindFramebuffer(GL_FRAMEBUFFER, target.draw_fbo());
  gl.DepthMask(GL_TRUE);
  gl.Clear(GL_DEPTH_BUFFER_BIT);
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_LESS);
  gl.ActiveTexture(GL_TEXTURE1);
  gl.BindTexture(GL_TEXTURE_2D, shadow.texture);
  // Unit 3 holds the scene depth for soft particles; until it is copied, bind the copy anyway
  // (a sampler must not see the depth buffer being written).
  gl.ActiveTexture(GL_TEXTURE3);
  gl.BindTexture(GL_TEXTURE_2D, target.depth_copy_texture());
  meshes.draw(frame, shadow, table);
}

namespace {

detail::FrameView frame_view(const RenderSettings& settings, const Camera& cam, const Light& light) {
  detail::FrameView frame{settings, cam, light};
  frame.view = detail::look_at(cam.position, cam.target, cam.up);
  frame.proj = detail::perspective(cam.fov_deg * std::numbers::pi_v<float> / 180.f,
                                   float(settings.width) / float(settings.height), cam.near_m, cam.far_m);
  return frame;
}

Mat3f slerp(const Mat3f& a, const Mat3f& b, float s) {
  const Eigen::Quaternionf qa(a);
  const Eigen::Quaternionf qb(b);
  return qa.slerp(s, qb).toRotationMatrix();
}

}  // namespace

Image Renderer::render() {
  Impl& r = *impl_;
  const GlTable& gl = r.gl;
  const Camera& cam = r.camera;
  const detail::FrameView frame = frame_view(r.settings, cam, r.light);

  gl.Disable(GL_BLEND);
  gl.Disable(GL_CULL_FACE);
  gl.CullFace(GL_BACK);
  r.particles.gather(r.table, cam, r.settings.height);
  auto draw_shadow = [&](const detail::FrameView& f) -> const detail::ShadowView& {
    return r.shadow.draw(f, r.table, r.meshes.cube(), r.particles.soft(), r.particles.droplets());
  };

  // The shutter: moving meshes and a moving camera are drawn at sub-frame instants
  // s in (1 - shutter/360, 1] between the last frame's pose (s = 0) and this one's (s = 1).
  bool moved = false;
  if (r.settings.shutter_deg > 0.f) {
    const auto& c0 = r.shown_camera;
    moved = r.camera_shown && (c0.position != cam.position || c0.target != cam.target ||
                               c0.fov_deg != cam.fov_deg || c0.up != cam.up);
    r.table.for_each([&](const Drawable& d) {
      moved |= d.kind != DrawableKind::particles && d.shown &&
               (d.shown_translation != d.translation || d.shown_rotation != d.rotation);
    });
  }
  const detail::ShadowView* shadow = nullptr;
  if (!moved) {
    shadow = &draw_shadow(frame);
    r.draw_opaque(frame, *shadow);
  } else {
    const int n = std::clamp(r.settings.shutter_samples, 2, 64);
    const float open = std::min(r.settings.shutter_deg, 360.f) / 360.f;
    // The poses at s = 1, put back after the sub-frames.
    std::vector<std::pair<Vec3f, Mat3f>> poses;
    poses.reserve(r.table.order.size());
    r.table.for_each([&](const Drawable& d) { poses.emplace_back(d.translation, d.rotation); });
    r.blur.begin();
    for (int k = 0; k < n; ++k) {
      // Evenly spaced, the last one at s = 1: its depth is what the particles test against.
      const float s = 1.f - open * float(n - 1 - k) / float(n);
      const bool last = k == n - 1;  // exactly this frame's poses
      std::size_t i = 0;
      for (const ObjectKey key : r.table.order) {
        Drawable& d = r.table.by_key.at(key);
        const auto& [t1, r1] = poses[i++];
        if (d.kind == DrawableKind::particles || !d.shown) continue;
        d.translation = last ? t1 : Vec3f(d.shown_translation + s * (t1 - d.shown_translation));
        d.rotation = last ? r1 : slerp(d.shown_rotation, r1, s);
      }
      Camera sub = cam;
      if (r.camera_shown && !last) {
        const Camera& c0 = r.shown_camera;
        sub.position = c0.position + s * (cam.position - c0.position);
        sub.target = c0.target + s * (cam.target - c0.target);
        sub.up = c0.up + s * (cam.up - c0.up);
        sub.fov_deg = c0.fov_deg + s * (cam.fov_deg - c0.fov_deg);
      }
      // Shadows move with their casters: the shadow map is fitted and drawn per instant; the
      // last one (this frame's poses) is what the particles use.
      const detail::FrameView sub_frame = frame_view(r.settings, sub, r.light);
      shadow = &draw_shadow(sub_frame);
      r.draw_opaque(sub_frame, *shadow);
      r.target.resolve();
      r.blur.add(r.target.resolve_texture(), 1.f / float(n), r.empty_vao);
    }
    std::size_t i = 0;
    for (const ObjectKey key : r.table.order) {
      Drawable& d = r.table.by_key.at(key);
      std::tie(d.translation, d.rotation) = poses[i++];
    }
    r.blur.end(r.target.draw_fbo(), r.empty_vao);
    gl.Enable(GL_DEPTH_TEST);
    gl.DepthFunc(GL_LESS);
    gl.ActiveTexture(GL_TEXTURE1);
    gl.BindTexture(GL_TEXTURE_2D, shadow->texture);
    gl.ActiveTexture(GL_TEXTURE3);
    gl.BindTexture(GL_TEXTURE_2D, r.target.depth_copy_texture());
  }
  r.particles.draw_droplets(frame, *shadow, r.target.samples());
  bool opaque_drawables = false;
  r.table.for_each([&](const Drawable& d) { opaque_drawables |= d.kind != DrawableKind::particles; });
  if (!r.particles.draw_blended(frame, *shadow, r.target, opaque_drawables)) r.target.resolve();
  r.post.draw(r.target.resolve_texture(), r.empty_vao);
  Image image = r.post.read_back();
  detail::check_error(gl, "drawing a frame");

  for (auto& [key, d] : r.table.by_key) {
    d.shown_translation = d.translation;
    d.shown_rotation = d.rotation;
    d.shown = true;
  }
  r.shown_camera = cam;
  r.camera_shown = true;
  return image;
}

// ---------------------------------------------------------------------------------------------
// Drawable table

Renderer::Renderer(Context& context, const RenderSettings& settings)
    : impl_(std::make_unique<Impl>(context, settings)) {}

Renderer::~Renderer() = default;

void Renderer::set_camera(const Camera& camera) {
  if (!(camera.fov_deg > 0.f && camera.fov_deg < 180.f)) {
    std::ostringstream m;  // (std::to_string's fixed decimals print 1e-9 as 0.000000)
    m << "camera fov_deg must be in (0, 180), got " << camera.fov_deg;
    throw std::invalid_argument(m.str());
  }
  if (!(camera.near_m > 0.f && camera.far_m > camera.near_m)) {
    throw std::invalid_argument("camera clip distances need 0 < near_m < far_m");
  }
  if ((camera.target - camera.position).squaredNorm() <= 0.f) {
    throw std::invalid_argument("camera target coincides with its position");
  }
  impl_->camera = camera;
}

void Renderer::set_light(const Light& light) { impl_->light = light; }

void Renderer::add_plane(ObjectKey key, const PlaneDesc& desc) {
  if (!(desc.half_size > 0.f) || desc.normal.squaredNorm() <= 0.f) {
    throw std::invalid_argument("plane needs half_size > 0 and a non-zero normal");
  }
  const GlTable& gl = impl_->gl;
  Drawable& d = impl_->table.add(key, DrawableKind::plane);
  d.plane = desc;
  const Vec3f n = desc.normal.normalized();
  const Vec3f u = detail::any_perpendicular(n);
  const Vec3f v = n.cross(u);
  const float h = desc.half_size;
  std::vector<Vertex> vertices;
  for (const auto& [a, b] : {std::pair{-h, -h}, {h, -h}, {h, h}, {-h, h}}) {
    const Vec3f p = desc.point + a * u + b * v;
    vertices.push_back(Vertex{{p.x(), p.y(), p.z()}, {n.x(), n.y(), n.z()}, {a, b}});
  }
  d.mesh = detail::upload_mesh(gl, vertices, {0, 1, 2, 0, 2, 3});
}

void Renderer::add_box(ObjectKey key, const BoxDesc& desc) {
  if (!(desc.half_extents.minCoeff() > 0.f)) {
    throw std::invalid_argument("box half_extents must be positive");
  }
  Drawable& d = impl_->table.add(key, DrawableKind::box);
  d.half_extents = desc.half_extents;
  d.color = desc.color;
}

namespace {

/// Checks a texture before any GL object is made, and returns it as RGBA8 rows bottom to top
/// (GL's order: uv (0, 0) is the image's bottom-left corner).
std::vector<std::uint8_t> texture_rows(const Material& m, int& width, int& height) {
  Image image;
  if (!m.texture_rgba.empty()) {
    if (m.texture_width < 1 || m.texture_height < 1 ||
        m.texture_rgba.size() != std::size_t(m.texture_width) * std::size_t(m.texture_height) * 4) {
      throw std::invalid_argument("mesh texture_rgba must hold texture_width x texture_height x 4 bytes");
    }
    image.width = m.texture_width;
    image.height = m.texture_height;
    image.rgba = m.texture_rgba;
  } else if (!m.texture_path.empty()) {
    image = read_image(m.texture_path);  // IoError names the file
  } else {
    return {};
  }
  width = image.width;
  height = image.height;
  const std::size_t row = std::size_t(width) * 4;
  std::vector<std::uint8_t> rows(image.rgba.size());
  for (int y = 0; y < height; ++y) {
    std::memcpy(&rows[std::size_t(height - 1 - y) * row], &image.rgba[std::size_t(y) * row], row);
  }
  return rows;
}

void fill_vertices(std::vector<Vertex>& out, std::span<const float> positions,
                   std::span<const float> normals) {
  const std::size_t n = positions.size() / 3;
  for (std::size_t i = 0; i < n; ++i) {
    std::memcpy(out[i].p, &positions[3 * i], 3 * sizeof(float));
    std::memcpy(out[i].n, &normals[3 * i], 3 * sizeof(float));
  }
}

}  // namespace

void Renderer::add_mesh(ObjectKey key, const MeshDesc& desc) {
  const std::size_t n = desc.positions.size() / 3;
  if (n == 0 || desc.positions.size() % 3 != 0) {
    throw std::invalid_argument("mesh positions must be n x 3 floats with n >= 1");
  }
  if (!desc.normals.empty() && desc.normals.size() != desc.positions.size()) {
    throw std::invalid_argument("mesh normals must be empty or n x 3 floats like the positions");
  }
  if (!desc.uvs.empty() && desc.uvs.size() != 2 * n) {
    throw std::invalid_argument("mesh uvs must be empty or n x 2 floats");
  }
  if (desc.indices.empty() || desc.indices.size() % 3 != 0) {
    throw std::invalid_argument("mesh indices must be m x 3 with m >= 1");
  }
  for (const std::uint32_t i : desc.indices) {
    if (i >= n) {
      throw std::invalid_argument("mesh index " + std::to_string(i) + " >= vertex count " +
                                  std::to_string(n));
    }
  }
  if (impl_->table.by_key.count(key) != 0) {
    throw std::invalid_argument("renderer: key " + std::to_string(key) + " is already used");
  }
  const std::size_t triangles = desc.indices.size() / 3;
  std::size_t next = 0;
  for (const MeshPart& part : desc.parts) {
    if (part.first_triangle != next || part.triangle_count == 0 || part.triangle_count > triangles - next) {
      throw std::invalid_argument("mesh parts must tile the " + std::to_string(triangles) +
                                  " triangles in order; a part at triangle " +
                                  std::to_string(part.first_triangle) + " with " +
                                  std::to_string(part.triangle_count) + " triangles follows triangle " +
                                  std::to_string(next));
    }
    next += part.triangle_count;
  }
  if (!desc.parts.empty() && next != triangles) {
    throw std::invalid_argument("mesh parts cover " + std::to_string(next) + " of the " +
                                std::to_string(triangles) + " triangles");
  }
  // Every texture is read and checked before any GL object is made.
  std::vector<MeshPart> parts = desc.parts;
  if (parts.empty()) parts.push_back({0, std::uint32_t(triangles), desc.material});
  struct Rows {
    std::vector<std::uint8_t> rgba;
    int width = 0, height = 0;
  };
  std::vector<Rows> tex(parts.size());
  for (std::size_t k = 0; k < parts.size(); ++k) tex[k].rgba = texture_rows(parts[k].material, tex[k].width, tex[k].height);

  std::vector<float> normals = desc.normals;
  if (normals.empty()) {
    normals.resize(desc.positions.size());
    compute_vertex_normals(desc.positions, desc.indices, normals);
  }
  const GlTable& gl = impl_->gl;
  Drawable& d = impl_->table.add(key, DrawableKind::mesh);
  d.dynamic = desc.dynamic;
  d.vertices.assign(n, Vertex{});
  fill_vertices(d.vertices, desc.positions, normals);
  for (std::size_t i = 0; i < n && !desc.uvs.empty(); ++i) {
    d.vertices[i].uv[0] = desc.uvs[2 * i];
    d.vertices[i].uv[1] = desc.uvs[2 * i + 1];
  }
  for (const Vertex& v : d.vertices) d.local_bounds.extend(Vec3f(v.p[0], v.p[1], v.p[2]));
  d.indices = desc.indices;
  d.mesh = detail::upload_mesh(gl, d.vertices, d.indices, desc.dynamic ? GL_DYNAMIC_DRAW : GL_STATIC_DRAW);
  d.parts.resize(parts.size());
  for (std::size_t k = 0; k < parts.size(); ++k) {
    Drawable::Part& part = d.parts[k];
    part.first_index = GLsizei(3 * parts[k].first_triangle);
    part.index_count = GLsizei(3 * parts[k].triangle_count);
    part.material = std::move(parts[k].material);
    part.material.texture_rgba.clear();  // uploaded below; no second copy kept
    if (tex[k].rgba.empty()) continue;
    gl.GenTextures(1, &part.texture);
    gl.BindTexture(GL_TEXTURE_2D, part.texture);
    gl.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
    // sRGB storage: the sampler returns linear colours, as the shading expects.
    gl.TexImage2D(GL_TEXTURE_2D, 0, GL_SRGB8_ALPHA8, tex[k].width, tex[k].height, 0, GL_RGBA,
                  GL_UNSIGNED_BYTE, tex[k].rgba.data());
    gl.GenerateMipmap(GL_TEXTURE_2D);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
  }
  detail::check_error(gl, "adding a mesh");
}

void Renderer::update_mesh(ObjectKey key, std::span<const float> positions,
                           std::span<const float> normals) {
  Drawable& d = impl_->find(key);
  if (d.kind != DrawableKind::mesh) {
    throw std::invalid_argument("renderer: key " + std::to_string(key) + " is not a mesh");
  }
  const std::size_t count = d.vertices.size();
  if (positions.size() != 3 * count) {
    throw std::invalid_argument("update_mesh: expected " + std::to_string(count) +
                                " x 3 positions, got " + std::to_string(positions.size()) + " floats");
  }
  if (!normals.empty() && normals.size() != positions.size()) {
    throw std::invalid_argument("update_mesh: normals must be empty or as many as the positions");
  }
  std::vector<float> computed;
  if (normals.empty()) {
    computed.resize(positions.size());
    compute_vertex_normals(positions, d.indices, computed);
    normals = computed;
  }
  fill_vertices(d.vertices, positions, normals);
  d.local_bounds.setEmpty();
  for (const Vertex& v : d.vertices) d.local_bounds.extend(Vec3f(v.p[0], v.p[1], v.p[2]));
  const GlTable& gl = impl_->gl;
  gl.BindBuffer(GL_ARRAY_BUFFER, d.mesh.vbo);
  gl.BufferSubData(GL_ARRAY_BUFFER, 0, GLsizeiptr(count * sizeof(Vertex)), d.vertices.data());
}

void Renderer::set_transform(ObjectKey key, const Vec3f& translation, const Mat3f& rotation) {
  Drawable& d = impl_->find(key);
  if (d.kind == DrawableKind::particles) {
    throw std::invalid_argument("renderer: key " + std::to_string(key) +
                                " holds particles, which are given in the world frame");
  }
  d.translation = translation;
  d.rotation = rotation;
}

void Renderer::set_particles(ObjectKey key, const ParticleBatch& batch) {
  if (batch.count > 0 &&
      (batch.position == nullptr || batch.color == nullptr || batch.radius == nullptr)) {
    throw std::invalid_argument("renderer: particle batch with count > 0 has a null array");
  }
  if (!(batch.streak_s >= 0.f)) {
    throw std::invalid_argument("renderer: particle batch streak_s must be >= 0 s");
  }
  if (!(batch.trail_s >= 0.f) || !(batch.emissive >= 0.f)) {
    throw std::invalid_argument("renderer: particle batch trail_s and emissive must be >= 0");
  }
  if (!(batch.strobe_hz >= 0.f) || !(batch.strobe_duty > 0.f && batch.strobe_duty <= 1.f)) {
    throw std::invalid_argument("renderer: particle batch strobe_hz must be >= 0 and strobe_duty in (0, 1]");
  }
  if (batch.count > 0 && batch.age != nullptr && batch.lifetime == nullptr) {
    throw std::invalid_argument("renderer: particle batch has ages but no lifetimes");
  }
  auto it = impl_->table.by_key.find(key);
  Drawable* d = nullptr;
  if (it == impl_->table.by_key.end()) {
    d = &impl_->table.add(key, DrawableKind::particles);
  } else if (it->second.kind != DrawableKind::particles) {
    throw std::invalid_argument("renderer: key " + std::to_string(key) + " is a mesh, not particles");
  } else {
    d = &it->second;
  }
  d->style = batch.style;
  d->particle_texture = batch.texture;
  const bool additive = batch.style == ParticleStyle::additive;
  d->trail = additive && batch.trail_s > 0.f && batch.velocity != nullptr;
  const bool streak = batch.style == ParticleStyle::streak || d->trail;
  const float streak_s = d->trail ? batch.trail_s : batch.streak_s;
  const bool flame = additive && batch.texture == ParticleTexture::flame;
  const bool textured = batch.texture != ParticleTexture::none;
  const std::size_t floats = streak ? detail::kStreakFloats : detail::kInstanceFloats;
  d->instances.resize(batch.count * floats);  // keeps its capacity when shrinking
  float* out = d->instances.data();
  for (std::size_t i = 0; i < batch.count; ++i, out += floats) {
    std::memcpy(out, batch.position + 3 * i, 3 * sizeof(float));
    out[3] = batch.radius[i];
    std::memcpy(out + 4, batch.color + 4 * i, 4 * sizeof(float));
    float param = -1.f;
    if (textured || flame) {
      const float age = batch.age != nullptr ? batch.age[i] : 0.f;
      const float life = batch.lifetime != nullptr ? batch.lifetime[i] : 0.f;
      const float age01 = life > 0.f ? std::clamp(age / life, 0.f, 1.f) : 0.f;
      const float rnd = detail::particle_random(batch.id != nullptr ? batch.id[i] : std::uint64_t(i));
      param = std::floor(age01 * 1023.f) + std::floor(rnd * 4096.f) / 4096.f;
      if (flame) detail::flame_color(age01, age, rnd, out + 4);
    }
    if (additive) {
      float gain = batch.emissive;
      if (batch.strobe_hz > 0.f) {
        const float age = batch.age != nullptr ? batch.age[i] : 0.f;
        const float rnd = detail::particle_random(batch.id != nullptr ? batch.id[i] : std::uint64_t(i));
        gain *= detail::strobe(age, rnd, batch.strobe_hz, batch.strobe_duty);
      }
      for (int k = 4; k < 7; ++k) out[k] *= gain;
    }
    if (streak) {
      // The tail trails behind the head, against the velocity.
      for (int k = 0; k < 3; ++k) {
        out[8 + k] = batch.velocity != nullptr ? -batch.velocity[3 * i + k] * streak_s : 0.f;
      }
      out[11] = param;
    } else {
      out[8] = param;
    }
  }
}

void Renderer::remove(ObjectKey key) {
  auto it = impl_->table.by_key.find(key);
  if (it == impl_->table.by_key.end()) return;
  impl_->destroy_drawable(it->second);
  impl_->table.by_key.erase(it);
  auto& order = impl_->table.order;
  order.erase(std::lower_bound(order.begin(), order.end(), key));
}

void Renderer::apply(const SceneList& list) {
  for (const SceneList::Added& a : list.added) {
    if (const auto* plane = std::get_if<PlaneDesc>(&a.desc)) add_plane(a.key, *plane);
    else if (const auto* box = std::get_if<BoxDesc>(&a.desc)) add_box(a.key, *box);
    else add_mesh(a.key, std::get<MeshDesc>(a.desc));
    if (a.has_transform) set_transform(a.key, a.translation, a.rotation);
  }
  for (const SceneList::Moved& m : list.moved) set_transform(m.key, m.translation, m.rotation);
  for (const ObjectKey key : list.removed) remove(key);
  for (const SceneList::Particles& p : list.particles) set_particles(p.key, p.batch);
  for (const SceneList::MeshVertices& m : list.meshes) update_mesh(m.key, m.positions, m.normals);
  if (list.camera) set_camera(*list.camera);
}

const RenderSettings& Renderer::settings() const { return impl_->settings; }

}  // namespace simreel::render
