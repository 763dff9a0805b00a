// Cloth topology (Coutinho §3.9.2, fig. 3.45): the grid's stretch, shear and bend springs and
// the vertex adjacency, built once and shared by every instance of the same grid.
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

#include "simreel/sim/cloth.hpp"

namespace simreel::sim {

ClothTopology::ClothTopology(std::size_t rows_, std::size_t columns_, double width_,
                             double height_)
    : rows(rows_), columns(columns_), width(width_), height(height_) {
  if (rows < 1 || columns < 1 || rows * columns < 2)
    throw std::invalid_argument("ClothTopology: rows, columns >= 1 and rows * columns >= 2");
  if ((columns > 1 && (!(width > 0.0) || !std::isfinite(width))) ||
      (rows > 1 && (!(height > 0.0) || !std::isfinite(height))))
    throw std::invalid_argument("ClothTopology: width and height must be > 0 and finite");
  const std::size_t n = rows * columns;
  const double dx = columns > 1 ? width / double(columns - 1) : 0.0;
  const double dy = rows > 1 ? height / double(rows - 1) : 0.0;
  local_rest.resize(n);
  uvs.resize(2 * n);
  auto id = [this](std::size_t r, std::size_t c) { return std::uint32_t(r * columns + c); };
  for (std::size_t r = 0; r < rows; ++r)
    for (std::size_t c = 0; c < columns; ++c) {
      const std::size_t i = id(r, c);
      local_rest[i] = Vec3(columns > 1 ? -0.5 * width + double(c) * dx : 0.0,
                           rows > 1 ? 0.5 * height - double(r) * dy : 0.0, 0.0);
      uvs[2 * i] = columns > 1 ? float(double(c) / double(columns - 1)) : 0.5f;
      uvs[2 * i + 1] = rows > 1 ? float(double(r) / double(rows - 1)) : 0.5f;
    }
  auto add = [&](std::uint32_t a, std::uint32_t b, SpringKind k) {
    spring_a.push_back(std::min(a, b));
    spring_b.push_back(std::max(a, b));
    rest_length.push_back((local_rest[a] - local_rest[b]).norm());
    kind.push_back(k);
  };
  for (std::size_t r = 0; r < rows; ++r)
    for (std::size_t c = 0; c < columns; ++c) {
      if (r + 1 < rows) add(id(r, c), id(r + 1, c), SpringKind::stretch);
      if (c + 1 < columns) add(id(r, c), id(r, c + 1), SpringKind::stretch);
    }
  for (std::size_t r = 0; r + 1 < rows; ++r)
    for (std::size_t c = 0; c + 1 < columns; ++c) {
      add(id(r, c), id(r + 1, c + 1), SpringKind::shear);
      add(id(r + 1, c), id(r, c + 1), SpringKind::shear);
    }
  limited_count = spring_a.size();
  for (std::size_t r = 0; r < rows; ++r)
    for (std::size_t c = 0; c < columns; ++c) {
      if (r + 2 < rows) add(id(r, c), id(r + 2, c), SpringKind::bend);
      if (c + 2 < columns) add(id(r, c), id(r, c + 2), SpringKind::bend);
    }
  // Triangles: each cell split along (r, c)-(r+1, c+1) as in §3.9.2; counter-clockwise seen from
  // local +z (row index grows towards -y).
  for (std::size_t r = 0; r + 1 < rows; ++r)
    for (std::size_t c = 0; c + 1 < columns; ++c) {
      const std::uint32_t a = id(r, c), b = id(r, c + 1), cc = id(r + 1, c), d = id(r + 1, c + 1);
      triangles.insert(triangles.end(), {a, cc, d, a, d, b});
    }
  finish();
}

/// Unique edges and the vertex → spring adjacency, from the springs and triangles.
void ClothTopology::finish() {
  // Unique edges of the triangles, each with the first triangle holding it.
  {
    std::vector<std::array<std::uint32_t, 3>> e;  // (a, b, triangle * 3 + k)
    for (std::size_t t = 0; 3 * t < triangles.size(); ++t)
      for (std::uint32_t k = 0; k < 3; ++k) {
        const std::uint32_t i = triangles[3 * t + k], j = triangles[3 * t + (k + 1) % 3];
        e.push_back({std::min(i, j), std::max(i, j), std::uint32_t(3 * t + k)});
      }
    std::sort(e.begin(), e.end());
    triangle_edges.assign(triangles.size(), 0);
    for (std::size_t k = 0; k < e.size(); ++k) {
      if (k == 0 || e[k][0] != e[k - 1][0] || e[k][1] != e[k - 1][1]) {
        edges.push_back(e[k][0]);
        edges.push_back(e[k][1]);
        edge_triangle.push_back(e[k][2] / 3);
      }
      triangle_edges[e[k][2]] = std::uint32_t(edge_triangle.size() - 1);
    }
  }
  vertex_triangle.assign(local_rest.size(), std::numeric_limits<std::uint32_t>::max());
  for (std::size_t k = triangles.size(); k-- > 0;) vertex_triangle[triangles[k]] = std::uint32_t(k / 3);
  // Adjacency in CSR form, springs of each vertex in spring order (a fixed summation order).
  const std::size_t n = local_rest.size();
  adj_start.assign(n + 1, 0);
  for (std::size_t s = 0; s < spring_a.size(); ++s) {
    ++adj_start[spring_a[s] + 1];
    ++adj_start[spring_b[s] + 1];
  }
  for (std::size_t i = 0; i < n; ++i) adj_start[i + 1] += adj_start[i];
  adj_spring.resize(adj_start[n]);
  adj_other.resize(adj_start[n]);
  std::vector<std::uint32_t> fill(adj_start.begin(), adj_start.end() - 1);
  for (std::size_t s = 0; s < spring_a.size(); ++s) {
    const std::uint32_t a = spring_a[s], b = spring_b[s];
    adj_spring[fill[a]] = std::uint32_t(s);
    adj_other[fill[a]++] = b;
    adj_spring[fill[b]] = std::uint32_t(s);
    adj_other[fill[b]++] = a;
  }
}

ClothTopology::ClothTopology(const ClothMesh& mesh)
    : rows(1), columns(mesh.vertices.size()), from_mesh(true) {
  const std::size_t n = mesh.vertices.size();
  if (n < 3 || mesh.triangles.empty() || mesh.triangles.size() % 3 != 0)
    throw std::invalid_argument("ClothTopology: a mesh needs >= 3 vertices and whole triangles");
  if (!mesh.uvs.empty() && mesh.uvs.size() != 2 * n)
    throw std::invalid_argument("ClothTopology: mesh uvs must hold 2 floats per vertex or none");
  for (const Vec3& p : mesh.vertices)
    if (!p.allFinite()) throw std::invalid_argument("ClothTopology: non-finite mesh vertex");
  for (std::size_t t = 0; 3 * t < mesh.triangles.size(); ++t) {
    const std::uint32_t a = mesh.triangles[3 * t], b = mesh.triangles[3 * t + 1],
                        c = mesh.triangles[3 * t + 2];
    if (a >= n || b >= n || c >= n)
      throw std::invalid_argument("ClothTopology: mesh triangle " + std::to_string(t) +
                                  " names a vertex beyond the " + std::to_string(n) + " given");
    if (a == b || b == c || a == c ||
        !((mesh.vertices[b] - mesh.vertices[a]).cross(mesh.vertices[c] - mesh.vertices[a]).norm() > 0.0))
      throw std::invalid_argument("ClothTopology: mesh triangle " + std::to_string(t) +
                                  " is degenerate (zero area)");
  }
  local_rest = mesh.vertices;
  triangles = mesh.triangles;
  if (!mesh.uvs.empty()) {
    uvs = mesh.uvs;
  } else {  // planar from the local x, y extent
    Vec3 lo = local_rest[0], hi = local_rest[0];
    for (const Vec3& p : local_rest) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const Vec3 ext = (hi - lo).cwiseMax(Vec3::Constant(1e-12));
    uvs.resize(2 * n);
    for (std::size_t i = 0; i < n; ++i) {
      uvs[2 * i] = float((local_rest[i].x() - lo.x()) / ext.x());
      uvs[2 * i + 1] = float((hi.y() - local_rest[i].y()) / ext.y());
    }
  }
  // Stretch springs on the edges; across each edge shared by two triangles a spring between the
  // two opposite vertices: shear when it is about as long as the edge (the other diagonal of a
  // quad split in two, as the grid's second shear spring), bend when longer (it resists folding
  // about the edge, the role of the grid's bend springs).
  std::vector<std::array<std::uint32_t, 3>> e;  // (a, b, opposite vertex)
  for (std::size_t t = 0; 3 * t < triangles.size(); ++t)
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::uint32_t i = triangles[3 * t + k], j = triangles[3 * t + (k + 1) % 3],
                          o = triangles[3 * t + (k + 2) % 3];
      e.push_back({std::min(i, j), std::max(i, j), o});
    }
  std::sort(e.begin(), e.end());
  std::vector<std::array<std::uint32_t, 2>> stretch, shear, bend;
  for (std::size_t k = 0; k < e.size(); ++k) {
    if (k > 0 && e[k][0] == e[k - 1][0] && e[k][1] == e[k - 1][1]) {
      const std::uint32_t o1 = e[k - 1][2], o2 = e[k][2];
      if (o1 == o2) continue;
      const double edge = (local_rest[e[k][0]] - local_rest[e[k][1]]).norm();
      const double across = (local_rest[o1] - local_rest[o2]).norm();
      (across < 1.5 * edge ? shear : bend).push_back({std::min(o1, o2), std::max(o1, o2)});
      continue;
    }
    stretch.push_back({e[k][0], e[k][1]});
  }
  // One spring per vertex pair, the first family wins (an edge is never also a shear spring).
  std::vector<std::array<std::uint32_t, 2>> seen(stretch);
  std::sort(seen.begin(), seen.end());
  auto add_family = [&](std::vector<std::array<std::uint32_t, 2>>& fam, SpringKind kd) {
    std::sort(fam.begin(), fam.end());
    fam.erase(std::unique(fam.begin(), fam.end()), fam.end());
    std::vector<std::array<std::uint32_t, 2>> kept;
    for (const auto& pr : fam) {
      if (kd != SpringKind::stretch && std::binary_search(seen.begin(), seen.end(), pr)) continue;
      kept.push_back(pr);
      spring_a.push_back(pr[0]);
      spring_b.push_back(pr[1]);
      const double L = (local_rest[pr[0]] - local_rest[pr[1]]).norm();
      if (!(L > 0.0))
        throw std::invalid_argument("ClothTopology: mesh vertices " + std::to_string(pr[0]) +
                                    " and " + std::to_string(pr[1]) +
                                    " are joined but at the same place (zero rest length)");
      rest_length.push_back(L);
      kind.push_back(kd);
    }
    if (kd != SpringKind::stretch) {
      seen.insert(seen.end(), kept.begin(), kept.end());
      std::sort(seen.begin(), seen.end());
    }
  };
  add_family(stretch, SpringKind::stretch);
  add_family(shear, SpringKind::shear);
  limited_count = spring_a.size();
  add_family(bend, SpringKind::bend);
  finish();
}

}  // namespace simreel::sim
