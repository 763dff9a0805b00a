#pragma once
// Private: GLSL of the sky pass; sky_at() is also the fog colour of the mesh pass.
namespace simreel::render::detail {

/// The background: the fog colour of every mesh is the sky behind it, so far ground and the
/// edge of the ground square dissolve into the sky instead of ending on a line.
inline constexpr char kSkyGlsl[] = R"(
uniform vec3 u_sky_top;
uniform vec3 u_sky_bottom;
uniform vec2 u_viewport;
vec3 sky_at(vec2 frag) {
  float t = clamp(frag.y / u_viewport.y, 0.0, 1.0);
  return mix(u_sky_bottom, u_sky_top, t);
}
)";

inline constexpr char kSkyFs[] = R"(
out vec4 o_color;
void main() { o_color = vec4(sky_at(gl_FragCoord.xy), 1.0); }
)";

}  // namespace simreel::render::detail
