// GLSL program compile + link (gl/program.hpp).
#include "program.hpp"

#include <algorithm>
#include <utility>

#include "simreel/render/context.hpp"

namespace simreel::render::detail {

std::string glsl_source(std::initializer_list<const char*> parts) {
  std::string s = kGlslVersion;
  for (const char* p : parts) s += p;
  return s;
}

Program::Program(const GlTable& gl, const char* name, const std::string& vs, const std::string& fs)
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

Program::~Program() {
  if (id_ != 0) gl_->DeleteProgram(id_);
}

Program& Program::operator=(Program&& o) noexcept {
  std::swap(gl_, o.gl_);
  std::swap(id_, o.id_);
  std::swap(locations_, o.locations_);
  return *this;
}

GLuint Program::compile(GLenum type, const char* name, const char* stage, const std::string& source) {
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

GLint Program::loc(const char* name) const {
  auto it = locations_.find(name);
  if (it == locations_.end()) {
    it = locations_.emplace(name, gl_->GetUniformLocation(id_, name)).first;
  }
  return it->second;
}

}  // namespace simreel::render::detail
