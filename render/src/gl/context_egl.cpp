// EGL surfaceless (EGL_PLATFORM_SURFACELESS_MESA): no window system, no pbuffer; uses a GPU
// render node where one exists and falls back to llvmpipe otherwise.
#include <GL/glcorearb.h>  // before any EGL/GL header, see gl_table.hpp

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <string>

#include "context_backends.hpp"

namespace simreel::render::detail {
namespace {

const char* egl_error_name(EGLint code) {
  switch (code) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
    default: {
      static thread_local char buf[32];
      std::snprintf(buf, sizeof buf, "EGL error 0x%04x", static_cast<unsigned>(code));
      return buf;
    }
  }
}

[[noreturn]] void fail(const std::string& what) {
  throw ContextError("egl: " + what + " failed (" + egl_error_name(eglGetError()) + ")");
}

void* egl_proc(const char* name) { return reinterpret_cast<void*>(eglGetProcAddress(name)); }

bool has_extension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    const bool starts = p == list || p[-1] == ' ';
    const bool ends = p[n] == ' ' || p[n] == '\0';
    if (starts && ends) return true;
  }
  return false;
}

// EGL hands out one display per platform and device, so two contexts share it; eglTerminate
// would pull it from under the other one. Count the users and terminate with the last.
std::mutex display_mutex;
int display_users = 0;

class EglContext final : public Context {
 public:
  EglContext() {
    const char* client_extensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!has_extension(client_extensions, "EGL_MESA_platform_surfaceless")) {
      throw ContextError("egl: EGL_MESA_platform_surfaceless is not supported by this EGL");
    }
    auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (get_platform_display == nullptr) {
      throw ContextError("egl: eglGetPlatformDisplayEXT is not available");
    }
    display_ = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (display_ == EGL_NO_DISPLAY) fail("eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA)");
    try {
      create();
    } catch (...) {
      release();
      throw;
    }
  }
  ~EglContext() override { release(); }
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  [[nodiscard]] const GlTable& gl() const override { return table_; }
  [[nodiscard]] std::string backend_name() const override { return "egl"; }

 private:
  void create() {
    EGLint major = 0;
    EGLint minor = 0;
    {
      const std::lock_guard lock(display_mutex);
      if (eglInitialize(display_, &major, &minor) == EGL_FALSE) fail("eglInitialize");
      ++display_users;
      initialized_ = true;
    }
    if (eglBindAPI(EGL_OPENGL_API) == EGL_FALSE) fail("eglBindAPI(EGL_OPENGL_API)");

    const char* extensions = eglQueryString(display_, EGL_EXTENSIONS);
    if (!has_extension(extensions, "EGL_KHR_surfaceless_context")) {
      throw ContextError("egl: EGL_KHR_surfaceless_context is not supported by this display");
    }
    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (!has_extension(extensions, "EGL_KHR_no_config_context")) {
      const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
      EGLint count = 0;
      if (eglChooseConfig(display_, config_attribs, &config, 1, &count) == EGL_FALSE) {
        fail("eglChooseConfig");
      }
      if (count < 1) throw ContextError("egl: no EGLConfig supports desktop OpenGL");
    }
    const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3,
                                      EGL_CONTEXT_MINOR_VERSION, 3,
                                      EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                      EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                      EGL_NONE};
    context_ = eglCreateContext(display_, config, EGL_NO_CONTEXT, context_attribs);
    if (context_ == EGL_NO_CONTEXT) fail("eglCreateContext(OpenGL 3.3 core)");
    if (eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_) == EGL_FALSE) {
      fail("eglMakeCurrent(surfaceless)");
    }
    try {
      table_.load(&egl_proc);
    } catch (const std::exception& e) {
      throw ContextError(std::string("egl: ") + e.what());
    }
  }

  void release() noexcept {
    if (display_ == EGL_NO_DISPLAY) return;
    if (context_ != EGL_NO_CONTEXT) {
      if (eglGetCurrentContext() == context_) {
        eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      }
      eglDestroyContext(display_, context_);
      context_ = EGL_NO_CONTEXT;
    }
    if (initialized_) {
      const std::lock_guard lock(display_mutex);
      if (--display_users == 0) eglTerminate(display_);
    }
    eglReleaseThread();
    display_ = EGL_NO_DISPLAY;
  }

  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
  bool initialized_ = false;
  GlTable table_;
};

}  // namespace

std::unique_ptr<Context> create_egl_context() { return std::make_unique<EglContext>(); }

}  // namespace simreel::render::detail
