#pragma once
// Private: GLSL pieces several passes share. Everything is shaded in linear RGB into a
// half-float target; the post pass alone tone-maps, gamma-encodes and dithers to 8 bits.
namespace simreel::render::detail {

/// Hemisphere sky light: the sky's colour from above, the ground's bounce from below.
inline constexpr char kAmbientGlsl[] = R"(
uniform vec3 u_ambient;          // facing +z
uniform vec3 u_ground_ambient;   // facing -z
vec3 hemisphere(float nz) { return mix(u_ground_ambient, u_ambient, 0.5 + 0.5 * nz); }
)";

inline constexpr char kFullscreenVs[] = R"(
out vec2 v_uv;
void main() {
  // One triangle covering the viewport; no vertex buffer needed.
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  v_uv = p;
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
)";

}  // namespace simreel::render::detail
