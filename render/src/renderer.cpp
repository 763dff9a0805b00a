#include "simreel/render/renderer.hpp"
#include "simreel/render/scene_list.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "shaders.hpp"

namespace simreel::render {

namespace {

using Mat4f = Eigen::Matrix4f;

constexpr int kShadowMapSize = 2048;
constexpr std::size_t kInstanceFloats = 8;   // centre xyz, radius, colour rgba
constexpr std::size_t kStreakFloats = 12;    // the same, then head-to-tail offset xyz, padding

// ---------------------------------------------------------------------------------------------
// Matrices (column-major, OpenGL clip conventions)

Vec3f any_perpendicular(const Vec3f& n) {
  const Vec3f ref = std::abs(n.x()) < 0.9f ? Vec3f::UnitX() : Vec3f::UnitY();
  return (ref - n * n.dot(ref)).normalized();
}

Mat4f look_at(const Vec3f& eye, const Vec3f& target, const Vec3f& up) {
  const Vec3f f = (target - eye).normalized();
  Vec3f s = f.cross(up);
  if (s.squaredNorm() < 1e-12f) s = f.cross(any_perpendicular(f));  // looking along `up`
  s.normalize();
  const Vec3f u = s.cross(f);
  Mat4f m = Mat4f::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m;
}

Mat4f perspective(float fovy_rad, float aspect, float near_m, float far_m) {
  const float t = 1.f / std::tan(0.5f * fovy_rad);
  Mat4f m = Mat4f::Zero();
  m(0, 0) = t / aspect;
  m(1, 1) = t;
  m(2, 2) = (far_m + near_m) / (near_m - far_m);
  m(2, 3) = 2.f * far_m * near_m / (near_m - far_m);
  m(3, 2) = -1.f;
  return m;
}

Mat4f ortho(float half_w, float half_h, float near_m, float far_m) {
  Mat4f m = Mat4f::Identity();
  m(0, 0) = 1.f / half_w;
  m(1, 1) = 1.f / half_h;
  m(2, 2) = -2.f / (far_m - near_m);
  m(2, 3) = -(far_m + near_m) / (far_m - near_m);
  return m;
}

Mat4f affine(const Mat3f& linear, const Vec3f& translation) {
  Mat4f m = Mat4f::Identity();
  m.block<3, 3>(0, 0) = linear;
  m.block<3, 1>(0, 3) = translation;
  return m;
}

// ---------------------------------------------------------------------------------------------
// Shader programs

class Program {
 public:
  Program() = default;
  Program(const GlTable& gl, const char* name, const std::string& vs, const std::string& fs)
      : gl_(&gl) {
    const GLuint v = compile(GL_VERTEX_SHADER, name, "vertex", vs);
    GLuint f = 0;
    try {
      f = compile(GL_FRAGMENT_SHADER, name, "fragment", fs);
    } catch (...) {
      gl.DeleteShader(v);
      throw;
    }
    id_ = gl.CreateProgram();
    gl.AttachShader(id_, v);
    gl.AttachShader(id_, f);
    gl.LinkProgram(id_);
    gl.DeleteShader(v);
    gl.DeleteShader(f);
    GLint ok = GL_FALSE;
    gl.GetProgramiv(id_, GL_LINK_STATUS, &ok);
    if (ok != GL_TRUE) {
      GLint length = 0;
      gl.GetProgramiv(id_, GL_INFO_LOG_LENGTH, &length);
      std::string log(std::size_t(std::max(length, 1)), '\0');
      gl.GetProgramInfoLog(id_, GLsizei(log.size()), nullptr, log.data());
      gl.DeleteProgram(id_);
      id_ = 0;
      throw ContextError(std::string("renderer: cannot link the ") + name + " shader: " +
                         log.c_str());
    }
  }
  ~Program() {
    if (id_ != 0) gl_->DeleteProgram(id_);
  }
  Program(const Program&) = delete;
  Program& operator=(const Program&) = delete;
  Program(Program&& o) noexcept { *this = std::move(o); }
  Program& operator=(Program&& o) noexcept {
    std::swap(gl_, o.gl_);
    std::swap(id_, o.id_);
    std::swap(locations_, o.locations_);
    return *this;
  }

  [[nodiscard]] bool valid() const { return id_ != 0; }
  void use() const { gl_->UseProgram(id_); }
  void set(const char* name, int v) const { gl_->Uniform1i(loc(name), v); }
  void set(const char* name, float v) const { gl_->Uniform1f(loc(name), v); }
  void set(const char* name, float x, float y) const { gl_->Uniform2f(loc(name), x, y); }
  void set(const char* name, const Vec3f& v) const { gl_->Uniform3f(loc(name), v.x(), v.y(), v.z()); }
  void set(const char* name, const Vec4f& v) const {
    gl_->Uniform4f(loc(name), v.x(), v.y(), v.z(), v.w());
  }
  void set(const char* name, const Mat3f& m) const {
    gl_->UniformMatrix3fv(loc(name), 1, GL_FALSE, m.data());
  }
  void set(const char* name, const Mat4f& m) const {
    gl_->UniformMatrix4fv(loc(name), 1, GL_FALSE, m.data());
  }

 private:
  GLuint compile(GLenum type, const char* name, const char* stage, const std::string& source) {
    const GLuint shader = gl_->CreateShader(type);
    const char* text = source.c_str();
    gl_->ShaderSource(shader, 1, &text, nullptr);
    gl_->CompileShader(shader);
    GLint ok = GL_FALSE;
    gl_->GetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (ok != GL_TRUE) {
      GLint length = 0;
      gl_->GetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
      std::string log(std::size_t(std::max(length, 1)), '\0');
      gl_->GetShaderInfoLog(shader, GLsizei(log.size()), nullptr, log.data());
      gl_->DeleteShader(shader);
      throw ContextError(std::string("renderer: cannot compile the ") + name + " " + stage +
                         " shader: " + log.c_str());
    }
    return shader;
  }

  // Uniforms a shader does not use report -1, which GL ignores on upload. Keyed by the
  // literal's address: no string is built per upload.
  GLint loc(const char* name) const {
    auto it = locations_.find(name);
    if (it == locations_.end()) {
      it = locations_.emplace(name, gl_->GetUniformLocation(id_, name)).first;
    }
    return it->second;
  }

  const GlTable* gl_ = nullptr;
  GLuint id_ = 0;
  mutable std::unordered_map<const char*, GLint> locations_;
};

std::string source(std::initializer_list<const char*> parts) {
  std::string s = detail::kGlslVersion;
  for (const char* p : parts) s += p;
  return s;
}

// ---------------------------------------------------------------------------------------------
// Geometry

/// Interleaved vertex: position (3), normal (3), plane coordinates in metres (2).
struct Vertex {
  float p[3];
  float n[3];
  float uv[2];
};

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

struct Mesh {
  GLuint vao = 0;
  GLuint vbo = 0;
  GLuint ebo = 0;
  GLsizei index_count = 0;
};

Mesh upload_mesh(const GlTable& gl, const std::vector<Vertex>& vertices,
                 const std::vector<GLuint>& indices, GLenum usage = GL_STATIC_DRAW) {
  Mesh m;
  gl.GenVertexArrays(1, &m.vao);
  gl.BindVertexArray(m.vao);
  gl.GenBuffers(1, &m.vbo);
  gl.BindBuffer(GL_ARRAY_BUFFER, m.vbo);
  gl.BufferData(GL_ARRAY_BUFFER, GLsizeiptr(vertices.size() * sizeof(Vertex)), vertices.data(), usage);
  gl.GenBuffers(1, &m.ebo);
  gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.ebo);
  gl.BufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(indices.size() * sizeof(GLuint)),
                indices.data(), GL_STATIC_DRAW);
  gl.EnableVertexAttribArray(0);
  gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                         reinterpret_cast<const void*>(offsetof(Vertex, p)));
  gl.EnableVertexAttribArray(1);
  gl.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                         reinterpret_cast<const void*>(offsetof(Vertex, n)));
  gl.EnableVertexAttribArray(2);
  gl.VertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                         reinterpret_cast<const void*>(offsetof(Vertex, uv)));
  gl.BindVertexArray(0);
  m.index_count = GLsizei(indices.size());
  return m;
}

void destroy_mesh(const GlTable& gl, Mesh& m) {
  if (m.vao != 0) gl.DeleteVertexArrays(1, &m.vao);
  if (m.vbo != 0) gl.DeleteBuffers(1, &m.vbo);
  if (m.ebo != 0) gl.DeleteBuffers(1, &m.ebo);
  m = Mesh{};
}

/// One particle stream: a growing vertex buffer of quads (four vertices per particle).
struct ParticleStream {
  std::size_t floats = kInstanceFloats;  // per instance
  GLuint vao = 0;
  GLuint instances = 0;
  std::size_t capacity = 0;  // particles the GL buffer holds
  std::vector<float> staging;   // per particle
  std::vector<float> expanded;  // per vertex: four copies of each particle
  std::size_t count = 0;
};

const char* framebuffer_status_name(GLenum status) {
  switch (status) {
    case GL_FRAMEBUFFER_UNDEFINED: return "GL_FRAMEBUFFER_UNDEFINED";
    case GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT: return "GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT";
    case GL_FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT:
      return "GL_FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT";
    case GL_FRAMEBUFFER_INCOMPLETE_DRAW_BUFFER: return "GL_FRAMEBUFFER_INCOMPLETE_DRAW_BUFFER";
    case GL_FRAMEBUFFER_INCOMPLETE_READ_BUFFER: return "GL_FRAMEBUFFER_INCOMPLETE_READ_BUFFER";
    case GL_FRAMEBUFFER_UNSUPPORTED: return "GL_FRAMEBUFFER_UNSUPPORTED";
    case GL_FRAMEBUFFER_INCOMPLETE_MULTISAMPLE: return "GL_FRAMEBUFFER_INCOMPLETE_MULTISAMPLE";
    default: return "unknown status";
  }
}

std::string hex(unsigned v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%04x", v);
  return buf;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

struct Renderer::Impl {
  enum class Kind { plane, box, mesh, particles };

  struct Drawable {
    Kind kind = Kind::box;
    Vec3f translation = Vec3f::Zero();
    Mat3f rotation = Mat3f::Identity();
    Vec4f color = Vec4f::Ones();
    Vec3f half_extents = Vec3f::Ones();  // box
    PlaneDesc plane;                     // plane
    Mesh mesh;                           // plane and mesh (boxes share the unit cube)
    // Mesh: material, texture, vertex data kept for update_mesh, local bounds for the shadow fit.
    Material material;
    GLuint texture = 0;
    std::vector<Vertex> vertices;  // CPU copy for update_mesh (keeps the UVs)
    std::vector<std::uint32_t> indices;
    Eigen::AlignedBox3f local_bounds;
    bool dynamic = false;
    std::vector<float> instances;  // particles, kInstanceFloats (kStreakFloats for streaks) each
    ParticleStyle style = ParticleStyle::soft;
  };

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
  void check_framebuffer(const char* what) const;
  void check_error(const char* stage) const;
  Drawable& add(ObjectKey key, Kind kind);

  void gather_particles();
  void draw_shadow_map();
  void draw_meshes();
  void draw_droplets();
  void draw_sky();
  void copy_scene_depth();
  void draw_particles();
  void set_particle_uniforms(const Program& p) const;
  void sort_back_to_front(std::size_t n);
  void upload_stream(ParticleStream& stream, const std::uint32_t* order = nullptr);
  Image read_back();

  const GlTable& gl;
  RenderSettings settings;
  Camera camera;
  Light light;
  int samples = 0;  // 0: no multisampling

  // Scene target: multisampled half-float colour + depth, resolved into `resolve_tex`.
  GLuint msaa_fbo = 0, msaa_color = 0, msaa_depth = 0;
  GLuint resolve_fbo = 0, resolve_tex = 0, resolve_depth = 0;
  // A single-sample copy of the opaque depth that soft particles read (a texture cannot be
  // sampled while it is the depth attachment being tested against).
  GLuint depth_fbo = 0, depth_tex = 0;
  // The sky gradient, drawn once into a target like the scene's and copied into the scene
  // target each frame: a same-format copy costs a fraction of shading the gradient again, and
  // the samples are the very values the sky pass wrote (the settings never change).
  GLuint sky_fbo = 0, sky_color = 0;
  bool sky_drawn = false;
  // depth_tex holds the cleared depth (1) everywhere: what a copy gives when no opaque object
  // was drawn, so such frames skip the copy (a multisample depth resolve) after the first.
  bool depth_copy_clear = false;
  // Tone-mapped 8-bit output that is read back.
  GLuint out_fbo = 0, out_color = 0;
  // The tone map for every half-float value (kToneLutFs), 256 x 256 floats, made once.
  GLuint tone_lut_tex = 0;
  GLuint shadow_fbo = 0, shadow_tex = 0;
  GLuint empty_vao = 0, quad_ebo = 0;
  std::size_t quad_capacity = 0;  // particles quad_ebo indexes
  Mesh cube;
  ParticleStream soft, additive, droplets, streaks;

  Program sky_program, lit_program, depth_program, particle_depth_program, post_program;
  // Particle programs by style and by sun taps per vertex (0: no shadow map this frame, 1, or
  // 4 with particle casters), compiled on first use: llvmpipe runs a vertex shader's texture
  // lookups even when a uniform branch skips them, so each variant samples only what it needs.
  enum ParticleProgram { soft_pp, additive_pp, droplet_pp, streak_pp };
  Program particle_programs[4][3];
  const Program& particle_program(ParticleProgram which);

  std::unordered_map<ObjectKey, Drawable> drawables;
  // Keys in increasing order, so drawing (and merging particle batches) is deterministic.
  std::vector<ObjectKey> order;

  // Per-frame values.
  Mat4f view = Mat4f::Identity();
  Mat4f proj = Mat4f::Identity();
  Mat4f light_view_proj = Mat4f::Identity();
  Vec3f light_right = Vec3f::UnitX(), light_up = Vec3f::UnitY();
  bool shadow_enabled = false;
  float shadow_bias = 0.f, shadow_offset = 0.f, shadow_radius = 0.f;
  std::vector<float> sort_depth;
  std::vector<std::uint32_t> sort_index, sort_scratch;
  std::vector<std::uint32_t> sort_key, sort_key_scratch;
};

void Renderer::Impl::check_framebuffer(const char* what) const {
  const GLenum status = gl.CheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    throw ContextError(std::string("renderer: the ") + what + " framebuffer (" +
                       std::to_string(settings.width) + "x" + std::to_string(settings.height) +
                       ") is incomplete: " + framebuffer_status_name(status));
  }
}

void Renderer::Impl::check_error(const char* stage) const {
  const GLenum error = gl.GetError();
  if (error != GL_NO_ERROR) {
    throw ContextError(std::string("renderer: OpenGL error ") + hex(error) + " while " + stage);
  }
}

void Renderer::Impl::create() {
  const int w = settings.width;
  const int h = settings.height;
  while (gl.GetError() != GL_NO_ERROR) {
  }

  using namespace detail;
  sky_program = Program(gl, "sky", source({kFullscreenVs}), source({kSkyGlsl, kSkyFs}));
  lit_program = Program(gl, "lit mesh", source({kLitVs}),
                        source({kSkyGlsl, kShadowGlsl, kAmbientGlsl, kLitFs}));
  depth_program = Program(gl, "shadow depth", source({kDepthVs}), source({kDepthFs}));
  particle_depth_program = Program(gl, "particle shadow depth", source({kParticleDepthVs}),
                                   source({kParticleDepthFs}));
  post_program = Program(gl, "tone map", source({kFullscreenVs}),
                         source({kPackingExtension, kPostFs}));

  GLint max_samples = 0;
  gl.GetIntegerv(GL_MAX_SAMPLES, &max_samples);
  samples = settings.msaa_samples > 1 ? std::min(settings.msaa_samples, int(max_samples)) : 0;
  if (samples < 2) samples = 0;

  auto texture_2d = [&](GLuint& tex, GLint internal, GLenum format, GLenum type, GLint filter) {
    gl.GenTextures(1, &tex);
    gl.BindTexture(GL_TEXTURE_2D, tex);
    gl.TexImage2D(GL_TEXTURE_2D, 0, internal, w, h, 0, format, type, nullptr);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  };

  // Resolve target (also the scene target without multisampling).
  texture_2d(resolve_tex, GL_RGBA16F, GL_RGBA, GL_FLOAT, GL_NEAREST);
  gl.GenFramebuffers(1, &resolve_fbo);
  gl.BindFramebuffer(GL_FRAMEBUFFER, resolve_fbo);
  gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, resolve_tex, 0);
  if (samples == 0) {
    gl.GenRenderbuffers(1, &resolve_depth);
    gl.BindRenderbuffer(GL_RENDERBUFFER, resolve_depth);
    gl.RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, resolve_depth);
  }
  check_framebuffer("resolve");

  texture_2d(depth_tex, GL_DEPTH_COMPONENT24, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, GL_NEAREST);
  gl.GenFramebuffers(1, &depth_fbo);
  gl.BindFramebuffer(GL_FRAMEBUFFER, depth_fbo);
  gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, depth_tex, 0);
  gl.DrawBuffer(GL_NONE);
  gl.ReadBuffer(GL_NONE);
  check_framebuffer("scene depth copy");

  if (samples > 0) {
    gl.GenRenderbuffers(1, &msaa_color);
    gl.BindRenderbuffer(GL_RENDERBUFFER, msaa_color);
    gl.RenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA16F, w, h);
    gl.GenRenderbuffers(1, &msaa_depth);
    gl.BindRenderbuffer(GL_RENDERBUFFER, msaa_depth);
    gl.RenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, w, h);
    gl.GenFramebuffers(1, &msaa_fbo);
    gl.BindFramebuffer(GL_FRAMEBUFFER, msaa_fbo);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, msaa_color);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, msaa_depth);
    check_framebuffer("multisampled scene");
  }

  gl.GenRenderbuffers(1, &sky_color);
  gl.BindRenderbuffer(GL_RENDERBUFFER, sky_color);
  if (samples > 0) {
    gl.RenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA16F, w, h);
  } else {
    gl.RenderbufferStorage(GL_RENDERBUFFER, GL_RGBA16F, w, h);
  }
  gl.GenFramebuffers(1, &sky_fbo);
  gl.BindFramebuffer(GL_FRAMEBUFFER, sky_fbo);
  gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, sky_color);
  check_framebuffer("sky");

  gl.GenRenderbuffers(1, &out_color);
  gl.BindRenderbuffer(GL_RENDERBUFFER, out_color);
  gl.RenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
  gl.GenFramebuffers(1, &out_fbo);
  gl.BindFramebuffer(GL_FRAMEBUFFER, out_fbo);
  gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, out_color);
  check_framebuffer("RGBA8 output");

  gl.GenTextures(1, &shadow_tex);
  gl.BindTexture(GL_TEXTURE_2D, shadow_tex);
  gl.TexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, kShadowMapSize, kShadowMapSize, 0,
                GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  gl.GenFramebuffers(1, &shadow_fbo);
  gl.BindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
  gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, shadow_tex, 0);
  gl.DrawBuffer(GL_NONE);
  gl.ReadBuffer(GL_NONE);
  check_framebuffer("shadow map");
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);

  // Core profile draws nothing without a bound vertex array, even with no attributes.
  gl.GenVertexArrays(1, &empty_vao);

  std::vector<Vertex> vertices;
  std::vector<GLuint> indices;
  unit_cube(vertices, indices);
  cube = upload_mesh(gl, vertices, indices);

  // Particles are drawn as indexed quads, four vertices per particle each carrying the
  // particle's data, not instanced: llvmpipe runs an instanced draw as one small draw per
  // instance, several times slower for 100k sprites. The index buffer is shared.
  gl.GenBuffers(1, &quad_ebo);
  streaks.floats = kStreakFloats;
  for (ParticleStream* stream : {&soft, &additive, &droplets, &streaks}) {
    gl.GenVertexArrays(1, &stream->vao);
    gl.BindVertexArray(stream->vao);
    gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, quad_ebo);
    gl.GenBuffers(1, &stream->instances);
    gl.BindBuffer(GL_ARRAY_BUFFER, stream->instances);
    const GLsizei stride = GLsizei(stream->floats * sizeof(float));
    for (GLuint attribute = 1; 4 * (attribute - 1) < stream->floats; ++attribute) {
      gl.EnableVertexAttribArray(attribute);
      gl.VertexAttribPointer(attribute, 4, GL_FLOAT, GL_FALSE, stride,
                             reinterpret_cast<const void*>(4 * (attribute - 1) * sizeof(float)));
    }
  }
  gl.BindVertexArray(0);
  gl.BindBuffer(GL_ARRAY_BUFFER, 0);

  {
    gl.GenTextures(1, &tone_lut_tex);
    gl.BindTexture(GL_TEXTURE_2D, tone_lut_tex);
    gl.TexImage2D(GL_TEXTURE_2D, 0, GL_R32F, 256, 256, 0, GL_RED, GL_FLOAT, nullptr);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    GLuint lut_fbo = 0;
    gl.GenFramebuffers(1, &lut_fbo);
    gl.BindFramebuffer(GL_FRAMEBUFFER, lut_fbo);
    gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tone_lut_tex, 0);
    const GLenum status = gl.CheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status == GL_FRAMEBUFFER_COMPLETE) {
      const Program lut(gl, "tone map table", source({kFullscreenVs}),
                        source({kPackingExtension, kToneMapGlsl, kToneLutFs}));
      lut.use();
      gl.Viewport(0, 0, 256, 256);
      gl.Disable(GL_DEPTH_TEST);
      gl.Disable(GL_BLEND);
      gl.BindVertexArray(empty_vao);
      gl.DrawArrays(GL_TRIANGLES, 0, 3);
      gl.BindVertexArray(0);
    }
    gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
    gl.DeleteFramebuffers(1, &lut_fbo);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
      throw ContextError(std::string("renderer: the tone map table framebuffer is incomplete: ") +
                         framebuffer_status_name(status));
    }
  }
  check_error("creating the renderer's framebuffers and buffers");
}

void Renderer::Impl::destroy_drawable(Drawable& d) noexcept {
  destroy_mesh(gl, d.mesh);
  if (d.texture != 0) gl.DeleteTextures(1, &d.texture);
  d.texture = 0;
}

void Renderer::Impl::destroy() noexcept {
  for (auto& [key, d] : drawables) destroy_drawable(d);
  drawables.clear();
  destroy_mesh(gl, cube);
  for (ParticleStream* stream : {&soft, &additive, &droplets, &streaks}) {
    if (stream->vao != 0) gl.DeleteVertexArrays(1, &stream->vao);
    if (stream->instances != 0) gl.DeleteBuffers(1, &stream->instances);
    *stream = ParticleStream{};
  }
  if (quad_ebo != 0) gl.DeleteBuffers(1, &quad_ebo);
  if (empty_vao != 0) gl.DeleteVertexArrays(1, &empty_vao);
  for (GLuint* fbo : {&msaa_fbo, &resolve_fbo, &out_fbo, &shadow_fbo, &depth_fbo, &sky_fbo}) {
    if (*fbo != 0) gl.DeleteFramebuffers(1, fbo);
  }
  for (GLuint* rb : {&msaa_color, &msaa_depth, &resolve_depth, &out_color, &sky_color}) {
    if (*rb != 0) gl.DeleteRenderbuffers(1, rb);
  }
  for (GLuint* tex : {&resolve_tex, &shadow_tex, &depth_tex, &tone_lut_tex}) {
    if (*tex != 0) gl.DeleteTextures(1, tex);
  }
  quad_ebo = empty_vao = 0;
  quad_capacity = 0;
  msaa_fbo = resolve_fbo = out_fbo = shadow_fbo = depth_fbo = sky_fbo = 0;
  msaa_color = msaa_depth = resolve_depth = out_color = sky_color = 0;
  sky_drawn = false;
  depth_copy_clear = false;
  resolve_tex = shadow_tex = depth_tex = tone_lut_tex = 0;
  for (Program* p : {&sky_program, &lit_program, &depth_program, &particle_depth_program, &post_program}) {
    *p = Program();
  }
  for (auto& by_taps : particle_programs) {
    for (Program& p : by_taps) p = Program();
  }
}

Renderer::Impl::Drawable& Renderer::Impl::add(ObjectKey key, Kind kind) {
  auto [it, inserted] = drawables.try_emplace(key);
  if (!inserted) {
    throw std::invalid_argument("renderer: key " + std::to_string(key) + " is already used");
  }
  it->second.kind = kind;
  order.insert(std::lower_bound(order.begin(), order.end(), key), key);
  return it->second;
}

// ---------------------------------------------------------------------------------------------
// Drawing

void Renderer::Impl::gather_particles() {
  // Soft particles of every batch are merged and sorted back to front, so two overlapping
  // batches blend correctly; additive ones, droplets (opaque) and thin streaks need no order.
  soft.staging.clear();  // unsorted; upload_stream takes the particles in sort_index order
  additive.staging.clear();
  droplets.staging.clear();
  streaks.staging.clear();
  for (const ObjectKey key : order) {
    const Drawable& d = drawables.at(key);
    if (d.kind != Kind::particles) continue;
    std::vector<float>* dst = &soft.staging;
    if (d.style == ParticleStyle::additive) dst = &additive.staging;
    if (d.style == ParticleStyle::droplet) dst = &droplets.staging;
    if (d.style == ParticleStyle::streak) dst = &streaks.staging;
    dst->insert(dst->end(), d.instances.begin(), d.instances.end());
  }

  const std::size_t n = soft.staging.size() / kInstanceFloats;
  if (n > 0) {
    const Vec3f forward = (camera.target - camera.position).normalized();
    sort_depth.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const float* c = &soft.staging[i * kInstanceFloats];
      sort_depth[i] = (Vec3f(c[0], c[1], c[2]) - camera.position).dot(forward);
    }
    sort_back_to_front(n);
  }
  upload_stream(soft, sort_index.data());
  for (ParticleStream* stream : {&additive, &droplets, &streaks}) upload_stream(*stream);
}

void Renderer::Impl::sort_back_to_front(std::size_t n) {
  // sort_index = particles by decreasing depth, equal depths in their given order: the order
  // std::stable_sort with `depth[a] > depth[b]` gives, found by a least-significant-digit
  // radix sort of the depths' bits (four passes of 8 bits, stable), several times faster for
  // 100k particles. NaN depths (no strict weak order) keep the comparison sort.
  sort_index.resize(n);
  for (std::size_t i = 0; i < n; ++i) sort_index[i] = std::uint32_t(i);
  bool has_nan = false;
  sort_key.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float d = sort_depth[i] + 0.f;  // -0 becomes +0: the comparison sees them equal
    has_nan |= d != d;
    std::uint32_t bits;
    std::memcpy(&bits, &d, sizeof bits);
    // Bits that increase with the float; inverted, so that far (large depth) comes first.
    const std::uint32_t ascending = (bits & 0x80000000u) != 0 ? ~bits : bits | 0x80000000u;
    sort_key[i] = ~ascending;
  }
  if (has_nan) {
    std::stable_sort(sort_index.begin(), sort_index.end(), [&](std::uint32_t a, std::uint32_t b) {
      return sort_depth[a] > sort_depth[b];
    });
    return;
  }
  sort_scratch.resize(n);
  sort_key_scratch.resize(n);
  for (int shift = 0; shift < 32; shift += 8) {
    std::size_t start[257] = {};
    for (std::size_t i = 0; i < n; ++i) ++start[((sort_key[i] >> shift) & 0xffu) + 1];
    if (start[((sort_key[0] >> shift) & 0xffu) + 1] == n) continue;  // one bucket: no change
    for (int b = 0; b < 256; ++b) start[b + 1] += start[b];
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t at = start[(sort_key[i] >> shift) & 0xffu]++;
      sort_scratch[at] = sort_index[i];
      sort_key_scratch[at] = sort_key[i];
    }
    sort_index.swap(sort_scratch);
    sort_key.swap(sort_key_scratch);
  }
}

void Renderer::Impl::draw_shadow_map() {
  // Fit an orthographic sun view around every caster: boxes, meshes and, if asked, particles.
  Eigen::AlignedBox3f bounds;
  for (const ObjectKey key : order) {
    const Drawable& d = drawables.at(key);
    if (d.kind == Kind::box) {
      for (int c = 0; c < 8; ++c) {
        const Vec3f corner((c & 1) ? 1.f : -1.f, (c & 2) ? 1.f : -1.f, (c & 4) ? 1.f : -1.f);
        bounds.extend(d.rotation * corner.cwiseProduct(d.half_extents) + d.translation);
      }
    } else if (d.kind == Kind::mesh && !d.local_bounds.isEmpty()) {
      for (int c = 0; c < 8; ++c) {
        bounds.extend(d.rotation * d.local_bounds.corner(Eigen::AlignedBox3f::CornerType(c)) +
                      d.translation);
      }
    } else if (d.kind == Kind::particles && settings.particle_shadows &&
               (d.style == ParticleStyle::soft || d.style == ParticleStyle::droplet)) {
      for (std::size_t i = 0; i < d.instances.size(); i += kInstanceFloats) {
        const Vec3f c(d.instances[i], d.instances[i + 1], d.instances[i + 2]);
        const float r = d.instances[i + 3];
        bounds.extend(c - Vec3f::Constant(r));
        bounds.extend(c + Vec3f::Constant(r));
      }
    }
  }
  shadow_enabled = !bounds.isEmpty() && bounds.diagonal().allFinite();
  if (!shadow_enabled) return;

  const Vec3f center = bounds.center();
  const float radius = std::max(0.5f * bounds.diagonal().norm() * 1.05f, 1e-3f);
  Vec3f dir = light.direction;
  dir = dir.squaredNorm() > 0.f ? dir.normalized() : Vec3f(0.f, 0.f, -1.f);
  const Vec3f eye = center - dir * (2.f * radius);
  const float far_m = 4.f * radius;
  const Mat4f light_view = look_at(eye, center, any_perpendicular(dir));
  light_view_proj = ortho(radius, radius, 0.f, far_m) * light_view;
  light_right = light_view.block<1, 3>(0, 0).transpose();
  light_up = light_view.block<1, 3>(1, 0).transpose();
  const float texel_m = 2.f * radius / float(kShadowMapSize);
  shadow_offset = 1.5f * texel_m;
  shadow_bias = 1.5f * texel_m / far_m;
  // A soft-edged sun: about 2 cm of penumbra at this scale, never sharper than two texels
  // (five with particle casters, whose stochastic texels the lookup must average away).
  const float min_texels = settings.particle_shadows ? 5.f : 2.f;
  shadow_radius = std::max(min_texels / float(kShadowMapSize), 0.02f / (2.f * radius));

  gl.BindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
  gl.Viewport(0, 0, kShadowMapSize, kShadowMapSize);
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_LESS);
  gl.DepthMask(GL_TRUE);
  gl.Clear(GL_DEPTH_BUFFER_BIT);
  gl.Enable(GL_POLYGON_OFFSET_FILL);
  gl.PolygonOffset(1.5f, 2.f);
  depth_program.use();
  depth_program.set("u_light_view_proj", light_view_proj);
  for (const ObjectKey key : order) {
    const Drawable& d = drawables.at(key);
    if (d.kind == Kind::box) {
      depth_program.set("u_model", affine(d.rotation * d.half_extents.asDiagonal(), d.translation));
      gl.BindVertexArray(cube.vao);
      gl.DrawElements(GL_TRIANGLES, cube.index_count, GL_UNSIGNED_INT, nullptr);
    } else if (d.kind == Kind::mesh) {
      depth_program.set("u_model", affine(d.rotation, d.translation));
      gl.BindVertexArray(d.mesh.vao);
      gl.DrawElements(GL_TRIANGLES, d.mesh.index_count, GL_UNSIGNED_INT, nullptr);
    }
  }
  if (settings.particle_shadows) {
    const Program& p = particle_depth_program;
    p.use();
    p.set("u_light_view_proj", light_view_proj);
    p.set("u_light_right", light_right);
    p.set("u_light_up", light_up);
    for (const ParticleStream* stream : {&soft, &droplets}) {
      if (stream->count == 0) continue;
      p.set("u_opaque", stream == &droplets ? 1 : 0);
      gl.BindVertexArray(stream->vao);
      gl.DrawElements(GL_TRIANGLES, GLsizei(6 * stream->count), GL_UNSIGNED_INT, nullptr);
    }
  }
  gl.Disable(GL_POLYGON_OFFSET_FILL);
}

void Renderer::Impl::draw_meshes() {
  const Program& p = lit_program;
  p.use();
  p.set("u_view_proj", Mat4f(proj * view));
  p.set("u_eye", camera.position);
  p.set("u_light_dir", light.direction.squaredNorm() > 0.f ? Vec3f(light.direction.normalized())
                                                           : Vec3f(0.f, 0.f, -1.f));
  p.set("u_light_color", light.color);
  p.set("u_ambient", light.ambient);
  p.set("u_ground_ambient", light.ground_ambient);
  const bool solid = settings.background == Background::solid;
  p.set("u_sky_top", solid ? settings.background_color : settings.sky_top);
  p.set("u_sky_bottom", solid ? settings.background_color : settings.sky_bottom);
  p.set("u_viewport", float(settings.width), float(settings.height));
  // Fog scales with how far the camera stands from what it looks at, so it reads the same in
  // a tabletop scene and a field.
  p.set("u_fog_distance", std::max(5.f * (camera.target - camera.position).norm(), 1e-3f));
  p.set("u_shadow_map", 1);
  p.set("u_texture", 2);
  p.set("u_shadow_enabled", shadow_enabled ? 1 : 0);
  p.set("u_light_view_proj", light_view_proj);
  p.set("u_shadow_bias", shadow_bias);
  p.set("u_shadow_offset", shadow_offset);
  p.set("u_shadow_radius", shadow_radius);
  p.set("u_has_texture", 0);

  for (const ObjectKey key : order) {
    const Drawable& d = drawables.at(key);
    if (d.kind == Kind::plane) {
      p.set("u_model", affine(d.rotation, d.translation));
      p.set("u_normal_matrix", d.rotation);
      p.set("u_color", d.plane.color);
      p.set("u_specular", 0.06f);
      p.set("u_checker_m", std::max(d.plane.checker_m, 0.f));
      p.set("u_half_size", std::max(d.plane.half_size, 1e-6f));
      gl.BindVertexArray(d.mesh.vao);
      gl.DrawElements(GL_TRIANGLES, d.mesh.index_count, GL_UNSIGNED_INT, nullptr);
    } else if (d.kind == Kind::box) {
      p.set("u_model", affine(d.rotation * d.half_extents.asDiagonal(), d.translation));
      p.set("u_normal_matrix", d.rotation);
      p.set("u_color", d.color);
      p.set("u_specular", 0.25f);
      p.set("u_checker_m", 0.f);
      p.set("u_half_size", 0.f);
      gl.BindVertexArray(cube.vao);
      gl.DrawElements(GL_TRIANGLES, cube.index_count, GL_UNSIGNED_INT, nullptr);
    } else if (d.kind == Kind::mesh) {
      p.set("u_model", affine(d.rotation, d.translation));
      p.set("u_normal_matrix", d.rotation);
      p.set("u_color", d.material.base_color);
      p.set("u_specular", std::clamp(d.material.specular, 0.f, 1.f));
      p.set("u_checker_m", std::max(d.material.checker_m, 0.f));
      p.set("u_half_size", 0.f);
      p.set("u_has_texture", d.texture != 0 ? 1 : 0);
      if (d.texture != 0) {
        gl.ActiveTexture(GL_TEXTURE2);
        gl.BindTexture(GL_TEXTURE_2D, d.texture);
      }
      if (!d.material.double_sided) gl.Enable(GL_CULL_FACE);
      gl.BindVertexArray(d.mesh.vao);
      gl.DrawElements(GL_TRIANGLES, d.mesh.index_count, GL_UNSIGNED_INT, nullptr);
      gl.Disable(GL_CULL_FACE);
      p.set("u_has_texture", 0);
    }
  }
}

void Renderer::Impl::upload_stream(ParticleStream& stream, const std::uint32_t* order) {
  stream.count = stream.staging.size() / stream.floats;
  if (stream.count == 0) return;
  if (stream.count > quad_capacity) {
    quad_capacity = std::max(stream.count, quad_capacity + quad_capacity / 2);
    std::vector<GLuint> indices(6 * quad_capacity);
    for (std::size_t i = 0; i < quad_capacity; ++i) {
      const auto base = GLuint(4 * i);
      const GLuint quad[6] = {base, base + 1, base + 2, base + 2, base + 1, base + 3};
      std::memcpy(&indices[6 * i], quad, sizeof quad);
    }
    gl.BindBuffer(GL_COPY_WRITE_BUFFER, quad_ebo);
    gl.BufferData(GL_COPY_WRITE_BUFFER, GLsizeiptr(indices.size() * sizeof(GLuint)), indices.data(),
                  GL_STATIC_DRAW);
  }
  // Four copies of each particle's data, one per corner (the shader derives the corner from
  // gl_VertexID).
  const std::size_t f = stream.floats;
  stream.expanded.resize(4 * stream.staging.size());
  float* dst = stream.expanded.data();
  for (std::size_t i = 0; i < stream.count; ++i) {
    const float* src = &stream.staging[(order != nullptr ? order[i] : i) * f];
    for (int k = 0; k < 4; ++k, dst += f) std::memcpy(dst, src, f * sizeof(float));
  }
  gl.BindBuffer(GL_ARRAY_BUFFER, stream.instances);
  const GLsizeiptr bytes = GLsizeiptr(stream.expanded.size() * sizeof(float));
  if (stream.count > stream.capacity) {
    stream.capacity = std::max(stream.count, stream.capacity + stream.capacity / 2);
    gl.BufferData(GL_ARRAY_BUFFER, GLsizeiptr(4 * stream.capacity * f * sizeof(float)), nullptr,
                  GL_STREAM_DRAW);
  }
  gl.BufferSubData(GL_ARRAY_BUFFER, 0, bytes, stream.expanded.data());
}

void Renderer::Impl::set_particle_uniforms(const Program& p) const {
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
  p.set("u_near", camera.near_m);
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
  p.set("u_depth_params", proj(2, 2), proj(2, 3));
  p.set("u_shadow_enabled", shadow_enabled ? 1 : 0);
  p.set("u_light_view_proj", light_view_proj);
  p.set("u_shadow_bias", shadow_bias);
  p.set("u_shadow_offset", 0.f);
  p.set("u_shadow_radius", shadow_radius);
}

const Program& Renderer::Impl::particle_program(ParticleProgram which) {
  const int variant = !shadow_enabled ? 0 : settings.particle_shadows ? 2 : 1;
  Program& p = particle_programs[which][variant];
  if (!p.valid()) {
    using namespace detail;
    // The fragment stages see SUN_TAPS too: without a shadow map v_sun is the constant 1.
    const char* taps = variant == 0 ? "#define SUN_TAPS 0\n" : variant == 1 ? "#define SUN_TAPS 1\n"
                                                                         : "#define SUN_TAPS 4\n";
    const std::string vs = which == streak_pp ? source({taps, kShadowGlsl, kStreakVs})
                                              : source({taps, kShadowGlsl, kParticleVs});
    switch (which) {
      case soft_pp:
        p = Program(gl, "soft particle", vs,
                    source({taps, kAmbientGlsl, kSceneDepthGlsl, kSphereDepthGlsl, kParticleSoftFs}));
        break;
      case additive_pp:
        p = Program(gl, "additive particle", vs,
                    source({taps, kAmbientGlsl, kSceneDepthGlsl, kSphereDepthGlsl, kParticleAddFs}));
        break;
      case droplet_pp:
        p = Program(gl, "droplet particle", vs,
                    source({taps, kAmbientGlsl, kSceneDepthGlsl, kSphereDepthGlsl, kParticleDropletFs}));
        break;
      case streak_pp:
        p = Program(gl, "streak particle", vs, source({taps, kAmbientGlsl, kSceneDepthGlsl, kStreakFs}));
        break;
    }
  }
  return p;
}

void Renderer::Impl::draw_droplets() {
  if (droplets.count == 0) return;
  // Opaque: drawn before the scene depth is copied, so soft particles fade against them too.
  const Program& program = particle_program(droplet_pp);
  set_particle_uniforms(program);
  program.set("u_opaque", 1);
  if (samples > 0) gl.Enable(GL_SAMPLE_ALPHA_TO_COVERAGE);
  gl.BindVertexArray(droplets.vao);
  gl.DrawElements(GL_TRIANGLES, GLsizei(6 * droplets.count), GL_UNSIGNED_INT, nullptr);
  gl.Disable(GL_SAMPLE_ALPHA_TO_COVERAGE);
}

void Renderer::Impl::draw_sky() {
  const int w = settings.width;
  const int h = settings.height;
  if (!sky_drawn) {
    gl.BindFramebuffer(GL_FRAMEBUFFER, sky_fbo);
    gl.Disable(GL_DEPTH_TEST);
    const bool solid = settings.background == Background::solid;
    sky_program.use();
    sky_program.set("u_sky_top", solid ? settings.background_color : settings.sky_top);
    sky_program.set("u_sky_bottom", solid ? settings.background_color : settings.sky_bottom);
    sky_program.set("u_viewport", float(w), float(h));
    gl.BindVertexArray(empty_vao);
    gl.DrawArrays(GL_TRIANGLES, 0, 3);
    sky_drawn = true;
  }
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, sky_fbo);
  gl.BindFramebuffer(GL_DRAW_FRAMEBUFFER, samples > 0 ? msaa_fbo : resolve_fbo);
  gl.BlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

void Renderer::Impl::copy_scene_depth() {
  const GLuint scene_fbo = samples > 0 ? msaa_fbo : resolve_fbo;
  bool opaque = droplets.count > 0;
  for (const ObjectKey key : order) opaque = opaque || drawables.at(key).kind != Kind::particles;
  if (opaque) {
    gl.BindFramebuffer(GL_READ_FRAMEBUFFER, scene_fbo);
    gl.BindFramebuffer(GL_DRAW_FRAMEBUFFER, depth_fbo);
    gl.BlitFramebuffer(0, 0, settings.width, settings.height, 0, 0, settings.width, settings.height,
                       GL_DEPTH_BUFFER_BIT, GL_NEAREST);
    depth_copy_clear = false;
  } else if (!depth_copy_clear) {
    gl.BindFramebuffer(GL_FRAMEBUFFER, depth_fbo);
    gl.DepthMask(GL_TRUE);
    gl.Clear(GL_DEPTH_BUFFER_BIT);  // the scene's clear depth, 1
    depth_copy_clear = true;
  }
  gl.BindFramebuffer(GL_FRAMEBUFFER, scene_fbo);
  gl.ActiveTexture(GL_TEXTURE3);
  gl.BindTexture(GL_TEXTURE_2D, depth_tex);
}

void Renderer::Impl::draw_particles() {
  if (soft.count == 0 && additive.count == 0 && streaks.count == 0) return;
  copy_scene_depth();
  gl.Enable(GL_BLEND);
  gl.DepthMask(GL_FALSE);
  struct Pass {
    const ParticleStream* stream;
    const Program* program;
    bool premultiplied;
  };
  for (const Pass& pass : {Pass{&soft, &particle_program(soft_pp), true},
                           Pass{&streaks, &particle_program(streak_pp), true},
                           Pass{&additive, &particle_program(additive_pp), false}}) {
    if (pass.stream->count == 0) continue;
    set_particle_uniforms(*pass.program);
    if (pass.premultiplied) {
      gl.BlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    } else {
      gl.BlendFunc(GL_ONE, GL_ONE);
    }
    gl.BindVertexArray(pass.stream->vao);
    gl.DrawElements(GL_TRIANGLES, GLsizei(6 * pass.stream->count), GL_UNSIGNED_INT, nullptr);
  }
  gl.DepthMask(GL_TRUE);
  gl.Disable(GL_BLEND);
}

Image Renderer::Impl::read_back() {
  const int w = settings.width;
  const int h = settings.height;
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, out_fbo);
  gl.ReadBuffer(GL_COLOR_ATTACHMENT0);
  gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  // The tone map pass wrote the rows upside down, so GL's bottom-to-top rows are the Image's
  // top-to-bottom ones: read straight into the image, no flip copy.
  Image image(w, h);
  gl.ReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, image.rgba.data());
  return image;
}

// ---------------------------------------------------------------------------------------------
// Public interface

Renderer::Renderer(Context& context, const RenderSettings& settings)
    : impl_(std::make_unique<Impl>(context, settings)) {}

Renderer::~Renderer() = default;

void Renderer::set_camera(const Camera& camera) {
  if (!(camera.fov_deg > 0.f && camera.fov_deg < 180.f)) {
    throw std::invalid_argument("camera fov_deg must be in (0, 180), got " +
                                std::to_string(camera.fov_deg));
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
  Impl::Drawable& d = impl_->add(key, Impl::Kind::plane);
  d.plane = desc;
  const Vec3f n = desc.normal.normalized();
  const Vec3f u = any_perpendicular(n);
  const Vec3f v = n.cross(u);
  const float h = desc.half_size;
  std::vector<Vertex> vertices;
  for (const auto& [a, b] : {std::pair{-h, -h}, {h, -h}, {h, h}, {-h, h}}) {
    const Vec3f p = desc.point + a * u + b * v;
    vertices.push_back(Vertex{{p.x(), p.y(), p.z()}, {n.x(), n.y(), n.z()}, {a, b}});
  }
  d.mesh = upload_mesh(gl, vertices, {0, 1, 2, 0, 2, 3});
}

void Renderer::add_box(ObjectKey key, const BoxDesc& desc) {
  if (!(desc.half_extents.minCoeff() > 0.f)) {
    throw std::invalid_argument("box half_extents must be positive");
  }
  Impl::Drawable& d = impl_->add(key, Impl::Kind::box);
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
  if (impl_->drawables.count(key) != 0) {
    throw std::invalid_argument("renderer: key " + std::to_string(key) + " is already used");
  }
  int tex_w = 0, tex_h = 0;
  const std::vector<std::uint8_t> tex = texture_rows(desc.material, tex_w, tex_h);

  std::vector<float> normals = desc.normals;
  if (normals.empty()) {
    normals.resize(desc.positions.size());
    compute_vertex_normals(desc.positions, desc.indices, normals);
  }
  const GlTable& gl = impl_->gl;
  Impl::Drawable& d = impl_->add(key, Impl::Kind::mesh);
  d.material = desc.material;
  d.material.texture_rgba.clear();  // uploaded below; no second copy kept
  d.dynamic = desc.dynamic;
  d.vertices.assign(n, Vertex{});
  fill_vertices(d.vertices, desc.positions, normals);
  for (std::size_t i = 0; i < n && !desc.uvs.empty(); ++i) {
    d.vertices[i].uv[0] = desc.uvs[2 * i];
    d.vertices[i].uv[1] = desc.uvs[2 * i + 1];
  }
  for (const Vertex& v : d.vertices) d.local_bounds.extend(Vec3f(v.p[0], v.p[1], v.p[2]));
  d.indices = desc.indices;
  d.mesh = upload_mesh(gl, d.vertices, d.indices, desc.dynamic ? GL_DYNAMIC_DRAW : GL_STATIC_DRAW);
  if (!tex.empty()) {
    gl.GenTextures(1, &d.texture);
    gl.BindTexture(GL_TEXTURE_2D, d.texture);
    gl.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
    // sRGB storage: the sampler returns linear colours, as the shading expects.
    gl.TexImage2D(GL_TEXTURE_2D, 0, GL_SRGB8_ALPHA8, tex_w, tex_h, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                  tex.data());
    gl.GenerateMipmap(GL_TEXTURE_2D);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
  }
  impl_->check_error("adding a mesh");
}

void Renderer::update_mesh(ObjectKey key, std::span<const float> positions,
                           std::span<const float> normals) {
  auto it = impl_->drawables.find(key);
  if (it == impl_->drawables.end()) {
    throw std::out_of_range("renderer: no drawable under key " + std::to_string(key));
  }
  Impl::Drawable& d = it->second;
  if (d.kind != Impl::Kind::mesh) {
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
  auto it = impl_->drawables.find(key);
  if (it == impl_->drawables.end()) {
    throw std::out_of_range("renderer: no drawable under key " + std::to_string(key));
  }
  if (it->second.kind == Impl::Kind::particles) {
    throw std::invalid_argument("renderer: key " + std::to_string(key) +
                                " holds particles, which are given in the world frame");
  }
  it->second.translation = translation;
  it->second.rotation = rotation;
}

void Renderer::set_particles(ObjectKey key, const ParticleBatch& batch) {
  if (batch.count > 0 &&
      (batch.position == nullptr || batch.color == nullptr || batch.radius == nullptr)) {
    throw std::invalid_argument("renderer: particle batch with count > 0 has a null array");
  }
  if (!(batch.streak_s >= 0.f)) {
    throw std::invalid_argument("renderer: particle batch streak_s must be >= 0 s");
  }
  auto it = impl_->drawables.find(key);
  Impl::Drawable* d = nullptr;
  if (it == impl_->drawables.end()) {
    d = &impl_->add(key, Impl::Kind::particles);
  } else if (it->second.kind != Impl::Kind::particles) {
    throw std::invalid_argument("renderer: key " + std::to_string(key) + " is a mesh, not particles");
  } else {
    d = &it->second;
  }
  d->style = batch.style;
  const bool streak = batch.style == ParticleStyle::streak;
  const std::size_t floats = streak ? kStreakFloats : kInstanceFloats;
  d->instances.resize(batch.count * floats);  // keeps its capacity when shrinking
  float* out = d->instances.data();
  for (std::size_t i = 0; i < batch.count; ++i, out += floats) {
    std::memcpy(out, batch.position + 3 * i, 3 * sizeof(float));
    out[3] = batch.radius[i];
    std::memcpy(out + 4, batch.color + 4 * i, 4 * sizeof(float));
    if (streak) {
      // The tail trails behind the head, against the velocity.
      for (int k = 0; k < 3; ++k) {
        out[8 + k] = batch.velocity != nullptr ? -batch.velocity[3 * i + k] * batch.streak_s : 0.f;
      }
      out[11] = 0.f;
    }
  }
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

void Renderer::remove(ObjectKey key) {
  auto it = impl_->drawables.find(key);
  if (it == impl_->drawables.end()) return;
  impl_->destroy_drawable(it->second);
  impl_->drawables.erase(it);
  auto& order = impl_->order;
  order.erase(std::lower_bound(order.begin(), order.end(), key));
}

const RenderSettings& Renderer::settings() const { return impl_->settings; }

Image Renderer::render() {
  Impl& r = *impl_;
  const GlTable& gl = r.gl;
  const int w = r.settings.width;
  const int h = r.settings.height;
  const Camera& cam = r.camera;
  r.view = look_at(cam.position, cam.target, cam.up);
  r.proj = perspective(cam.fov_deg * std::numbers::pi_v<float> / 180.f, float(w) / float(h),
                       cam.near_m, cam.far_m);

  gl.Disable(GL_BLEND);
  gl.Disable(GL_CULL_FACE);
  gl.CullFace(GL_BACK);
  r.gather_particles();
  r.draw_shadow_map();

  gl.Viewport(0, 0, w, h);
  r.draw_sky();
  gl.BindFramebuffer(GL_FRAMEBUFFER, r.samples > 0 ? r.msaa_fbo : r.resolve_fbo);
  gl.DepthMask(GL_TRUE);
  gl.Clear(GL_DEPTH_BUFFER_BIT);

  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_LESS);
  gl.ActiveTexture(GL_TEXTURE1);
  gl.BindTexture(GL_TEXTURE_2D, r.shadow_tex);
  // Unit 3 holds the scene depth for soft particles; until it is copied, bind the copy anyway
  // (a sampler must not see the depth buffer being written).
  gl.ActiveTexture(GL_TEXTURE3);
  gl.BindTexture(GL_TEXTURE_2D, r.depth_tex);
  r.draw_meshes();
  r.draw_droplets();
  r.draw_particles();

  if (r.samples > 0) {
    gl.BindFramebuffer(GL_READ_FRAMEBUFFER, r.msaa_fbo);
    gl.BindFramebuffer(GL_DRAW_FRAMEBUFFER, r.resolve_fbo);
    gl.BlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }

  gl.BindFramebuffer(GL_FRAMEBUFFER, r.out_fbo);
  gl.Disable(GL_DEPTH_TEST);
  gl.ActiveTexture(GL_TEXTURE0);
  gl.BindTexture(GL_TEXTURE_2D, r.resolve_tex);
  r.post_program.use();
  r.post_program.set("u_hdr", 0);
  r.post_program.set("u_tone_lut", 4);
  gl.ActiveTexture(GL_TEXTURE4);
  gl.BindTexture(GL_TEXTURE_2D, r.tone_lut_tex);
  gl.ActiveTexture(GL_TEXTURE0);
  r.post_program.set("u_height", float(h));
  gl.BindVertexArray(r.empty_vao);
  gl.DrawArrays(GL_TRIANGLES, 0, 3);
  gl.BindVertexArray(0);

  Image image = r.read_back();
  r.check_error("drawing a frame");
  return image;
}

}  // namespace simreel::render
