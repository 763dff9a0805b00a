#pragma once
// Private: GLSL of the shadow pass (casters into the sun's depth map) and the shadow lookup
// that the mesh and particle passes run.
namespace simreel::render::detail {

/// Sun shadow lookup, usable from vertex and fragment stages (explicit LOD).
inline constexpr char kShadowGlsl[] = R"(
uniform sampler2DShadow u_shadow_map;
uniform mat4 u_light_view_proj;
uniform int u_shadow_enabled;
uniform float u_shadow_bias;     // light-depth units
uniform float u_shadow_offset;   // (m) normal offset against acne
uniform float u_shadow_radius;   // shadow-map uv units, penumbra width
const vec2 k_poisson[12] = vec2[](
  vec2(-0.326, -0.406), vec2(-0.840, -0.074), vec2(-0.696, 0.457), vec2(-0.203, 0.621),
  vec2(0.962, -0.195), vec2(0.473, -0.480), vec2(0.519, 0.767), vec2(0.185, -0.893),
  vec2(0.507, 0.064), vec2(0.896, 0.412), vec2(-0.322, -0.933), vec2(-0.792, -0.598));
float sun_visibility(vec3 world, vec3 normal) {
  if (u_shadow_enabled == 0) return 1.0;
  vec4 lp = u_light_view_proj * vec4(world + normal * u_shadow_offset, 1.0);
  vec3 p = lp.xyz / lp.w * 0.5 + 0.5;
  if (p.x < 0.0 || p.x > 1.0 || p.y < 0.0 || p.y > 1.0) return 1.0;
  // Receivers beyond the far plane compare as 1.0: shadowed under a caster, lit elsewhere.
  float ref = min(p.z - u_shadow_bias, 1.0);
  float sum = 0.0;
  for (int i = 0; i < 12; ++i) {
    sum += textureLod(u_shadow_map, vec3(p.xy + k_poisson[i] * u_shadow_radius, ref), 0.0);
  }
  return sum / 12.0;
}
// SUN_TAPS bilinear comparisons (0, 1 or 4; see the renderer's particle program variants):
// enough for particles, which are small and already soft; four average the dithered shadows
// of translucent particles (particle_shadows).
#ifndef SUN_TAPS
#define SUN_TAPS 1
#endif
float sun_visibility_fast(vec3 world) {
#if SUN_TAPS == 0
  return 1.0;
#else
  if (u_shadow_enabled == 0) return 1.0;
  vec4 lp = u_light_view_proj * vec4(world, 1.0);
  vec3 p = lp.xyz / lp.w * 0.5 + 0.5;
  if (p.x < 0.0 || p.x > 1.0 || p.y < 0.0 || p.y > 1.0) return 1.0;
  float ref = min(p.z - u_shadow_bias, 1.0);
#if SUN_TAPS == 1
  return textureLod(u_shadow_map, vec3(p.xy, ref), 0.0);
#else
  float sum = 0.0;
  for (int i = 0; i < SUN_TAPS; ++i) {
    sum += textureLod(u_shadow_map, vec3(p.xy + k_poisson[3 * i] * (2.0 * u_shadow_radius), ref), 0.0);
  }
  return sum / float(SUN_TAPS);
#endif
#endif
}
)";

inline constexpr char kDepthVs[] = R"(
layout(location = 0) in vec3 a_position;
uniform mat4 u_model;
uniform mat4 u_light_view_proj;
void main() { gl_Position = u_light_view_proj * (u_model * vec4(a_position, 1.0)); }
)";

inline constexpr char kDepthFs[] = R"(
void main() {}
)";

/// Particles in the sun's shadow map: discs facing the sun; see RenderSettings::particle_shadows.
inline constexpr char kParticleDepthVs[] = R"(
layout(location = 1) in vec4 a_center_radius;
layout(location = 2) in vec4 a_color;
uniform mat4 u_light_view_proj;
uniform vec3 u_light_right;
uniform vec3 u_light_up;
uniform int u_opaque;
out vec2 v_corner;
flat out float v_alpha;
flat out float v_seed;
void main() {
  vec2 a_corner = sprite_corner();  // the triangle around the unit disc (kSpriteCornerGlsl)
  vec3 w = a_center_radius.xyz + (u_light_right * a_corner.x + u_light_up * a_corner.y) * a_center_radius.w;
  v_corner = a_corner;
  v_alpha = u_opaque != 0 ? 1.0 : min(a_color.a, 0.999);
  v_seed = float((gl_VertexID / u_sprite_vertices) & 15);  // the particle's index
  gl_Position = u_light_view_proj * vec4(w, 1.0);
}
)";

/// Translucent casters keep a fraction of their texels equal to their opacity through the
/// sphere (an ordered 4 x 4 Bayer dither, shifted per particle so overlapping particles keep
/// different texels; fixed, so frames stay deterministic); the receivers' filtered lookups
/// average each 4 x 4 block back into a partial shadow.
inline constexpr char kParticleDepthFs[] = R"(
in vec2 v_corner;
flat in float v_alpha;
flat in float v_seed;
const float k_bayer[16] = float[](0.0, 8.0, 2.0, 10.0, 12.0, 4.0, 14.0, 6.0,
                                  3.0, 11.0, 1.0, 9.0, 15.0, 7.0, 13.0, 5.0);
void main() {
  float r2 = dot(v_corner, v_corner);
  if (r2 >= 1.0) discard;
  float opacity = 1.0 - exp2(log2(1.0 - v_alpha) * sqrt(1.0 - r2));
  int seed = int(v_seed);
  ivec2 p = (ivec2(gl_FragCoord.xy) + ivec2(seed, seed >> 2)) & 3;
  if ((k_bayer[p.y * 4 + p.x] + 0.5) / 16.0 >= opacity) discard;
}
)";

}  // namespace simreel::render::detail
