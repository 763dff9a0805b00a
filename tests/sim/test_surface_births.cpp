// Births on a surface (issue 15, Coutinho §3.4.2): a particle born on a solid's surface, within
// float rounding, is not inside and must not be removed; one inside by more than the surface
// tolerance (1e-6 of the shape's size plus a few float ulps of its coordinates) still is.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>

#include "sim_test_util.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

const Vec3 kC{0.37, -1.21, 2.05};  // shape centre, off the origin so coordinates round

ParticleSystemDef still_system() {
  ParticleSystemDef def = test::spawn_only_system();
  def.gravity = Vec3::Zero();
  def.emitter.max_particles = 200000;
  return def;
}

/// A closed cube mesh of half extent h centred on kC (12 triangles, outward normals).
MeshDef cube(double h) {
  MeshDef d;
  for (int k = 0; k < 8; ++k)
    d.vertices.emplace_back((k & 1 ? 1 : -1) * h, (k & 2 ? 1 : -1) * h, (k & 4 ? 1 : -1) * h);
  d.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                 {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  d.transform.translation = kC;
  return d;
}

/// The emitter on the sphere of radius R at kC, or on the cube mesh's surface, at `rate`,
/// particles at rest: none may be removed over 1 s.
std::uint64_t removed_from_emitter(bool mesh, double rate) {
  const double R = 0.5;
  World world(WorldDef{1.0 / 240, 1, 0.05});
  ParticleSystemDef def = still_system();
  def.emitter.rate = rate;
  def.emitter.start_speed = {0.0, 0.0, 0.0, 0.0};
  def.emitter.radius = {0.01, 0.0, 1e-6};
  def.emitter.transform.translation = kC;
  if (mesh) {
    const MeshDef m = cube(R);
    world.add_mesh(m);
    def.emitter.shape = EmitterShape::mesh;
    for (const Vec3& v : m.vertices)
      for (int k = 0; k < 3; ++k) def.emitter.mesh_positions.push_back(v[k]);
    for (const auto& t : m.triangles)
      for (int k = 0; k < 3; ++k) def.emitter.mesh_triangles.push_back(t[k]);
  } else {
    SphereDef s;
    s.radius = R;
    s.transform.translation = kC;
    world.add_sphere(s);
    def.emitter.shape = EmitterShape::sphere;
    def.emitter.sphere_radius = R;
  }
  const auto ps = world.add_particle_system(def);
  for (int f = 0; f < 30; ++f) world.advance(1.0 / 30);
  EXPECT_GT(world.particles(ps).count, std::size_t(0.5 * rate));
  return world.removed_inside_count(ps);
}

TEST(SurfaceBirths, SphereAndMeshEmittersOnTheirColliderLoseNone) {
  for (double rate : {300.0, 3000.0, 30000.0}) {
    EXPECT_EQ(removed_from_emitter(false, rate), 0u) << "sphere, rate " << rate;
    EXPECT_EQ(removed_from_emitter(true, rate), 0u) << "mesh, rate " << rate;
  }
}

/// Spawns n particles at points on a shape's surface (`surface(u, v, w)` from uniform draws, then
/// rounded to float as stored) and one just inside; advances one step.
void check_kind(const char* kind, const std::function<void(World&)>& add,
                const std::function<Vec3(double, double, double)>& surface, const Vec3& inside,
                bool removable) {
  for (int n : {100, 1000, 10000}) {
    World world(WorldDef{1.0 / 240, 1, 0.05});
    add(world);
    const auto ps = world.add_particle_system(still_system());
    std::mt19937_64 rng{std::uint64_t(n)};
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    for (int i = 0; i < n; ++i)
      world.spawn_particle(ps, surface(u01(rng), u01(rng), u01(rng)), Vec3::Zero(), 0.01, 0.01, 100.0);
    world.advance(1.0 / 240);
    EXPECT_EQ(world.removed_inside_count(ps), 0u) << kind << ", n " << n;
    world.spawn_particle(ps, inside, Vec3::Zero(), 0.01, 0.01, 100.0);
    world.advance(1.0 / 240);
    EXPECT_EQ(world.removed_inside_count(ps), removable ? 1u : 0u) << kind << " inside";
  }
}

Vec3 on_sphere(double u, double v, double R) {
  const double z = 2.0 * u - 1.0, ph = 2.0 * std::numbers::pi * v, s = std::sqrt(1.0 - z * z);
  return Vec3(R * s * std::cos(ph), R * s * std::sin(ph), R * z);
}

TEST(SurfaceBirths, ParticlesOnEveryColliderKindSurviveAndInsideOnesAreRemoved) {
  const double R = 0.5, H = 0.7;
  const double in = 1.0 - 1e-4;  // inside by 1e-4 of the size: far beyond the tolerance
  check_kind(
      "sphere",
      [&](World& w) {
        SphereDef s;
        s.radius = R;
        s.transform.translation = kC;
        w.add_sphere(s);
      },
      [&](double u, double v, double) { return Vec3(kC + on_sphere(u, v, R)); },
      kC + Vec3(R * in, 0, 0), true);
  check_kind(
      "cylinder",
      [&](World& w) {
        CylinderDef c;
        c.radius = R;
        c.half_height = H;
        c.transform.translation = kC;
        w.add_cylinder(c);
      },
      [&](double u, double v, double w) {
        const double ph = 2.0 * std::numbers::pi * v;
        if (w < 0.5) return Vec3(kC + Vec3(R * std::cos(ph), R * std::sin(ph), H * (2 * u - 1)));
        const double r = R * std::sqrt(u);  // a cap
        return Vec3(kC + Vec3(r * std::cos(ph), r * std::sin(ph), w < 0.75 ? H : -H));
      },
      kC + Vec3(0, 0, H * in), true);
  check_kind(
      "capsule",
      [&](World& w) {
        BodyDef b;
        b.pose.translation = kC;
        b.shapes = {ShapeDef::capsule(R, H)};
        w.add_body(b);
      },
      [&](double u, double v, double w) {
        if (w < 0.5) {
          const double ph = 2.0 * std::numbers::pi * v;
          return Vec3(kC + Vec3(R * std::cos(ph), R * std::sin(ph), H * (2 * u - 1)));
        }
        Vec3 p = on_sphere(u, v, R);
        p.z() += p.z() >= 0.0 ? H : -H;
        return Vec3(kC + p);
      },
      kC + Vec3(0, 0, (H + R) * in), true);
  check_kind(
      "mesh",
      [&](World& w) { w.add_mesh(cube(R)); },
      [&](double u, double v, double w) {
        Vec3 p(R * (2 * u - 1), R * (2 * v - 1), R);
        const int face = int(w * 6.0);
        if (face / 2 == 1) p = Vec3(p.z(), p.x(), p.y());
        if (face / 2 == 2) p = Vec3(p.y(), p.z(), p.x());
        if (face % 2) p = -p;
        return Vec3(kC + p);
      },
      kC + Vec3(0, 0, R * in), true);
  check_kind(
      "box",  // boxes push particles out through the nearest face: never removed
      [&](World& w) {
        BoxDef b;
        b.half_extents = Vec3(R, R, R);
        b.transform.translation = kC;
        w.add_box(b);
      },
      [&](double u, double v, double) { return Vec3(kC + Vec3(R * (2 * u - 1), R * (2 * v - 1), R)); },
      kC + Vec3(0, 0, R * in), false);
}

}  // namespace
}  // namespace simreel::sim
