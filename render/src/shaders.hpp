#pragma once
// Private: GLSL sources of the renderer. Everything is shaded in linear RGB into a half-float
// target; the post pass alone tone-maps, gamma-encodes and dithers to 8 bits.

namespace simreel::render::detail {

inline constexpr char kGlslVersion[] = "#version 330 core\n";

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

/// Hemisphere sky light: the sky's colour from above, the ground's bounce from below.
inline constexpr char kAmbientGlsl[] = R"(
uniform vec3 u_ambient;          // facing +z
uniform vec3 u_ground_ambient;   // facing -z
vec3 hemisphere(float nz) { return mix(u_ground_ambient, u_ambient, 0.5 + 0.5 * nz); }
)";

/// The opaque scene's depth (a resolved copy) for soft particles, as view distance (m).
inline constexpr char kSceneDepthGlsl[] = R"(
uniform sampler2D u_scene_depth;
uniform vec2 u_depth_params;  // (A, B) of the projection: distance = B / (ndc_z + A)
float view_distance(float window_z) { return u_depth_params.y / (window_z * 2.0 - 1.0 + u_depth_params.x); }
float scene_distance() { return view_distance(texelFetch(u_scene_depth, ivec2(gl_FragCoord.xy), 0).r); }
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

inline constexpr char kSkyFs[] = R"(
out vec4 o_color;
void main() { o_color = vec4(sky_at(gl_FragCoord.xy), 1.0); }
)";

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
uniform vec3 u_light_dir;     // direction the light travels
uniform vec3 u_light_color;
uniform vec4 u_color;
uniform sampler2D u_texture;
uniform int u_has_texture;
uniform float u_specular;
uniform float u_checker_m;    // 0: plain colour
uniform float u_half_size;    // 0: no edge fade (boxes)
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
  float spec = u_specular * pow(max(dot(n, h), 0.0), 48.0) * ndl;
  vec3 ambient = hemisphere(n.z);
  vec3 color = albedo * (ambient + u_light_color * (ndl * sun)) + u_light_color * (spec * sun);
  color = mix(color, sky_at(gl_FragCoord.xy), max(fog, edge));
  o_color = vec4(color, 1.0);
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

inline constexpr char kParticleVs[] = R"(
layout(location = 1) in vec4 a_center_radius; // per instance: world position (m), radius (m)
layout(location = 2) in vec4 a_color;         // per instance: linear RGBA
uniform mat4 u_view;
uniform mat4 u_proj;
uniform float u_pixels_per_unit; // projected pixels per metre at unit depth
uniform vec3 u_to_sun;           // world frame; the sun is sampled this side of the centre
uniform float u_sun_offset;      // radii towards the sun: a casting particle must not shadow itself
uniform int u_opaque;            // droplets: alpha only carries sub-pixel coverage
out vec2 v_corner;
out vec4 v_color;
out float v_sun;
flat out vec4 v_center_view;  // sprite centre, view frame (m), and drawn radius (m)
void main() {
  // Quad corner in [-1, 1]^2 from the vertex's place in its particle's four (see
  // upload_stream): (-1, -1), (1, -1), (-1, 1), (1, 1).
  vec2 a_corner = vec2((gl_VertexID & 1) != 0 ? 1.0 : -1.0, (gl_VertexID & 2) != 0 ? 1.0 : -1.0);
  vec4 c = u_view * vec4(a_center_radius.xyz, 1.0);
  float depth = max(-c.z, 1e-4);
  // A sprite under a pixel would flicker in and out of the sample grid: draw it one pixel
  // wide and fainter instead, keeping its coverage.
  float r = a_center_radius.w;
  float px = r * u_pixels_per_unit / depth;
  float grow = px < 1.0 ? 1.0 / max(px, 1e-3) : 1.0;
  v_center_view = vec4(c.xyz, r * grow);
  c.xy += a_corner * (r * grow);
  v_corner = a_corner;
  v_color = vec4(a_color.rgb, (u_opaque != 0 ? 1.0 : a_color.a) / (grow * grow));
  v_sun = sun_visibility_fast(a_center_radius.xyz + u_to_sun * (u_sun_offset * r));
  gl_Position = u_proj * c;
}
)";

/// Particle fragments take the depth of the sphere they stand for, not of the flat sprite, so a
/// droplet resting on the ground or touching a box meets it along a round outline.
inline constexpr char kSphereDepthGlsl[] = R"(
in vec2 v_corner;
in vec4 v_color;
#if SUN_TAPS == 0
const float v_sun = 1.0;  // no shadow map this frame: the vertex stage's v_sun is 1
#else
in float v_sun;
#endif
flat in vec4 v_center_view;
uniform vec3 u_up_view;  // world +z in the view frame: a view-frame normal's world z is dot(n, u_up_view)
// Writes the depth of the sphere's front surface at this fragment; h is the half chord
// sqrt(1 - r2) in radii. A perspective projection's depth depends on view z alone.
void write_sphere_depth(float h) {
  float z = v_center_view.z + v_center_view.w * h;
  gl_FragDepth = clamp(0.5 * (u_depth_params.x * z + u_depth_params.y) / (-z) + 0.5, 0.0, 1.0);
}
// Fraction of the sphere's chord through this fragment that lies in front of the opaque
// scene: 1 in open air, falling smoothly to 0 where the sphere sinks into a surface (no hard
// intersection line: soft particles).
float visible_fraction(float h) {
  float front = -(v_center_view.z + v_center_view.w * h);
  float chord = 2.0 * v_center_view.w * h;
  return clamp((scene_distance() - front) / max(chord, 1e-6), 0.0, 1.0);
}
)";

inline constexpr char kParticleSoftFs[] = R"(
out vec4 o_color;
uniform vec3 u_light_view;   // towards the sun, view frame
uniform vec3 u_half_view;    // half vector between the sun and the viewer, view frame
uniform vec3 u_light_color;
void main() {
  float r2 = dot(v_corner, v_corner);
  if (r2 >= 1.0) discard;
  float h = sqrt(1.0 - r2);
  write_sphere_depth(h);
  float visible = visible_fraction(h);
  if (visible <= 0.0) discard;
  float r = sqrt(r2);
  float aa = fwidth(r);
  // Beer-Lambert through the sphere: the centre has the given opacity, thinner chords less,
  // and only the part of the chord in front of the scene counts. Optical depth ~ h^e: e = 1
  // for a uniform sphere (dense droplets keep a crisp rim), rising to 3 for a density that
  // falls off as 1 - r^2 (thin smoke puffs blur into each other).
  float a = min(v_color.a, 0.999);
  float e = 3.0 - 2.0 * a;
  float alpha = (1.0 - exp2(log2(1.0 - a) * exp2(e * log2(max(h, 1e-6))) * visible)) *
                (1.0 - smoothstep(1.0 - aa, 1.0, r));
  // A sphere's normal from the sprite coordinates, in the view frame: the side away from the
  // sun is darker, which is what makes a cloud of sprites read as a volume.
  vec3 n = vec3(v_corner, h);
  float wrap = max((dot(n, u_light_view) + 0.25) / 1.25, 0.0);
  float s8 = max(dot(n, u_half_view), 0.0);
  s8 *= s8; s8 *= s8; s8 *= s8;
  float s32 = s8 * s8; s32 *= s32;
  float spec = 0.35 * a * s32 * s8;  // exponent 40 by squaring: pow() is costly on llvmpipe
  vec3 ambient = hemisphere(dot(n, u_up_view));
  vec3 color = v_color.rgb * (ambient + u_light_color * (wrap * v_sun)) + u_light_color * (spec * v_sun);
  o_color = vec4(color * alpha, alpha);  // premultiplied
}
)";

/// Small opaque spheres; sub-pixel ones and the rim reach the multisample coverage through
/// alpha-to-coverage.
inline constexpr char kParticleDropletFs[] = R"(
out vec4 o_color;
uniform vec3 u_light_view;
uniform vec3 u_half_view;
uniform vec3 u_light_color;
void main() {
  float r2 = dot(v_corner, v_corner);
  if (r2 >= 1.0) discard;
  float h = sqrt(1.0 - r2);
  write_sphere_depth(h);
  float r = sqrt(r2);
  float aa = fwidth(r);
  vec3 n = vec3(v_corner, h);
  float ndl = max(dot(n, u_light_view), 0.0);
  float s8 = max(dot(n, u_half_view), 0.0);
  s8 *= s8; s8 *= s8; s8 *= s8;
  float s32 = s8 * s8; s32 *= s32;
  float spec = 0.5 * s32 * s32;
  vec3 ambient = hemisphere(dot(n, u_up_view));
  vec3 color = v_color.rgb * (ambient + u_light_color * (ndl * v_sun)) + u_light_color * (spec * v_sun);
  o_color = vec4(color, v_color.a * (1.0 - smoothstep(1.0 - aa, 1.0, r)));
}
)";

/// Rain: a capsule from the head back along the screen-space velocity, built in pixels so its
/// width never drops under a pixel (thin streaks get fainter instead).
inline constexpr char kStreakVs[] = R"(
layout(location = 1) in vec4 a_center_radius; // head position (m), radius (m)
layout(location = 2) in vec4 a_color;
layout(location = 3) in vec3 a_trail;         // head to tail, world frame (m)
uniform mat4 u_view;
uniform mat4 u_proj;
uniform float u_pixels_per_unit;
uniform vec2 u_viewport;
uniform float u_near;
uniform vec3 u_to_sun;
uniform float u_sun_offset;
noperspective out vec2 v_local;  // (along from the head, across), in half-widths
flat out float v_length;         // head-to-tail length in half-widths
out vec4 v_color;
out float v_sun;
out float v_distance;            // view distance (m)
flat out float v_radius;
void main() {
  // Quad corner in [-1, 1]^2 from the vertex's place in its particle's four (see
  // upload_stream): (-1, -1), (1, -1), (-1, 1), (1, 1).
  vec2 a_corner = vec2((gl_VertexID & 1) != 0 ? 1.0 : -1.0, (gl_VertexID & 2) != 0 ? 1.0 : -1.0);
  vec3 head = (u_view * vec4(a_center_radius.xyz, 1.0)).xyz;
  vec3 tail = head + mat3(u_view) * a_trail;
  float limit = -1.001 * u_near;
  if (tail.z > limit && head.z < limit) tail = mix(head, tail, (limit - head.z) / (tail.z - head.z));
  vec4 ch = u_proj * vec4(head, 1.0);
  vec4 ct = u_proj * vec4(tail, 1.0);
  vec2 half_vp = 0.5 * u_viewport;
  vec2 d = (ct.xy / ct.w - ch.xy / ch.w) * half_vp;
  float len = length(d);
  vec2 u = len > 1e-3 ? d / len : vec2(1.0, 0.0);
  vec2 w = vec2(-u.y, u.x);
  float r = a_center_radius.w;
  float width = r * u_pixels_per_unit / max(-head.z, 1e-4);  // half-width (pixels)
  float hw = max(width, 0.75);
  float s = 0.5 * a_corner.x + 0.5;
  vec4 base = mix(ch, ct, s);
  base.xy += (u * (a_corner.x * hw) + w * (a_corner.y * hw)) / half_vp * base.w;
  v_local = vec2(s * len / hw + a_corner.x, a_corner.y);
  v_length = len / hw;
  v_color = vec4(a_color.rgb, a_color.a * min(width / hw, 1.0));
  v_sun = sun_visibility_fast(a_center_radius.xyz + u_to_sun * (u_sun_offset * r));
  v_distance = -mix(head.z, tail.z, s);
  v_radius = r;
  gl_Position = base;
}
)";

inline constexpr char kStreakFs[] = R"(
noperspective in vec2 v_local;
flat in float v_length;
in vec4 v_color;
#if SUN_TAPS == 0
const float v_sun = 1.0;  // no shadow map this frame: the vertex stage's v_sun is 1
#else
in float v_sun;
#endif
in float v_distance;
flat in float v_radius;
out vec4 o_color;
uniform vec3 u_light_color;
void main() {
  vec2 q = vec2(v_local.x - clamp(v_local.x, 0.0, v_length), v_local.y);
  float d = length(q);
  if (d >= 1.0) discard;
  float fade = clamp((scene_distance() - v_distance) / (2.0 * v_radius), 0.0, 1.0);
  float taper = 1.0 - 0.6 * clamp(v_local.x, 0.0, v_length) / max(v_length, 1.0);
  float alpha = v_color.a * (1.0 - smoothstep(0.35, 1.0, d)) * taper * fade;
  vec3 color = v_color.rgb * (hemisphere(0.0) + u_light_color * (0.5 * v_sun));
  o_color = vec4(color * alpha, alpha);
}
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
  // Quad corner in [-1, 1]^2 from the vertex's place in its particle's four (see
  // upload_stream): (-1, -1), (1, -1), (-1, 1), (1, 1).
  vec2 a_corner = vec2((gl_VertexID & 1) != 0 ? 1.0 : -1.0, (gl_VertexID & 2) != 0 ? 1.0 : -1.0);
  vec3 w = a_center_radius.xyz + (u_light_right * a_corner.x + u_light_up * a_corner.y) * a_center_radius.w;
  v_corner = a_corner;
  v_alpha = u_opaque != 0 ? 1.0 : min(a_color.a, 0.999);
  v_seed = float((gl_VertexID >> 2) & 15);
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

inline constexpr char kParticleAddFs[] = R"(
out vec4 o_color;
void main() {
  float r2 = dot(v_corner, v_corner);
  if (r2 >= 1.0) discard;
  float h = sqrt(1.0 - r2);
  write_sphere_depth(h);
  // Bright core with a long falloff; exactly zero at the rim so quads leave no edges.
  float falloff = (1.0 - r2) * (1.0 - r2);
  float glow = falloff * (0.35 + 0.65 * exp(-6.0 * r2)) * visible_fraction(h);
  o_color = vec4(v_color.rgb * (v_color.a * glow), 0.0);
}
)";

/// Tone map and sRGB encoding of one linear HDR value; kToneLutFs tabulates it for every
/// half-float bit pattern, kPostFs looks the table up.
inline constexpr char kToneMapGlsl[] = R"(
// Linear up to the knee, then a smooth shoulder towards 1: the colours a scene gives come out
// as given, highlights and stacked glow roll off instead of clipping.
vec3 tonemap(vec3 x) {
  const float k = 0.8;
  vec3 over = max(x - k, 0.0);
  return min(x, vec3(k)) + (1.0 - k) * (1.0 - exp(-over / (1.0 - k)));
}
vec3 srgb_encode(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}
)";

inline constexpr char kPackingExtension[] = "#extension GL_ARB_shading_language_packing : require\n";

/// The tone map table: texel (x, y) holds the encoded value of the half float whose bits are
/// 256 y + x, computed by the very code the frame pass used to run per pixel, so a look-up
/// gives the same float bit for bit (the HDR target is half float: its values are exactly
/// these 65536) at a fraction of the exp and pow per channel.
inline constexpr char kToneLutFs[] = R"(
out vec4 o_color;
void main() {
  uint bits = uint(gl_FragCoord.y) * 256u + uint(gl_FragCoord.x);
  vec3 c = vec3(unpackHalf2x16(bits).x);
  o_color = vec4(srgb_encode(tonemap(max(c, 0.0))), 1.0);
}
)";

inline constexpr char kPostFs[] = R"(
uniform sampler2D u_hdr;
uniform sampler2D u_tone_lut;  // kToneLutFs
out vec4 o_color;
float tone_lut(uint bits) { return texelFetch(u_tone_lut, ivec2(int(bits & 255u), int(bits >> 8)), 0).r; }
uniform float u_height;  // rows of the target: the image is written upside down (see below)
void main() {
  // The scene's pixel this fragment shows: rows are flipped here, so that GL's bottom-to-top
  // read back is already the image's top-to-bottom order (exact: integers and halves).
  vec2 frag = vec2(gl_FragCoord.x, u_height - gl_FragCoord.y);
  vec3 c = texelFetch(u_hdr, ivec2(frag), 0).rgb;
  uint rg = packHalf2x16(c.rg);
  uint b = packHalf2x16(vec2(c.b, 0.0));
  c = vec3(tone_lut(rg & 0xffffu), tone_lut(rg >> 16), tone_lut(b & 0xffffu));
  // Half-LSB interleaved-gradient dither: no banding in the sky gradient; fixed per pixel.
  float noise = fract(52.9829189 * fract(dot(frag, vec2(0.06711056, 0.00583715))));
  c += (noise - 0.5) / 255.0;
  o_color = vec4(c, 1.0);
}
)";

}  // namespace simreel::render::detail
