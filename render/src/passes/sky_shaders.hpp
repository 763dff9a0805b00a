#pragma once
// Private: GLSL of the sky pass. sky_color() is also the fog colour of the mesh pass and
// ground_color() the far ground's, so fogged meshes and the ground square's edge meet the
// background without a line.
namespace simreel::render::detail {

/// The sky seen along a world direction (z up). Elevation sets the gradient: the horizon colour
/// (RenderSettings::sky_bottom) at and below the horizon, the zenith colour (sky_top) overhead;
/// around the sun, forward-scattered light brightens the haze, and `disk` adds the sun itself
/// (HDR, so it blooms). u_sky_mode 1 (solid) is the background colour everywhere; 2 is
/// transparent (the callers keep alpha 0 there).
inline constexpr char kSkyGlsl[] = R"(
uniform vec3 u_sky_top;      // zenith (linear RGB)
uniform vec3 u_sky_bottom;   // horizon
uniform vec3 u_sun_dir;      // unit, towards the sun
uniform vec3 u_sun_color;
uniform int u_sky_mode;      // 0 gradient, 1 solid, 2 transparent
vec3 sky_color(vec3 dir, float disk) {
  if (u_sky_mode == 1) return u_sky_top;
  float el = clamp(dir.z, 0.0, 1.0);
  // Most of the change within ~15 degrees of the horizon, with a finite slope there: a soft
  // haze band, no kink at the horizon line.
  vec3 c = mix(u_sky_bottom, u_sky_top, (1.0 - exp(-el / 0.18)) / (1.0 - exp(-1.0 / 0.18)));
  float mu = max(dot(dir, u_sun_dir), 0.0);
  // Haze around the sun: wide and faint, stronger towards the horizon, plus a tight aureole.
  float haze = 1.0 - 0.6 * el;
  // Powers by squaring (mu^6, mu^180 = mu^128 mu^32 mu^16 mu^4): pow() is exp2(log2) on
  // llvmpipe, and this runs for every sky pixel and every fogged mesh fragment.
  float mu2 = mu * mu, mu4 = mu2 * mu2, mu8 = mu4 * mu4, mu16 = mu8 * mu8;
  float mu32 = mu16 * mu16, mu64 = mu32 * mu32, mu128 = mu64 * mu64;
  c += u_sun_color * (0.10 * haze * (mu4 * mu2) + 0.25 * (mu128 * mu32 * mu16 * mu4));
  // The disk: 0.8 degrees in radius, its edge smoothed over a few hundredths of a degree.
  if (disk > 0.0) c += u_sun_color * (24.0 * disk * smoothstep(0.999893, 0.999912, mu));
  return c;
}
// The far ground beyond the drawn square: the ground plane's colour lit like the mesh pass lights
// an unshadowed, untextured plane (sky ambient from above, sun, the plane's faint highlight).
uniform vec3 u_light_dir;     // direction the light travels
uniform vec3 u_light_color;
// (u_ambient: kAmbientGlsl, which comes first)
vec3 ground_color(vec3 albedo, vec3 view_dir) {
  vec3 l = normalize(-u_light_dir);
  float ndl = max(l.z, 0.0);
  vec3 h = normalize(l - view_dir);
  float spec = 0.06 * pow48(max(h.z, 0.0)) * ndl;
  return albedo * (u_ambient + u_light_color * ndl) + u_light_color * spec;
}
)";

inline constexpr char kSkyFs[] = R"(
uniform mat4 u_inv_view_proj;
uniform vec3 u_eye;
uniform vec2 u_viewport;
uniform int u_ground;          // 1: a horizontal ground plane continues below the horizon
uniform float u_ground_z;      // (m)
uniform vec3 u_ground_albedo;
uniform float u_fog_distance;  // (m), as the mesh pass
out vec4 o_color;
void main() {
  if (u_sky_mode == 2) { o_color = vec4(0.0); return; }
  vec2 ndc = gl_FragCoord.xy / u_viewport * 2.0 - 1.0;
  vec4 far = u_inv_view_proj * vec4(ndc, 1.0, 1.0);
  vec3 dir = normalize(far.xyz / far.w - u_eye);
  vec3 c = sky_color(dir, 1.0);
  if (u_ground != 0 && dir.z < 0.0 && u_eye.z > u_ground_z) {
    // Aerial perspective: the same fog as the mesh pass, so the drawn ground square continues
    // seamlessly and fades into the horizon's colour with distance.
    float t = (u_ground_z - u_eye.z) / dir.z;
    float fog = 1.0 - exp(-(t * t) / (u_fog_distance * u_fog_distance));
    c = mix(ground_color(u_ground_albedo, dir), sky_color(dir, 0.0), fog);
  }
  o_color = vec4(c, 1.0);
}
)";

}  // namespace simreel::render::detail
