#pragma once
// Private: vertex and index buffers of lit geometry (planes, boxes, meshes, cloth).

#include <vector>

#include "simreel/render/gl_table.hpp"

namespace simreel::render::detail {

/// Interleaved vertex: position (3, m, local frame), normal (3), plane or texture coordinates
/// (2; for planes in metres). Attribute locations 0, 1, 2.
struct Vertex {
  float p[3];
  float n[3];
  float uv[2];
};

/// A vertex array with its vertex and index buffers (GL_UNSIGNED_INT triangles).
struct GpuMesh {
  GLuint vao = 0;
  GLuint vbo = 0;
  GLuint ebo = 0;
  GLsizei index_count = 0;
};

/// Creates the buffers and the vertex array (attributes 0..2 as Vertex); leaves no vertex array
/// bound. `usage` is the vertex buffer's (GL_DYNAMIC_DRAW for cloth); indices are static.
GpuMesh upload_mesh(const GlTable& gl, const std::vector<Vertex>& vertices,
                    const std::vector<GLuint>& indices, GLenum usage = GL_STATIC_DRAW);
/// Deletes what upload_mesh made and resets `m`; a null mesh is fine.
void destroy_mesh(const GlTable& gl, GpuMesh& m) noexcept;

}  // namespace simreel::render::detail
