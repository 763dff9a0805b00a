#pragma once
// Private: GLSL of the post pass: tone map, sRGB encoding, dither.
namespace simreel::render::detail {

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
uniform sampler2D u_bloom;     // BloomPass::result(), quarter size, linear filtering
uniform float u_bloom_intensity;
uniform vec2 u_size;           // the frame (pixels)
uniform int u_transparent;     // Background::transparent: keep alpha, un-premultiply
out vec4 o_color;
float tone_lut(uint bits) { return texelFetch(u_tone_lut, ivec2(int(bits & 255u), int(bits >> 8)), 0).r; }
void main() {
  // The scene's pixel this fragment shows: rows are flipped here, so that GL's bottom-to-top
  // read back is already the image's top-to-bottom order (exact: integers and halves).
  vec2 frag = vec2(gl_FragCoord.x, u_size.y - gl_FragCoord.y);
  ivec2 texel = ivec2(frag);
  vec4 frame = texelFetch(u_hdr, texel, 0);
  float alpha = 1.0;
  float bloom = u_bloom_intensity;
  if (u_transparent != 0) {
    // The frame is premultiplied over transparent black. Additive light (glow, sparks) adds
    // colour but no alpha: it counts as coverage by its brightness, so it composites as light.
    // Bloom stays within that coverage: where nothing was drawn, alpha stays exactly 0.
    vec3 f = max(frame.rgb, 0.0);
    alpha = clamp(max(frame.a, max(f.r, max(f.g, f.b))), 0.0, 1.0);
    bloom *= alpha;
  }
  vec4 src = frame;
  if (bloom > 0.0) src = mix(frame, texture(u_bloom, (vec2(texel) + 0.5) / u_size), bloom);
  vec3 c = max(src.rgb, 0.0);
  if (u_transparent != 0) {
    if (alpha < 0.5 / 255.0) alpha = 0.0;  // under half an 8-bit step: nothing
    c = alpha > 0.0 ? c / alpha : vec3(0.0);
  }
  uint rg = packHalf2x16(c.rg);
  uint b = packHalf2x16(vec2(c.b, 0.0));
  c = vec3(tone_lut(rg & 0xffffu), tone_lut(rg >> 16), tone_lut(b & 0xffffu));
  // Half-LSB interleaved-gradient dither: no banding in the sky gradient; fixed per pixel.
  float noise = fract(52.9829189 * fract(dot(frag, vec2(0.06711056, 0.00583715))));
  c += (noise - 0.5) / 255.0;
  o_color = vec4(c, alpha);
}
)";

}  // namespace simreel::render::detail
