#include "simreel/render/context.hpp"

#include <stdexcept>
#include <string>

#include "context_backends.hpp"

namespace simreel::render {

Backend parse_backend(const std::string& name) {
  if (name == "osmesa") return Backend::osmesa;
  if (name == "egl") return Backend::egl;
  throw std::invalid_argument("unknown render backend \"" + name + "\" (expected osmesa or egl)");
}

namespace {
std::string gl_string(const GlTable& gl, GLenum name) {
  const GLubyte* s = gl.GetString(name);
  return s != nullptr ? std::string(reinterpret_cast<const char*>(s)) : std::string();
}
}  // namespace

std::string Context::renderer_string() const { return gl_string(gl(), GL_RENDERER); }
std::string Context::version_string() const { return gl_string(gl(), GL_VERSION); }

std::unique_ptr<Context> create_context(Backend backend) {
  switch (backend) {
    case Backend::osmesa: return detail::create_osmesa_context();
    case Backend::egl: return detail::create_egl_context();
  }
  throw std::invalid_argument("unknown render backend");
}

}  // namespace simreel::render
