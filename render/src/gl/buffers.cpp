// Vertex/index buffers of lit geometry (gl/buffers.hpp).
#include "buffers.hpp"

#include <cstddef>

namespace simreel::render::detail {

GpuMesh upload_mesh(const GlTable& gl, const std::vector<Vertex>& vertices,
                    const std::vector<GLuint>& indices, GLenum usage) {
  GpuMesh m;
  gl.GenVertexArrays(1, &m.vao);
  gl.BindVertexArray(m.vao);
  gl.GenBuffers(1, &m.vbo);
  gl.BindBuffer(GL_ARRAY_BUFFER, m.vbo);
  gl.BufferData(GL_ARRAY_BUFFER, GLsizeiptr(vertices.size() * sizeof(Vertex)), vertices.data(), usage);
  gl.GenBuffers(1, &m.ebo);
  gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.ebo);
  gl.BufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(indices.size() * sizeof(GLuint)),
                indices.data(), GL_STATIC_DRAW);
  gl.EnableVertexAttribArray(0);
  gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                         reinterpret_cast<const void*>(offsetof(Vertex, p)));
  gl.EnableVertexAttribArray(1);
  gl.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                         reinterpret_cast<const void*>(offsetof(Vertex, n)));
  gl.EnableVertexAttribArray(2);
  gl.VertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                         reinterpret_cast<const void*>(offsetof(Vertex, uv)));
  gl.BindVertexArray(0);
  m.index_count = GLsizei(indices.size());
  return m;
}

void destroy_mesh(const GlTable& gl, GpuMesh& m) noexcept {
  if (m.vao != 0) gl.DeleteVertexArrays(1, &m.vao);
  if (m.vbo != 0) gl.DeleteBuffers(1, &m.vbo);
  if (m.ebo != 0) gl.DeleteBuffers(1, &m.ebo);
  m = GpuMesh{};
}

}  // namespace simreel::render::detail
