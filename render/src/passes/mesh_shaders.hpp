#pragma once
// Private: GLSL of the mesh pass (planes, boxes, meshes, cloth): lit, shadowed, fogged.
namespace simreel::render::detail {

inline constexpr char kLitVs[] = R"(
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv;
uniform mat4 u_model;
uniform mat3 u_normal_matrix;
uniform mat4 u_view_proj;
out vec3 v_world;
out vec3 v_normal;
out vec2 v_uv;
void main() {
  vec4 w = u_model * vec4(a_position, 1.0);
  v_world = w.xyz;
  v_normal = u_normal_matrix * a_normal;
  v_uv = a_uv;
  gl_Position = u_view_proj * w;
}
)";

inline constexpr char kLitFs[] = R"(
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
out vec4 o_color;
uniform vec3 u_eye;
uniform vec4 u_color;
uniform sampler2D u_texture;
uniform int u_has_texture;
uniform float u_specular;
uniform float u_checker_m;    // 0: plain colour
uniform float u_half_size;    // 0: no edge fade (boxes)
uniform int u_ground_plane;   // 1: the ground (find_ground): its edge fades into the far ground
uniform float u_fog_distance; // (m)

// Box-filtered checker (1 on dark cells): the filter width is the pixel footprint, so cells
// smaller than a pixel average to grey instead of producing moire.
float checker(vec2 p, out float footprint) {
  vec2 w = fwidth(p) + 1e-4;
  footprint = max(w.x, w.y);
  vec2 i = 2.0 * (abs(fract((p - 0.5 * w) * 0.5) - 0.5) - abs(fract((p + 0.5 * w) * 0.5) - 0.5)) / w;
  return 0.5 - 0.5 * i.x * i.y;
}

void main() {
  vec3 n = normalize(v_normal);
  if (!gl_FrontFacing) n = -n;
  vec3 to_eye = u_eye - v_world;
  float dist = length(to_eye);
  vec3 v = to_eye / dist;
  vec3 l = normalize(-u_light_dir);

  vec3 albedo = u_color.rgb;
  if (u_has_texture != 0) albedo *= texture(u_texture, v_uv).rgb;
  float fog = 1.0 - exp(-(dist * dist) / (u_fog_distance * u_fog_distance));
  if (u_checker_m > 0.0) {
    float footprint;
    float c = checker(v_uv / u_checker_m, footprint);
    // Fade the pattern out well before the filter has to, and with the fog.
    float contrast = (1.0 - smoothstep(0.15, 0.6, footprint)) * (1.0 - fog);
    albedo *= 1.0 - 0.12 * c * contrast;
  }
  float edge = 0.0;
  if (u_half_size > 0.0) {
    // Rounded-square distance to the centre: the square's corners fade a little earlier.
    vec2 q = abs(v_uv) / u_half_size;
    q *= q;
    edge = smoothstep(0.6, 1.0, sqrt(sqrt(dot(q, q))));
  }

  float ndl = max(dot(n, l), 0.0);
  float sun = ndl > 0.0 ? sun_visibility(v_world, n) : 0.0;
  vec3 h = normalize(l + v);
  float spec = u_specular * pow48(max(dot(n, h), 0.0)) * ndl;
  vec3 ambient = hemisphere(n.z);
  vec3 color = albedo * (ambient + u_light_color * (ndl * sun)) + u_light_color * (spec * sun);
  // Aerial perspective: fog towards the sky seen behind the point (its horizon colour for
  // anything below the horizon).
  vec3 fog_color = sky_color(-v, 0.0);
  float fade = max(fog, edge);
  if (u_ground_plane != 0 && u_sky_mode != 2) {
    // The ground continues as the sky pass's far ground: towards the edge the square turns
    // into exactly that (no checker, no shadow), then both fog alike.
    if (edge > 0.0) color = mix(color, ground_color(u_color.rgb, -v), edge);
    fade = fog;
  }
  if (u_sky_mode == 2) {
    // Nothing behind to fog towards: objects stay opaque for compositing; only the ground
    // square's edge fades out (premultiplied, over nothing).
    o_color = vec4(color * (1.0 - edge), 1.0 - edge);
  } else {
    o_color = vec4(mix(color, fog_color, fade), 1.0);
  }
}
)";

}  // namespace simreel::render::detail
