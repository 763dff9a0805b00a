// EGL without a window system or pbuffer. A hardware EGLDevice (EGL_EXT_platform_device) is
// preferred: it names the GPU rather than leaving the choice to whichever vendor library glvnd
// asks first, and it is the platform NVIDIA documents for headless rendering (the 580 driver
// checked on an H100 offers Mesa's surfaceless one too). Without a hardware device, Mesa's
// EGL_PLATFORM_SURFACELESS_MESA is used: a GPU render node where one exists, llvmpipe otherwise.
// SIMREEL_EGL_DEVICE=<n> picks the n-th EGLDevice (0-based, as eglQueryDevicesEXT lists them),
// for a machine with several GPUs; SIMREEL_EGL_DEVICE=surfaceless forces Mesa's path.
#include <GL/glcorearb.h>  // before any EGL/GL header, see gl_table.hpp

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

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

// The display of the device SIMREEL_EGL_DEVICE names, else of the first hardware EGLDevice (one
// without EGL_MESA_device_software), else EGL_NO_DISPLAY. Throws when the variable names a device
// that does not exist, so a typo is not silently rendered on another device.
EGLDisplay device_display(const char* client_extensions) {
  const char* wanted = std::getenv("SIMREEL_EGL_DEVICE");
  const bool forced = wanted != nullptr && *wanted != '\0';
  if (forced && std::strcmp(wanted, "surfaceless") == 0) return EGL_NO_DISPLAY;
  if (!has_extension(client_extensions, "EGL_EXT_platform_device") ||
      !(has_extension(client_extensions, "EGL_EXT_device_enumeration") ||
        has_extension(client_extensions, "EGL_EXT_device_base"))) {
    if (forced) throw ContextError("egl: SIMREEL_EGL_DEVICE is set but this EGL cannot enumerate devices");
    return EGL_NO_DISPLAY;
  }
  auto query_devices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  auto query_device_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
      eglGetProcAddress("eglQueryDeviceStringEXT"));
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (query_devices == nullptr || get_platform_display == nullptr) return EGL_NO_DISPLAY;
  EGLint count = 0;
  if (query_devices(0, nullptr, &count) == EGL_FALSE || count <= 0) count = 0;
  std::vector<EGLDeviceEXT> devices(static_cast<std::size_t>(count));
  if (count > 0 && query_devices(count, devices.data(), &count) == EGL_FALSE) count = 0;
  devices.resize(static_cast<std::size_t>(count));

  if (forced) {
    char* end = nullptr;
    const long index = std::strtol(wanted, &end, 10);
    if (end == wanted || *end != '\0' || index < 0 || index >= count) {
      throw ContextError(std::string("egl: SIMREEL_EGL_DEVICE=") + wanted + ": expected 0.." +
                         std::to_string(count - 1) + " or surfaceless (" + std::to_string(count) +
                         " EGL devices found)");
    }
    EGLDisplay d = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[index], nullptr);
    if (d == EGL_NO_DISPLAY) fail("eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT)");
    return d;
  }
  for (EGLDeviceEXT device : devices) {
    const char* extensions =
        query_device_string != nullptr ? query_device_string(device, EGL_EXTENSIONS) : nullptr;
    if (has_extension(extensions, "EGL_MESA_device_software")) continue;
    EGLDisplay d = get_platform_display(EGL_PLATFORM_DEVICE_EXT, device, nullptr);
    if (d != EGL_NO_DISPLAY) return d;
  }
  return EGL_NO_DISPLAY;
}

class EglContext final : public Context {
 public:
  EglContext() {
    const char* client_extensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    display_ = device_display(client_extensions);
    if (display_ == EGL_NO_DISPLAY) {
      if (!has_extension(client_extensions, "EGL_MESA_platform_surfaceless")) {
        throw ContextError(
            "egl: no hardware EGLDevice and EGL_MESA_platform_surfaceless is not supported by "
            "this EGL");
      }
      auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
          eglGetProcAddress("eglGetPlatformDisplayEXT"));
      if (get_platform_display == nullptr) {
        throw ContextError("egl: eglGetPlatformDisplayEXT is not available");
      }
      display_ = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
      if (display_ == EGL_NO_DISPLAY) {
        fail("eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA)");
      }
    }
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
