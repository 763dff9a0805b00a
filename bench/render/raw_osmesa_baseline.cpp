// Baseline for the renderer's cost: the plainest OSMesa program that draws what simreel's
// particle frame draws — 100k instanced, alpha-blended round sprites at 1280x720 with 4x MSAA,
// instance data uploaded every frame, resolved and read back to memory every frame. No
// simreel code. Usage: raw_osmesa_baseline [particles] [frames] [msaa]
// (optional 4th and 5th arguments: width height). Prints the median frame time; bench_render reports simreel's time as a ratio of it.
#include <GL/glcorearb.h>  // before osmesa.h

#include <GL/osmesa.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "bench_particle_cloud.hpp"

namespace {

#define GL_FUNCTIONS(X)                                                                          \
  X(PFNGLCREATESHADERPROC, CreateShader) X(PFNGLSHADERSOURCEPROC, ShaderSource)                  \
  X(PFNGLCOMPILESHADERPROC, CompileShader) X(PFNGLCREATEPROGRAMPROC, CreateProgram)              \
  X(PFNGLATTACHSHADERPROC, AttachShader) X(PFNGLLINKPROGRAMPROC, LinkProgram)                    \
  X(PFNGLUSEPROGRAMPROC, UseProgram) X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)          \
  X(PFNGLUNIFORMMATRIX4FVPROC, UniformMatrix4fv) X(PFNGLUNIFORM1FPROC, Uniform1f)                \
  X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays) X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)      \
  X(PFNGLGENBUFFERSPROC, GenBuffers) X(PFNGLBINDBUFFERPROC, BindBuffer)                          \
  X(PFNGLBUFFERDATAPROC, BufferData) X(PFNGLBUFFERSUBDATAPROC, BufferSubData)                    \
  X(PFNGLENABLEVERTEXATTRIBARRAYPROC, EnableVertexAttribArray)                                   \
  X(PFNGLVERTEXATTRIBPOINTERPROC, VertexAttribPointer)                                           \
  X(PFNGLVERTEXATTRIBDIVISORPROC, VertexAttribDivisor)                                           \
  X(PFNGLDRAWARRAYSINSTANCEDPROC, DrawArraysInstanced)                                           \
  X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers) X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)      \
  X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers) X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer)  \
  X(PFNGLRENDERBUFFERSTORAGEMULTISAMPLEPROC, RenderbufferStorageMultisample)                     \
  X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer)                                   \
  X(PFNGLBLITFRAMEBUFFERPROC, BlitFramebuffer) X(PFNGLREADPIXELSPROC, ReadPixels)                \
  X(PFNGLVIEWPORTPROC, Viewport) X(PFNGLCLEARCOLORPROC, ClearColor) X(PFNGLCLEARPROC, Clear)     \
  X(PFNGLENABLEPROC, Enable) X(PFNGLDISABLEPROC, Disable) X(PFNGLBLENDFUNCPROC, BlendFunc)       \
  X(PFNGLDEPTHMASKPROC, DepthMask) X(PFNGLFINISHPROC, Finish) X(PFNGLGETERRORPROC, GetError)     \
  X(PFNGLREADBUFFERPROC, ReadBuffer)
// Own names: gl.h (pulled in by osmesa.h) already declares the GL 1.x functions.
namespace g {
#define DECLARE(type, name) type name = nullptr;
GL_FUNCTIONS(DECLARE)
}  // namespace g

const char* kVs = R"(#version 330 core
layout(location = 0) in vec2 a_corner;
layout(location = 1) in vec4 a_center_radius;
layout(location = 2) in vec4 a_color;
uniform mat4 u_view;
uniform mat4 u_proj;
out vec2 v_corner;
out vec4 v_color;
void main() {
  vec4 c = u_view * vec4(a_center_radius.xyz, 1.0);
  c.xy += a_corner * a_center_radius.w;
  v_corner = a_corner;
  v_color = a_color;
  gl_Position = u_proj * c;
})";
const char* kFs = R"(#version 330 core
in vec2 v_corner;
in vec4 v_color;
out vec4 o_color;
void main() {
  float r2 = dot(v_corner, v_corner);
  if (r2 >= 1.0) discard;
  float a = v_color.a * (1.0 - smoothstep(0.8, 1.0, sqrt(r2)));
  float shade = 0.6 + 0.4 * sqrt(1.0 - r2);
  o_color = vec4(v_color.rgb * shade * a, a);
})";

// Column-major 4x4 matrices, as simreel's renderer builds them for its default camera.
void look_at(float* m, const float eye[3], const float at[3]) {
  float f[3] = {at[0] - eye[0], at[1] - eye[1], at[2] - eye[2]};
  const float fl = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  for (float& v : f) v /= fl;
  float s[3] = {f[1] * 1.f - f[2] * 0.f, f[2] * 0.f - f[0] * 1.f, 0.f};  // f x (0, 0, 1)
  const float sl = std::sqrt(s[0] * s[0] + s[1] * s[1]);
  s[0] /= sl, s[1] /= sl;
  const float u[3] = {s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0]};
  const float rows[3][3] = {{s[0], s[1], s[2]}, {u[0], u[1], u[2]}, {-f[0], -f[1], -f[2]}};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m[c * 4 + r] = rows[r][c];
    m[12 + r] = -(rows[r][0] * eye[0] + rows[r][1] * eye[1] + rows[r][2] * eye[2]);
    m[r * 4 + 3] = 0.f;
  }
  m[15] = 1.f;
}

void perspective(float* m, float fovy_rad, float aspect, float n, float f) {
  std::fill(m, m + 16, 0.f);
  const float t = 1.f / std::tan(0.5f * fovy_rad);
  m[0] = t / aspect;
  m[5] = t;
  m[10] = (f + n) / (n - f);
  m[14] = 2.f * f * n / (n - f);
  m[11] = -1.f;
}

}  // namespace

int main(int argc, char** argv) {
  const std::size_t n = argc > 1 ? std::size_t(std::atol(argv[1])) : 100000;
  const int frames = argc > 2 ? std::atoi(argv[2]) : 30;
  const int samples = argc > 3 ? std::atoi(argv[3]) : 4;
  const int w = argc > 4 ? std::atoi(argv[4]) : 1280;
  const int h = argc > 5 ? std::atoi(argv[5]) : 720;

  const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 0, OSMESA_PROFILE,
                         OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, 3,
                         OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
  OSMesaContext ctx = OSMesaCreateContextAttribs(attribs, nullptr);
  static unsigned char dummy[4 * 4 * 4];
  if (ctx == nullptr || !OSMesaMakeCurrent(ctx, dummy, GL_UNSIGNED_BYTE, 4, 4)) {
    std::fprintf(stderr, "no OSMesa context\n");
    return 1;
  }
#define LOAD(type, name) g::name = reinterpret_cast<type>(OSMesaGetProcAddress("gl" #name));
  GL_FUNCTIONS(LOAD)

  auto shader = [](GLenum type, const char* src) {
    const GLuint s = g::CreateShader(type);
    g::ShaderSource(s, 1, &src, nullptr);
    g::CompileShader(s);
    return s;
  };
  const GLuint program = g::CreateProgram();
  g::AttachShader(program, shader(GL_VERTEX_SHADER, kVs));
  g::AttachShader(program, shader(GL_FRAGMENT_SHADER, kFs));
  g::LinkProgram(program);

  GLuint fbo[2], rb[3];
  g::GenFramebuffers(2, fbo);
  g::GenRenderbuffers(3, rb);
  g::BindRenderbuffer(GL_RENDERBUFFER, rb[0]);
  g::RenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, w, h);
  g::BindRenderbuffer(GL_RENDERBUFFER, rb[1]);
  g::RenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, w, h);
  g::BindFramebuffer(GL_FRAMEBUFFER, fbo[0]);
  g::FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
  g::FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
  g::BindRenderbuffer(GL_RENDERBUFFER, rb[2]);
  g::RenderbufferStorageMultisample(GL_RENDERBUFFER, 0, GL_RGBA8, w, h);
  g::BindFramebuffer(GL_FRAMEBUFFER, fbo[1]);
  g::FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[2]);

  const bench::ParticleCloud cloud = bench::make_particle_cloud(n);
  std::vector<float> instances(8 * n);
  for (std::size_t i = 0; i < n; ++i) {
    std::copy_n(&cloud.position[3 * i], 3, &instances[8 * i]);
    instances[8 * i + 3] = cloud.radius[i];
    std::copy_n(&cloud.color[4 * i], 4, &instances[8 * i + 4]);
  }
  GLuint vao, quad, inst;
  g::GenVertexArrays(1, &vao);
  g::BindVertexArray(vao);
  const float corners[] = {-1.f, -1.f, 1.f, -1.f, -1.f, 1.f, 1.f, 1.f};
  g::GenBuffers(1, &quad);
  g::BindBuffer(GL_ARRAY_BUFFER, quad);
  g::BufferData(GL_ARRAY_BUFFER, sizeof corners, corners, GL_STATIC_DRAW);
  g::EnableVertexAttribArray(0);
  g::VertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
  g::GenBuffers(1, &inst);
  g::BindBuffer(GL_ARRAY_BUFFER, inst);
  g::BufferData(GL_ARRAY_BUFFER, GLsizeiptr(instances.size() * sizeof(float)), nullptr, GL_STREAM_DRAW);
  for (GLuint a = 1; a <= 2; ++a) {
    g::EnableVertexAttribArray(a);
    g::VertexAttribPointer(a, 4, GL_FLOAT, GL_FALSE, 8 * sizeof(float),
                          reinterpret_cast<const void*>((a - 1) * 4 * sizeof(float)));
    g::VertexAttribDivisor(a, 1);
  }

  float view[16], proj[16];
  const float eye[3] = {6.f, -6.f, 3.f}, at[3] = {0.f, 0.f, 0.5f};
  look_at(view, eye, at);
  perspective(proj, 40.f * 3.14159265f / 180.f, float(w) / float(h), 0.05f, 500.f);
  g::UseProgram(program);
  g::UniformMatrix4fv(g::GetUniformLocation(program, "u_view"), 1, GL_FALSE, view);
  g::UniformMatrix4fv(g::GetUniformLocation(program, "u_proj"), 1, GL_FALSE, proj);

  std::vector<unsigned char> pixels(std::size_t(w) * h * 4);
  std::vector<double> ms, wall;
  for (int f = 0; f < frames + 2; ++f) {
    const auto w0 = std::chrono::steady_clock::now();
    const std::clock_t t0 = std::clock();  // process CPU time, llvmpipe's threads included
    g::BindFramebuffer(GL_FRAMEBUFFER, fbo[0]);
    g::Viewport(0, 0, w, h);
    g::ClearColor(0.6f, 0.7f, 0.85f, 1.f);
    g::Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    g::Enable(GL_DEPTH_TEST);
    g::DepthMask(GL_FALSE);
    g::Enable(GL_BLEND);
    g::BlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    g::BindBuffer(GL_ARRAY_BUFFER, inst);
    g::BufferSubData(GL_ARRAY_BUFFER, 0, GLsizeiptr(instances.size() * sizeof(float)), instances.data());
    g::DrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, GLsizei(n));
    g::DepthMask(GL_TRUE);
    g::Disable(GL_BLEND);
    g::BindFramebuffer(GL_READ_FRAMEBUFFER, fbo[0]);
    g::BindFramebuffer(GL_DRAW_FRAMEBUFFER, fbo[1]);
    g::BlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    g::BindFramebuffer(GL_READ_FRAMEBUFFER, fbo[1]);
    g::ReadBuffer(GL_COLOR_ATTACHMENT0);
    g::ReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
    const std::clock_t t1 = std::clock();
    const auto w1 = std::chrono::steady_clock::now();
    if (f >= 2) {  // 2 warm-up frames
      ms.push_back(1000.0 * double(t1 - t0) / CLOCKS_PER_SEC);
      wall.push_back(std::chrono::duration<double, std::milli>(w1 - w0).count());
    }
  }
  std::sort(ms.begin(), ms.end());
  std::sort(wall.begin(), wall.end());
  const GLenum err = g::GetError();
  std::printf("raw_osmesa_baseline: %zu sprites %dx%d msaa %d: median %.2f ms CPU/frame (min %.2f, %d frames), %.2f ms wall%s\n",
              n, w, h, samples, ms[ms.size() / 2], ms.front(), frames, wall[wall.size() / 2],
              err ? " GL ERROR" : "");
  OSMesaDestroyContext(ctx);
  return err ? 1 : 0;
}
