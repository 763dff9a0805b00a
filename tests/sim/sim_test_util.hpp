#pragma once
// Helpers shared by the sim tests: single-particle worlds, view accessors, one-shape bodies.

#include <cstddef>
#include <cstdint>

#include "simreel/sim/world.hpp"

namespace simreel::sim::test {

/// A system that never emits on its own (rate 0): particles come from World::spawn_particle.
inline ParticleSystemDef spawn_only_system(const char* name = "probe") {
  ParticleSystemDef def;
  def.name = name;
  def.emitter.rate = 0.0;
  def.emitter.max_particles = 1000;
  return def;
}

/// A blast field (forces.hpp FieldKind::blast) of momentum Pi (N s) from `centre` at `time` (s),
/// everywhere, on bodies and every particle system.
inline ForceFieldDef blast_field(const Vec3& centre, double Pi, double time) {
  ForceFieldDef f;
  f.kind = FieldKind::blast;
  f.transform.translation = centre;
  f.impulse = Pi;
  f.time = time;
  return f;
}

/// An n x n height field over [-half, half]² (m): vertices z = height(x, y) on the grid, two
/// triangles a square wound counter-clockwise from +z, appended to d (a MeshDef or a ShapeDef).
template <class Def, class Height>
void fill_height_field(Def& d, int n, double half, const Height& height) {
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = -half + 2.0 * half * i / n, y = -half + 2.0 * half * j / n;
      d.vertices.emplace_back(x, y, height(x, y));
    }
  const auto at = [&](int i, int j) { return std::uint32_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      d.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      d.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
}

inline Vec3 position_of(const ParticleView& v, std::size_t i) {
  return {v.position[3 * i], v.position[3 * i + 1], v.position[3 * i + 2]};
}
inline Vec3 velocity_of(const ParticleView& v, std::size_t i) {
  return {v.velocity[3 * i], v.velocity[3 * i + 1], v.velocity[3 * i + 2]};
}

/// A dynamic body of one shape at `position` (identity rotation) with material m.
inline BodyDef dynamic_body(ShapeDef shape, const Vec3& position, const Material& m = {0.0, 0.5}) {
  BodyDef b;
  b.type = BodyType::dynamic;
  b.pose.translation = position;
  shape.material = m;
  b.shapes.push_back(shape);
  return b;
}

/// A static ground: the plane z = 0 with material m.
inline BodyDef ground_plane(const Material& m = {0.0, 0.5}) {
  BodyDef g;
  ShapeDef p = ShapeDef::plane();
  p.material = m;
  g.shapes.push_back(p);
  return g;
}

}  // namespace simreel::sim::test
