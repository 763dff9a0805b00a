#include "simreel/render/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

namespace simreel::render {

void compute_vertex_normals(std::span<const float> positions, std::span<const std::uint32_t> indices,
                            std::span<float> normals) {
  if (positions.size() % 3 != 0 || indices.size() % 3 != 0 || normals.size() != positions.size()) {
    throw std::invalid_argument(
        "compute_vertex_normals: positions and normals need n x 3 floats each, indices m x 3");
  }
  const std::size_t n = positions.size() / 3;
  std::fill(normals.begin(), normals.end(), 0.f);
  using V = Eigen::Vector3f;
  auto at = [&](std::uint32_t i) { return V(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]); };
  for (std::size_t t = 0; t < indices.size(); t += 3) {
    const std::uint32_t a = indices[t], b = indices[t + 1], c = indices[t + 2];
    if (a >= n || b >= n || c >= n) {
      throw std::invalid_argument("compute_vertex_normals: triangle " + std::to_string(t / 3) +
                                  " has an index >= the vertex count " + std::to_string(n));
    }
    // The unnormalised cross product weights each face by its area.
    const V face = (at(b) - at(a)).cross(at(c) - at(a));
    for (const std::uint32_t i : {a, b, c}) {
      for (int k = 0; k < 3; ++k) normals[3 * i + k] += face[k];
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    float* v = &normals[3 * i];
    const float len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (len > 0.f) {
      v[0] /= len;
      v[1] /= len;
      v[2] /= len;
    } else {
      v[0] = 0.f;
      v[1] = 0.f;
      v[2] = 1.f;
    }
  }
}

MeshDesc make_sphere_mesh(float radius, int segments) {
  if (!(radius > 0.f) || segments < 3) {
    throw std::invalid_argument("make_sphere_mesh needs radius > 0 and segments >= 3");
  }
  const int slices = segments;
  const int stacks = std::max(segments / 2, 2);
  const float pi = std::numbers::pi_v<float>;
  MeshDesc m;
  // A seam column (slice == slices) duplicates the first so UVs do not wrap back across it.
  for (int j = 0; j <= stacks; ++j) {
    const float theta = pi * float(j) / float(stacks);  // from the south pole
    const float z = -std::cos(theta);
    const float ring = std::sin(theta);
    for (int i = 0; i <= slices; ++i) {
      const float phi = 2.f * pi * float(i) / float(slices);
      const float nx = ring * std::cos(phi), ny = ring * std::sin(phi);
      m.positions.insert(m.positions.end(), {radius * nx, radius * ny, radius * z});
      m.normals.insert(m.normals.end(), {nx, ny, z});
      m.uvs.insert(m.uvs.end(), {radius * phi, radius * theta});
    }
  }
  const auto row = std::uint32_t(slices + 1);
  for (int j = 0; j < stacks; ++j) {
    for (int i = 0; i < slices; ++i) {
      const std::uint32_t a = std::uint32_t(j) * row + std::uint32_t(i);
      const std::uint32_t b = a + 1, c = a + row, d = a + row + 1;
      // Counter-clockwise seen from outside; the pole rows' degenerate triangles are dropped.
      if (j != 0) m.indices.insert(m.indices.end(), {a, b, d});
      if (j != stacks - 1) m.indices.insert(m.indices.end(), {a, d, c});
    }
  }
  return m;
}

MeshDesc make_capsule_mesh(float radius, float half_height, int segments) {
  if (!(radius > 0.f) || !(half_height > 0.f) || segments < 3) {
    throw std::invalid_argument("make_capsule_mesh needs radius > 0, half_height > 0 and segments >= 3");
  }
  // A UV sphere cut at its equator, the halves moved apart by 2 half_height: the equator ring is
  // there twice (z = -half_height and +half_height) and the band between them is the side.
  const int slices = segments;
  const int half_stacks = std::max(segments / 4, 1);
  const float pi = std::numbers::pi_v<float>;
  MeshDesc m;
  int rows = 0;
  for (int hemisphere = 0; hemisphere < 2; ++hemisphere) {
    const float shift = hemisphere == 0 ? -half_height : half_height;
    for (int k = 0; k <= half_stacks; ++k) {
      const int j = hemisphere == 0 ? k : half_stacks + k;  // stack index over the whole sphere
      const float theta = pi * float(j) / float(2 * half_stacks);
      const float z = -std::cos(theta);
      const float ring = std::sin(theta);
      for (int i = 0; i <= slices; ++i) {
        const float phi = 2.f * pi * float(i) / float(slices);
        const float nx = ring * std::cos(phi), ny = ring * std::sin(phi);
        m.positions.insert(m.positions.end(), {radius * nx, radius * ny, radius * z + shift});
        m.normals.insert(m.normals.end(), {nx, ny, z});
        m.uvs.insert(m.uvs.end(), {radius * phi, radius * theta + (hemisphere == 0 ? 0.f : 2.f * half_height)});
      }
      ++rows;
    }
  }
  const auto row = std::uint32_t(slices + 1);
  for (int j = 0; j + 1 < rows; ++j) {
    for (int i = 0; i < slices; ++i) {
      const std::uint32_t a = std::uint32_t(j) * row + std::uint32_t(i);
      const std::uint32_t b = a + 1, c = a + row, d = a + row + 1;
      if (j != 0) m.indices.insert(m.indices.end(), {a, b, d});
      if (j != rows - 2) m.indices.insert(m.indices.end(), {a, d, c});
    }
  }
  return m;
}

MeshDesc make_cylinder_mesh(float radius, float half_height, int segments) {
  if (!(radius > 0.f) || !(half_height > 0.f) || segments < 3) {
    throw std::invalid_argument("make_cylinder_mesh needs radius > 0, half_height > 0 and segments >= 3");
  }
  const float pi = std::numbers::pi_v<float>;
  MeshDesc m;
  auto vertex = [&m](float x, float y, float z, float nx, float ny, float nz, float u, float v) {
    m.positions.insert(m.positions.end(), {x, y, z});
    m.normals.insert(m.normals.end(), {nx, ny, nz});
    m.uvs.insert(m.uvs.end(), {u, v});
    return std::uint32_t(m.positions.size() / 3 - 1);
  };
  // Side: two rings with a seam column.
  for (int i = 0; i <= segments; ++i) {
    const float phi = 2.f * pi * float(i) / float(segments);
    const float c = std::cos(phi), s = std::sin(phi);
    vertex(radius * c, radius * s, -half_height, c, s, 0.f, radius * phi, 0.f);
    vertex(radius * c, radius * s, half_height, c, s, 0.f, radius * phi, 2.f * half_height);
  }
  for (int i = 0; i < segments; ++i) {
    const std::uint32_t a = std::uint32_t(2 * i), b = a + 2, c = a + 1, d = a + 3;
    m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
  }
  // Caps: a centre vertex and a ring each, flat normals.
  for (const float sign : {-1.f, 1.f}) {
    const std::uint32_t centre = vertex(0.f, 0.f, sign * half_height, 0.f, 0.f, sign, 0.f, 0.f);
    for (int i = 0; i < segments; ++i) {
      const float phi = 2.f * pi * float(i) / float(segments);
      const float x = radius * std::cos(phi), y = radius * std::sin(phi);
      vertex(x, y, sign * half_height, 0.f, 0.f, sign, x, y);
    }
    for (int i = 0; i < segments; ++i) {
      const std::uint32_t a = centre + 1 + std::uint32_t(i);
      const std::uint32_t b = centre + 1 + std::uint32_t((i + 1) % segments);
      if (sign > 0.f) {
        m.indices.insert(m.indices.end(), {centre, a, b});
      } else {
        m.indices.insert(m.indices.end(), {centre, b, a});
      }
    }
  }
  return m;
}

}  // namespace simreel::render
