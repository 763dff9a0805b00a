#pragma once
// Private: GLSL pieces several passes share. Everything is shaded in linear RGB into a
// half-float target; the post pass alone tone-maps, gamma-encodes and dithers to 8 bits.
namespace simreel::render::detail {

/// Hemisphere sky light: the sky's colour from above, the ground's bounce from below.
inline constexpr char kAmbientGlsl[] = R"(
uniform vec3 u_ambient;          // facing +z
uniform vec3 u_ground_ambient;   // facing -z
vec3 hemisphere(float nz) { return mix(u_ground_ambient, u_ambient, 0.5 + 0.5 * nz); }
// x^48 by squaring (x^32 x^16): pow() is exp2(log2) on llvmpipe, several times the cost.
float pow48(float x) {
  float x2 = x * x, x4 = x2 * x2, x8 = x4 * x4, x16 = x8 * x8;
  return x16 * x16 * x16;
}
)";

/// A sphere sprite's corners; each vertex carries its particle's data (ParticlePass). The
/// shaders keep only the unit disc, so any shape around it draws the same sprite. Small sprites
/// (u_sprite_vertices 3) are one triangle, the equilateral one whose inscribed circle is the
/// disc (ParticlePass::sprite_vertices): llvmpipe sets up and shades every triangle on its own, and a sprite of a few pixels
/// costs about a triangle's fixed cost, so a quad's two cost about twice as much. Big sprites
/// (4) are an indexed quad [-1, 1]^2: the triangle's 30 % more area (3 sqrt(3) against 4) would
/// cost more in fragments than the second triangle's set-up.
inline constexpr char kSpriteCornerGlsl[] = R"(
uniform int u_sprite_vertices;  // 3: one triangle per sprite; 4: an indexed quad
// This vertex's corner in sprite units (radii): (0, 2), (-sqrt(3), -1), (sqrt(3), -1) for a
// triangle; (-1, -1), (1, -1), (-1, 1), (1, 1) for a quad.
vec2 sprite_corner() {
  if (u_sprite_vertices == 4) {
    return vec2((gl_VertexID & 1) != 0 ? 1.0 : -1.0, (gl_VertexID & 2) != 0 ? 1.0 : -1.0);
  }
  int k = gl_VertexID % 3;
  return k == 0 ? vec2(0.0, 2.0) : vec2(k == 1 ? -1.7320508 : 1.7320508, -1.0);
}
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
