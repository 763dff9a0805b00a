#pragma once
/// @file mesh.hpp
/// Triangle meshes the renderer draws: plain arrays (no engine or assimp types), a material,
/// and helpers that build the shapes the program needs to show colliders (spheres, cylinders)
/// and the smooth normals of a deforming cloth.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace simreel::render {

/// Surface appearance of a mesh. Colours are linear RGB.
struct Material {
  Eigen::Vector4f base_color{0.8f, 0.8f, 0.8f, 1.f};  ///< linear RGBA; alpha is ignored (opaque)
  /// Image file (PNG/JPEG/BMP/TGA, sRGB-encoded) multiplied into base_color, sampled at the
  /// mesh's UVs with (0, 0) at the image's bottom-left corner and repeat wrapping. Read when the
  /// mesh is added; empty: none. Ignored when `texture_rgba` is given.
  std::string texture_path;
  /// In-memory texture instead of a file: RGBA8, rows top to bottom, sRGB-encoded,
  /// (texture_height x texture_width x 4) bytes.
  std::vector<std::uint8_t> texture_rgba;
  int texture_width = 0;   ///< (pixels) of texture_rgba
  int texture_height = 0;  ///< (pixels) of texture_rgba
  /// Draw both faces, each lit on the side facing the viewer (cloth, open surfaces). Otherwise
  /// back faces are culled: indices must wind counter-clockwise seen from outside.
  bool double_sided = false;
  /// (m) Procedural checker on the UV coordinates read as metres (the helpers below build UVs
  /// in metres of arc length); 0: none. Darkens alternate cells by 12 %, box-filtered.
  float checker_m = 0.f;
  float specular = 0.25f;  ///< Blinn-Phong highlight strength in [0, 1]
};

/// A run of a mesh's triangles drawn with its own material, sharing the mesh's vertices and
/// transform: a compound body's shapes, each in its own colour (glTF's primitives, assimp's
/// sub-meshes).
struct MeshPart {
  std::uint32_t first_triangle = 0;  ///< index of its first triangle (indices[3 * first_triangle])
  std::uint32_t triangle_count = 0;  ///< triangles in the run, >= 1
  Material material;
};

/// A static or deforming triangle mesh, in its local frame (set_transform places it).
struct MeshDesc {
  std::vector<float> positions;        ///< (n x 3) vertex positions, local frame (m)
  std::vector<float> normals;          ///< (n x 3) unit vertex normals; empty: computed (smooth)
  std::vector<float> uvs;              ///< (n x 2) texture coordinates; empty: all zero
  std::vector<std::uint32_t> indices;  ///< (m x 3) vertex indices of triangles, CCW from outside
  Material material;
  /// Empty: every triangle is drawn with `material`. Otherwise runs that tile the triangles in
  /// order (the first starts at 0, each starts where the one before ends, the last ends at the
  /// triangle count), each drawn with its own material; `material` is then unused.
  std::vector<MeshPart> parts;
  /// Vertex data will be replaced with Renderer::update_mesh every frame (cloth): stored in a
  /// GL buffer meant for frequent uploads. Static meshes can be updated too, just slower.
  bool dynamic = false;
};

/// Area-weighted smooth vertex normals: each triangle adds its unnormalised face normal
/// (cross product, |n| = 2 x area) to its three vertices; sums are normalised. Vertices in no
/// triangle (or only degenerate ones) get (0, 0, 1).
/// @param positions (n x 3) @param indices (m x 3) @param normals (n x 3) output
/// @throws std::invalid_argument if sizes disagree or an index is >= n.
void compute_vertex_normals(std::span<const float> positions, std::span<const std::uint32_t> indices,
                            std::span<float> normals);

/// UV sphere centred at the origin: `segments` slices around z (>= 3) and segments / 2 stacks
/// (>= 2), outward normals, UVs in metres (u: arc length along the equator from +x, v: arc
/// length from the south pole). @throws std::invalid_argument if radius <= 0 or segments < 3.
MeshDesc make_sphere_mesh(float radius, int segments);

/// Closed cylinder along z centred at the origin, from -half_height to +half_height, with flat
/// caps: `segments` (>= 3) sides with smooth normals, caps with normals +-z. UVs in metres
/// (side: arc length, height; caps: x, y). @throws std::invalid_argument if radius or
/// half_height <= 0 or segments < 3.
MeshDesc make_cylinder_mesh(float radius, float half_height, int segments);

/// Capsule along z centred at the origin: the segment from -half_height to +half_height grown by
/// `radius` (sim::ShapeDef::capsule), i.e. two hemispheres of `segments / 4` stacks (>= 1) joined
/// by a side band; `segments` (>= 3) slices around z, outward smooth normals, UVs in metres (u:
/// arc length around z, v: arc length from the south pole). @throws std::invalid_argument if
/// radius or half_height <= 0 or segments < 3.
MeshDesc make_capsule_mesh(float radius, float half_height, int segments);

}  // namespace simreel::render
