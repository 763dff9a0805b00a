#pragma once
// Private: GLSL of the particle passes: soft, additive, droplet sprites and streaks.
namespace simreel::render::detail {

/// The opaque scene's depth (a resolved copy) for soft particles, as view distance (m).
inline constexpr char kSceneDepthGlsl[] = R"(
uniform sampler2D u_scene_depth;
uniform vec2 u_depth_params;  // (A, B) of the projection: distance = B / (ndc_z + A)
float view_distance(float window_z) { return u_depth_params.y / (window_z * 2.0 - 1.0 + u_depth_params.x); }
float scene_distance() { return view_distance(texelFetch(u_scene_depth, ivec2(gl_FragCoord.xy), 0).r); }
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
#if defined(TEXTURED) && TEXTURED
layout(location = 3) in float a_param; // age / lifetime (integer part, 0..1023) + own random (fraction); -1: none
out vec2 v_uv;                // noise texture coordinates (tiles of the noise)
flat out vec2 v_texture;      // (dissolve threshold, texture contrast); contrast 0: plain sprite
#endif
out vec2 v_corner;
out vec4 v_color;
out float v_sun;
flat out vec4 v_center_view;  // sprite centre, view frame (m), and drawn radius (m)
// Soft sprites' Beer-Lambert terms, per particle: log2(1 - alpha) and 1 - alpha (alpha <= 0.999).
flat out vec2 v_optics;
#if defined(SPARK) && SPARK
// Small sparks: (corner -> pixels, corner -> glow radii, weight of the pixel-tent splat, its light)
flat out vec4 v_spark;
#endif
void main() {
  vec2 a_corner = sprite_corner();  // the triangle around the unit disc (kSpriteCornerGlsl)
  vec4 c = u_view * vec4(a_center_radius.xyz, 1.0);
  float depth = max(-c.z, 1e-4);
  // A sprite under a pixel would flicker in and out of the sample grid: draw it one pixel
  // wide and fainter instead, keeping its coverage.
  float r = a_center_radius.w;
  float px = r * u_pixels_per_unit / depth;
  float grow = px < 1.0 ? 1.0 / max(px, 1e-3) : 1.0;
#if defined(SPARK) && SPARK
  // A spark under a pixel is splatted with the bilinear tent of one pixel, whose weights at the
  // pixel centres always sum to 1 wherever the spark falls: its light is exactly the glow's
  // integral over its true disc (0.6123 r_px^2), with no twinkling as it moves. The quad spans
  // at least +-1.5 px so every pixel the tent reaches is wholly covered (MSAA keeps its full
  // weight). Between 1 and 2 px the splat cross-fades into the glow disc (sampled at pixel
  // centres, whose sum wanders with the position at that size), so nothing pops as a spark
  // grows or shrinks through a pixel.
  v_spark = vec4(0.0, 1.0, 0.0, 0.0);
  if (px < 2.0) {
    float half_px = max(px, 1.5);
    grow = half_px / max(px, 1e-4);
    v_spark = vec4(half_px, grow, 1.0 - smoothstep(1.0, 2.0, px), 0.6123 * px * px);
  }
  v_color = a_color;
#else
  v_color = vec4(a_color.rgb, (u_opaque != 0 ? 1.0 : a_color.a) / (grow * grow));
#endif
  float a0 = min(v_color.a, 0.999);
  v_optics = vec2(log2(1.0 - a0), 1.0 - a0);
  v_center_view = vec4(c.xyz, r * grow);
  c.xy += a_corner * (r * grow);
  v_corner = a_corner;
  v_sun = sun_visibility_fast(a_center_radius.xyz + u_to_sun * (u_sun_offset * r));
#if defined(TEXTURED) && TEXTURED
  // Each particle reads its own region of the noise, turned by its own angle; as it ages it
  // turns further (each its own way) and drifts through the noise, and its dissolve threshold
  // rises so thin parts vanish first. The texture fades out on sprites under a few pixels
  // (where it would only sparkle).
  if (a_param < 0.0) {
    v_uv = vec2(0.0);
    v_texture = vec2(-1.0, 0.0);
  } else {
    float age = floor(a_param) / 1023.0;
    float rnd = fract(a_param);
    float angle = 6.2831853 * rnd + (2.0 * rnd - 1.0) * 2.5 * age;
    float ca = cos(angle), sa = sin(angle);
    v_uv = mat2(ca, sa, -sa, ca) * a_corner * 0.42 + vec2(37.0 * rnd, 53.0 * rnd + 0.3 * age);
    v_texture = vec2(-0.25 + 0.8 * age, clamp((px * grow - 3.0) / 9.0, 0.0, 1.0));
  }
#endif
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
// intersection line: soft particles). It is 0 exactly where the sphere's front surface lies
// behind the scene, so it is the blended sprites' whole depth test: they are drawn with the
// hardware test off and write no depth (ParticlePass::draw_blended).
float visible_fraction(float h) {
  float front = -(v_center_view.z + v_center_view.w * h);
  float chord = 2.0 * v_center_view.w * h;
  return clamp((scene_distance() - front) / max(chord, 1e-6), 0.0, 1.0);
}
)";

inline constexpr char kParticleSoftFs[] = R"(
out vec4 o_color;
flat in vec2 v_optics;
#if defined(TEXTURED) && TEXTURED
uniform sampler2D u_noise;
in vec2 v_uv;
flat in vec2 v_texture;
#endif
uniform vec3 u_light_view;   // towards the sun, view frame
uniform vec3 u_half_view;    // half vector between the sun and the viewer, view frame
uniform vec3 u_light_color;
void main() {
  float r2 = dot(v_corner, v_corner);
  if (r2 >= 1.0) discard;
  float h = sqrt(1.0 - r2);
  float visible = visible_fraction(h);
  if (visible <= 0.0) discard;
  float r = sqrt(r2);
  float aa = fwidth(r);
  // Beer-Lambert through the sphere: the centre has the given opacity alpha, thinner chords
  // less, and only the part of the chord in front of the scene counts. The sphere's density is
  // a blend of uniform (weight alpha: dense droplets keep a crisp rim) and 1 - r^2 (weight
  // 1 - alpha: thin smoke puffs blur into each other), whose optical depths along the chord at
  // r are h and h^3 (normalised to 1 at the centre): tau = alpha h + (1 - alpha) h^3 =
  // h (1 - (1 - alpha) r^2). One exp2 per fragment (the log2 is per particle).
  float a = min(v_color.a, 0.999);
  float density = 1.0;
#if defined(TEXTURED) && TEXTURED
  // Smoke: the noise thins the puff's density where it is low, dissolving it from its thin parts
  // as the threshold rises with age; `shade` darkens dense parts, more so on the side away from
  // the sun.
  float nz = texture(u_noise, v_uv).r;
  float tex = smoothstep(v_texture.x, v_texture.x + 0.45, nz) * (0.55 + 0.9 * nz);
  density = mix(1.0, tex, v_texture.y);
  a = min(a * density, 0.999);
#endif
  float tau = h * (1.0 - v_optics.y * r2);
  float alpha = (1.0 - exp2(v_optics.x * (density * tau * visible))) *
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
#if defined(TEXTURED) && TEXTURED
  float away = 0.5 - 0.5 * dot(n, u_light_view);  // 0 facing the sun, 1 facing away
  float shade = mix(1.0, 1.0 - 0.55 * nz * (0.4 + 0.6 * away), v_texture.y);
  wrap *= shade;
  ambient *= mix(1.0, 0.8 + 0.2 * shade, v_texture.y);
#endif
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
  // Water reflects the sky at grazing angles (Schlick's Fresnel, n = 1.33: 2% head-on): a
  // bright rim against the sky. The reflected ray points up where the normal does.
  float m = 1.0 - h;
  float m2 = m * m;
  float fresnel = 0.02 + 0.98 * m2 * m2 * m;
  vec3 reflected = reflect(vec3(0.0, 0.0, -1.0), n);
  color = mix(color, 2.2 * hemisphere(dot(reflected, u_up_view)), fresnel);
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
  // ParticlePass::upload): (-1, -1), (1, -1), (-1, 1), (1, 1).
  vec2 a_corner = vec2((gl_VertexID & 1) != 0 ? 1.0 : -1.0, (gl_VertexID & 2) != 0 ? 1.0 : -1.0);
  vec3 head = (u_view * vec4(a_center_radius.xyz, 1.0)).xyz;
  vec3 tail = head + mat3(u_view) * a_trail;
  // Clip the segment to the near plane at either end; wholly behind it, nothing is drawn (all
  // four corners outside the clip volume).
  float limit = -1.001 * u_near;
  if (head.z >= limit && tail.z >= limit) {
    gl_Position = vec4(0.0, 0.0, -2.0, 1.0);
    return;
  }
  if (tail.z > limit) tail = mix(head, tail, (limit - head.z) / (tail.z - head.z));
  if (head.z > limit) head = mix(tail, head, (limit - tail.z) / (head.z - tail.z));
  vec4 ch = u_proj * vec4(head, 1.0);
  vec4 ct = u_proj * vec4(tail, 1.0);
  vec2 half_vp = 0.5 * u_viewport;
  vec2 d = (ct.xy / ct.w - ch.xy / ch.w) * half_vp;
  float len = min(length(d), 1e5);  // finite however close to the camera plane an end lies
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
#if defined(ADDITIVE) && ADDITIVE
  // A glowing trail carries the light of the dot it replaces: its coverage (width / hw)^2 like
  // a sub-pixel sprite, spread over the capsule's glow integral (disc 0.6123, across the body
  // 0.7751 per half-width of length, a linear fade to 0.3 at the tail; in half-widths^2).
  float cover = min(width / hw, 1.0);
  float L = len / hw;
  float fade_end = 1.0 - 0.7 * L / max(L, 1.0);
  float energy = 0.6123 / (0.30615 * (1.0 + fade_end) + 0.7751 * L * 0.5 * (1.0 + fade_end));
  v_color = vec4(a_color.rgb, a_color.a * cover * cover * energy);
#else
  v_color = vec4(a_color.rgb, a_color.a * min(width / hw, 1.0));
#endif
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

/// Additive trails (fireworks stars, sparks, motion blur): the dot's glow profile across a
/// capsule from the head back along the trail, fading linearly to 0.3 at the tail, added to the
/// frame; the vertex stage scales it so the trail's summed light equals the dot's.
inline constexpr char kTrailFs[] = R"(
noperspective in vec2 v_local;
flat in float v_length;
in vec4 v_color;
in float v_distance;
flat in float v_radius;
out vec4 o_color;
void main() {
  vec2 q = vec2(v_local.x - clamp(v_local.x, 0.0, v_length), v_local.y);
  float d2 = dot(q, q);
  if (!(d2 < 1.0)) discard;  // also drops a non-finite fragment
  float fade = clamp((scene_distance() - v_distance) / (2.0 * v_radius), 0.0, 1.0);
  float taper = 1.0 - 0.7 * clamp(v_local.x, 0.0, v_length) / max(v_length, 1.0);
  float glow = (1.0 - d2) * (1.0 - d2) * (0.35 + 0.65 * exp(-6.0 * d2));
  o_color = vec4(min(v_color.rgb * (v_color.a * glow * taper * fade), vec3(1e3)), 0.0);
}
)";

inline constexpr char kParticleAddFs[] = R"(
out vec4 o_color;
flat in vec4 v_spark;
#if defined(TEXTURED) && TEXTURED
uniform sampler2D u_noise;
in vec2 v_uv;
flat in vec2 v_texture;
#endif
void main() {
  float r2 = dot(v_corner, v_corner);
  if (r2 >= 1.0) discard;
  float h = sqrt(1.0 - r2);
  // Bright core with a long falloff; exactly zero at the rim so quads leave no edges. Its
  // integral over the disc is 0.6123 (in radii squared), which the trails match.
  vec2 q = v_corner * v_spark.y;  // in radii of the glow disc
  float g2 = min(dot(q, q), 1.0);
  float glow = (1.0 - g2) * (1.0 - g2) * (0.35 + 0.65 * exp(-6.0 * g2));
  if (v_spark.z > 0.0) {
    vec2 t = max(1.0 - abs(v_corner * v_spark.x), 0.0);
    glow = mix(glow, t.x * t.y * v_spark.w, v_spark.z);
  }
  glow *= visible_fraction(h);
#if defined(TEXTURED) && TEXTURED
  // Flame: the noise breaks the glow into tongues that burn away from their thin parts as the
  // flame ages (mean ~1, so the flame's total light stays about the same).
  float nz = texture(u_noise, v_uv).r;
  glow *= mix(1.0, smoothstep(v_texture.x, v_texture.x + 0.5, nz) * (0.3 + 1.6 * nz), v_texture.y);
#endif
  o_color = vec4(v_color.rgb * (v_color.a * glow), 0.0);
}
)";

}  // namespace simreel::render::detail
