#pragma once
// Private: a linked GLSL program with cached uniform locations, and the source assembly every
// pass uses (the version line, then shared GLSL pieces, then the stage's own code).

#include <initializer_list>
#include <string>
#include <unordered_map>
#include <utility>

#include <Eigen/Core>

#include "simreel/render/gl_table.hpp"

namespace simreel::render::detail {

inline constexpr char kGlslVersion[] = "#version 330 core\n";

/// kGlslVersion followed by `parts` in order.
std::string glsl_source(std::initializer_list<const char*> parts);

/// A vertex + fragment program. Move-only; deletes its GL program on destruction.
class Program {
 public:
  Program() = default;
  /// Compiles and links. @throws ContextError "renderer: cannot compile the <name> <stage>
  /// shader: <log>" or "... cannot link the <name> shader: <log>".
  Program(const GlTable& gl, const char* name, const std::string& vs, const std::string& fs);
  ~Program();
  Program(const Program&) = delete;
  Program& operator=(const Program&) = delete;
  Program(Program&& o) noexcept { *this = std::move(o); }
  Program& operator=(Program&& o) noexcept;

  [[nodiscard]] bool valid() const { return id_ != 0; }
  void use() const { gl_->UseProgram(id_); }
  void set(const char* name, int v) const { gl_->Uniform1i(loc(name), v); }
  void set(const char* name, float v) const { gl_->Uniform1f(loc(name), v); }
  void set(const char* name, float x, float y) const { gl_->Uniform2f(loc(name), x, y); }
  void set(const char* name, const Eigen::Vector3f& v) const {
    gl_->Uniform3f(loc(name), v.x(), v.y(), v.z());
  }
  void set(const char* name, const Eigen::Vector4f& v) const {
    gl_->Uniform4f(loc(name), v.x(), v.y(), v.z(), v.w());
  }
  void set(const char* name, const Eigen::Matrix3f& m) const {
    gl_->UniformMatrix3fv(loc(name), 1, GL_FALSE, m.data());
  }
  void set(const char* name, const Eigen::Matrix4f& m) const {
    gl_->UniformMatrix4fv(loc(name), 1, GL_FALSE, m.data());
  }

 private:
  GLuint compile(GLenum type, const char* name, const char* stage, const std::string& source);
  GLint loc(const char* name) const;

  const GlTable* gl_ = nullptr;
  GLuint id_ = 0;
  // Uniforms a shader does not use report -1, which GL ignores on upload. Keyed by the
  // literal's address: no string is built per upload.
  mutable std::unordered_map<const char*, GLint> locations_;
};

}  // namespace simreel::render::detail
