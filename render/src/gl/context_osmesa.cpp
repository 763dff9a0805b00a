// OSMesa: Mesa's pure-software offscreen context (llvmpipe), the default because it needs no
// device and no display.
#include <GL/glcorearb.h>  // before osmesa.h, see gl_table.hpp

#include <GL/osmesa.h>

#include <array>
#include <exception>
#include <memory>
#include <string>

#include "context_backends.hpp"

namespace simreel::render::detail {
namespace {

void* osmesa_proc(const char* name) {
  return reinterpret_cast<void*>(OSMesaGetProcAddress(name));
}

class OsmesaContext final : public Context {
 public:
  OsmesaContext() {
    const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA,
                           OSMESA_DEPTH_BITS, 0,
                           OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION, 3,
                           OSMESA_CONTEXT_MINOR_VERSION, 3,
                           0};
    context_ = OSMesaCreateContextAttribs(attribs, nullptr);
    if (context_ == nullptr) {
      throw ContextError("osmesa: OSMesaCreateContextAttribs failed for an OpenGL 3.3 core context");
    }
    // The renderer draws into its own framebuffer objects; the default buffer only has to exist.
    if (OSMesaMakeCurrent(context_, buffer_.data(), GL_UNSIGNED_BYTE, kBufferSide, kBufferSide) ==
        GL_FALSE) {
      OSMesaDestroyContext(context_);
      throw ContextError("osmesa: OSMesaMakeCurrent failed");
    }
    try {
      table_.load(&osmesa_proc);
    } catch (const std::exception& e) {
      OSMesaDestroyContext(context_);
      throw ContextError(std::string("osmesa: ") + e.what());
    }
  }
  ~OsmesaContext() override {
    if (OSMesaGetCurrentContext() == context_) {
      OSMesaMakeCurrent(nullptr, nullptr, GL_UNSIGNED_BYTE, 0, 0);
    }
    OSMesaDestroyContext(context_);
  }
  OsmesaContext(const OsmesaContext&) = delete;
  OsmesaContext& operator=(const OsmesaContext&) = delete;

  [[nodiscard]] const GlTable& gl() const override { return table_; }
  [[nodiscard]] std::string backend_name() const override { return "osmesa"; }

 private:
  static constexpr int kBufferSide = 4;
  OSMesaContext context_ = nullptr;
  std::array<unsigned char, kBufferSide * kBufferSide * 4> buffer_{};
  GlTable table_;
};

}  // namespace

std::unique_ptr<Context> create_osmesa_context() { return std::make_unique<OsmesaContext>(); }

}  // namespace simreel::render::detail
