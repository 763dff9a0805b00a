#pragma once
/// @file context.hpp
/// Offscreen OpenGL contexts (core profile >= 3.3): OSMesa (default) and EGL without a window
/// system: the first hardware EGLDevice (EGL_EXT_platform_device, as NVIDIA's driver offers),
/// else Mesa's EGL_PLATFORM_SURFACELESS_MESA (a GPU render node, else llvmpipe). The environment
/// variable SIMREEL_EGL_DEVICE=<n> picks the n-th EGLDevice, =surfaceless forces Mesa's path.

#include <memory>
#include <stdexcept>
#include <string>

#include "simreel/render/gl_table.hpp"

namespace simreel::render {

enum class Backend { osmesa, egl };

/// Parses "osmesa" / "egl". @throws std::invalid_argument otherwise.
Backend parse_backend(const std::string& name);

/// A context could not be created; the message says which backend and why.
class ContextError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A current OpenGL context with its function table. Rendering goes into framebuffer objects
/// the renderer owns, so the default framebuffer's size does not matter.
class Context {
 public:
  virtual ~Context() = default;
  [[nodiscard]] virtual const GlTable& gl() const = 0;
  [[nodiscard]] virtual std::string backend_name() const = 0;
  /// GL_RENDERER and GL_VERSION strings (stored beside image-hash goldens).
  [[nodiscard]] std::string renderer_string() const;
  [[nodiscard]] std::string version_string() const;
};

/// Creates a context and makes it current on the calling thread; destroying it releases it.
/// @throws ContextError naming the backend and reason, e.g. "egl: eglInitialize failed
///         (EGL_NOT_INITIALIZED)".
std::unique_ptr<Context> create_context(Backend backend);

}  // namespace simreel::render
