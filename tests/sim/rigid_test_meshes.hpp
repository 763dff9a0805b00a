#pragma once
// Closed, outward-wound triangle meshes for the rigid-body tests: a box, an icosphere, a
// hemisphere. Vertices in metres, triangles counter-clockwise seen from outside.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <utility>
#include <vector>

#include "simreel/sim/types.hpp"

namespace simreel::sim::test {

struct Mesh {
  std::vector<Vec3> vertices;                           ///< (n) positions (m)
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< (m) outward winding
};

/// Box centred at the origin with half extents h: 8 corners (index = x + 2y + 4z bits), 12
/// triangles.
inline Mesh box_mesh(const Vec3& h) {
  Mesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z());
  m.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                 {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return m;
}

/// Icosahedron subdivided `level` times (each triangle into four, edge length halved), vertices
/// pushed onto the sphere of `radius`: 20 · 4^level triangles, inscribed in the sphere.
inline Mesh icosphere(int level, double radius) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  Mesh m;
  m.vertices = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& v : m.vertices) v = v.normalized() * radius;
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoint;
    const auto mid = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      m.vertices.push_back((m.vertices[a] + m.vertices[b]).normalized() * radius);
      const auto index = std::uint32_t(m.vertices.size() - 1);
      midpoint.emplace(key, index);
      return index;
    };
    std::vector<std::array<std::uint32_t, 3>> finer;
    for (const auto& [a, b, c] : m.triangles) {
      const std::uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      finer.push_back({a, ab, ca});
      finer.push_back({b, bc, ab});
      finer.push_back({c, ca, bc});
      finer.push_back({ab, bc, ca});
    }
    m.triangles = std::move(finer);
  }
  return m;
}

/// Solid hemisphere of `radius`, flat face on z = 0, dome up: `n_lon` meridians, `n_lat` rings
/// from the pole to the equator, the flat face as a fan around its centre.
inline Mesh hemisphere_mesh(double radius, std::uint32_t n_lon, std::uint32_t n_lat) {
  Mesh m;
  m.vertices.emplace_back(0, 0, radius);  // pole, index 0
  for (std::uint32_t i = 1; i <= n_lat; ++i) {
    const double theta = std::numbers::pi / 2 * double(i) / double(n_lat);
    for (std::uint32_t j = 0; j < n_lon; ++j) {
      const double phi = 2 * std::numbers::pi * double(j) / double(n_lon);
      m.vertices.emplace_back(radius * std::sin(theta) * std::cos(phi),
                              radius * std::sin(theta) * std::sin(phi), radius * std::cos(theta));
    }
  }
  const auto centre = std::uint32_t(m.vertices.size());
  m.vertices.emplace_back(0, 0, 0);
  const auto ring = [&](std::uint32_t i, std::uint32_t j) {
    return 1 + (i - 1) * n_lon + j % n_lon;
  };
  for (std::uint32_t j = 0; j < n_lon; ++j) {
    m.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
    for (std::uint32_t i = 1; i < n_lat; ++i) {
      const std::uint32_t a = ring(i, j), b = ring(i, j + 1), c = ring(i + 1, j),
                          d = ring(i + 1, j + 1);
      m.triangles.push_back({a, c, d});
      m.triangles.push_back({a, d, b});
    }
    m.triangles.push_back({centre, ring(n_lat, j + 1), ring(n_lat, j)});
  }
  return m;
}

}  // namespace simreel::sim::test
