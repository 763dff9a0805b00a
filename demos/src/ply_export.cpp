#include "ply_export.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

namespace simreel::app {

namespace {

template <class T>
void put(std::string& s, const T& v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof v);
}

std::uint8_t to_byte(float c) {
  const float x = std::clamp(c, 0.0f, 1.0f) * 255.0f + 0.5f;
  return std::uint8_t(x);
}

const char kVertexProperties[] =
    "property float x\nproperty float y\nproperty float z\n"
    "property float vx\nproperty float vy\nproperty float vz\n"
    "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
    "property float radius\nproperty uint id\n";

}  // namespace

void particles_ply(const sim::ParticleView& v, std::string& out) {
  out.clear();
  out += "ply\nformat binary_little_endian 1.0\ncomment simreel particles (SI units, z up)\n";
  out += "element vertex " + std::to_string(v.count) + "\n";
  out += kVertexProperties;
  out += "end_header\n";
  out.reserve(out.size() + v.count * 36);
  for (std::size_t i = 0; i < v.count; ++i) {
    for (int k = 0; k < 3; ++k) put(out, v.position[3 * i + k]);
    for (int k = 0; k < 3; ++k) put(out, v.velocity[3 * i + k]);
    for (int k = 0; k < 4; ++k) put(out, to_byte(v.color[4 * i + k]));
    put(out, v.radius[i]);
    put(out, std::uint32_t(v.id[i]));
  }
}

void cloth_ply(const sim::ClothView& v, const float rgba[4], float radius, std::string& out) {
  out.clear();
  out += "ply\nformat binary_little_endian 1.0\ncomment simreel cloth (SI units, z up)\n";
  out += "element vertex " + std::to_string(v.vertex_count) + "\n";
  out += kVertexProperties;
  out += "property float nx\nproperty float ny\nproperty float nz\n";
  out += "element face " + std::to_string(v.triangle_count) + "\n";
  out += "property list uchar uint vertex_indices\n";
  out += "end_header\n";
  std::uint8_t c[4];
  for (int k = 0; k < 4; ++k) c[k] = to_byte(rgba[k]);
  for (std::size_t i = 0; i < v.vertex_count; ++i) {
    for (int k = 0; k < 3; ++k) put(out, v.positions[3 * i + k]);
    for (int k = 0; k < 3; ++k) put(out, v.velocities[3 * i + k]);
    for (int k = 0; k < 4; ++k) put(out, c[k]);
    put(out, radius);
    put(out, std::uint32_t(i));
    for (int k = 0; k < 3; ++k) put(out, v.normals[3 * i + k]);
  }
  for (std::size_t t = 0; t < v.triangle_count; ++t) {
    put(out, std::uint8_t(3));
    for (int k = 0; k < 3; ++k) put(out, v.triangles[3 * t + k]);
  }
}

std::filesystem::path ply_file(const std::filesystem::path& dir, const std::string& object, int index, int frame) {
  char name[64];
  std::snprintf(name, sizeof name, "%s%d.%05d.ply", object.c_str(), index, frame);
  return dir / "ply" / name;
}

}  // namespace simreel::app
