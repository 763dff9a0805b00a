#pragma once
// Private: GLSL of the bloom chain (bloom_pass.hpp). Both read their source with bilinear
// filtering and clamp-to-edge, so each fetch already averages a 2 x 2 block.
namespace simreel::render::detail {

/// 13-tap downsample (Jimenez 2014, slide 153): five overlapping 2 x 2 boxes, the centre one
/// weighted 0.5 and the four corner ones 0.125 each; the weights sum to 1.
/// The first level (a quarter of the frame's size) takes the frame's 4 x 4 box instead, 16
/// exact fetches: no half-size level to write and add back up (on llvmpipe that level's passes
/// were half the chain's cost), and at the default intensity (0.04) the finest glow it held
/// cannot be told from its 4 x 4 blur.
inline constexpr char kBloomDownFs[] = R"(
uniform sampler2D u_src;
uniform vec2 u_src_texel;   // 1 / source size
uniform vec2 u_dst_size;
uniform int u_box;          // 1: the frame's 4 x 4 box
out vec4 o_color;
void main() {
  vec2 uv = gl_FragCoord.xy / u_dst_size;
  vec2 t = u_src_texel;
  if (u_box != 0) {
    // Exact integer fetches: llvmpipe filters half floats slowly, and the frame is half float.
    ivec2 p = 4 * ivec2(gl_FragCoord.xy);
    ivec2 m = textureSize(u_src, 0) - 1;
    vec4 sum = vec4(0.0);
    for (int y = 0; y < 4; ++y) {
      for (int x = 0; x < 4; ++x) sum += texelFetch(u_src, min(p + ivec2(x, y), m), 0);
    }
    o_color = sum * 0.0625;
    return;
  }
  vec4 a = texture(u_src, uv + t * vec2(-2.0, 2.0));
  vec4 b = texture(u_src, uv + t * vec2(0.0, 2.0));
  vec4 c = texture(u_src, uv + t * vec2(2.0, 2.0));
  vec4 d = texture(u_src, uv + t * vec2(-2.0, 0.0));
  vec4 e = texture(u_src, uv);
  vec4 f = texture(u_src, uv + t * vec2(2.0, 0.0));
  vec4 g = texture(u_src, uv + t * vec2(-2.0, -2.0));
  vec4 h = texture(u_src, uv + t * vec2(0.0, -2.0));
  vec4 i = texture(u_src, uv + t * vec2(2.0, -2.0));
  vec4 j = texture(u_src, uv + t * vec2(-1.0, 1.0));
  vec4 k = texture(u_src, uv + t * vec2(1.0, 1.0));
  vec4 l = texture(u_src, uv + t * vec2(-1.0, -1.0));
  vec4 m = texture(u_src, uv + t * vec2(1.0, -1.0));
  o_color = e * 0.125 + (a + c + g + i) * 0.03125 + (b + d + f + h) * 0.0625 + (j + k + l + m) * 0.125;
}
)";

/// Upsample with a 3 x 3 tent (weights 1 2 1 / 2 4 2 / 1 2 1 over 16) of the coarser level,
/// mixed with this level's downsample: (1 - radius) down + radius tent(coarser).
inline constexpr char kBloomUpFs[] = R"(
uniform sampler2D u_coarse;
uniform sampler2D u_down;
uniform vec2 u_coarse_texel;  // 1 / coarser level size
uniform vec2 u_dst_size;
uniform float u_radius;
out vec4 o_color;
void main() {
  vec2 uv = gl_FragCoord.xy / u_dst_size;
  vec2 t = u_coarse_texel;
  vec4 s = texture(u_coarse, uv) * 4.0;
  s += (texture(u_coarse, uv + vec2(t.x, 0.0)) + texture(u_coarse, uv - vec2(t.x, 0.0)) +
        texture(u_coarse, uv + vec2(0.0, t.y)) + texture(u_coarse, uv - vec2(0.0, t.y))) * 2.0;
  s += texture(u_coarse, uv + t) + texture(u_coarse, uv - t) +
       texture(u_coarse, uv + vec2(t.x, -t.y)) + texture(u_coarse, uv + vec2(-t.x, t.y));
  o_color = mix(texelFetch(u_down, ivec2(gl_FragCoord.xy), 0), s / 16.0, u_radius);
}
)";

}  // namespace simreel::render::detail
