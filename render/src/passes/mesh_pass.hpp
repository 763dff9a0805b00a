#pragma once
// Private: the lit opaque geometry: ground planes (checker, edge fade), boxes (one shared unit
// cube scaled per box), triangle meshes and two-sided cloth; sun with shadow lookup, hemisphere
// sky light, fog towards the sky colour.

#include "drawables.hpp"
#include "frame.hpp"
#include "gl/program.hpp"

namespace simreel::render::detail {

class MeshPass {
 public:
  /// @throws ContextError if the program cannot be made.
  void create(const GlTable& gl);
  void destroy() noexcept;
  /// The unit cube [-1, 1]^3 every box is drawn with (also by the shadow pass).
  [[nodiscard]] const GpuMesh& cube() const { return cube_; }
  /// Draws every plane, box and mesh of `table` in key order into the bound framebuffer
  /// (depth test on, shadow map on unit 1).
  void draw(const FrameView& frame, const ShadowView& shadow, const DrawableTable& table);

 private:
  const GlTable* gl_ = nullptr;
  Program program_;
  GpuMesh cube_;
};

}  // namespace simreel::render::detail
