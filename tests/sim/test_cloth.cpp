// Mass-spring cloth (Coutinho §3.9.2): the maximum-deformation pass, implicit vs explicit
// stability, the static sag of a hanging spring chain, energy dissipation, collisions, the
// aerodynamic force on a plate, pins and determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <vector>

#include "cloth/contact_geometry.hpp"
#include "simreel/sim/cloth.hpp"
#include "simreel/sim/world.hpp"
#include "sim_test_util.hpp"

namespace {

using namespace simreel::sim;

constexpr double kFrame = 1.0 / 60.0;
constexpr double kStrainEps = 1e-9;

/// A square cloth lying flat (local xy = world xy) at height z.
ClothDef flat_cloth(std::size_t nodes, double size, double mass, double z) {
  ClothDef d;
  d.rows = d.columns = nodes;
  d.width = d.height = size;
  d.mass = mass;
  d.transform.translation = Vec3(0, 0, z);
  return d;
}

/// Rotation taking the cloth's local +y to world +z (a hanging sheet facing -y).
Quat upright() { return Quat(Eigen::AngleAxisd(std::numbers::pi / 2, Vec3::UnitX())); }

/// A flag: columns along world x, rows down world z, left edge pinned, wind along +x.
ClothDef gale_flag(double max_strain) {
  ClothDef d;
  d.name = "flag";
  d.rows = 16;
  d.columns = 24;
  d.width = 1.5;
  d.height = 1.0;
  d.mass = 0.3;
  d.transform.translation = Vec3(0.75, 0, 2.0);
  d.transform.rotation = upright();
  for (std::size_t r = 0; r < d.rows; ++r) d.pins.push_back({r, 0, {}});
  d.wind.velocity = Vec3(30.0, 0.0, 0.0);
  d.wind.gust_amplitude = 6.0;
  d.wind.gust_frequency = 1.5;
  d.max_strain = max_strain;
  return d;
}

double max_strain_over_run(World& w, ClothHandle h, int frames) {
  double worst = 0.0;
  for (int f = 0; f < frames; ++f) {
    w.advance(kFrame);
    worst = std::max(worst, w.cloth_stats(h).max_strain);
  }
  return worst;
}

TEST(Cloth, TopologyCountsFollowFigure345) {
  const ClothTopology t(5, 7, 1.2, 0.8);
  // stretch: r(c-1) + (r-1)c; shear: 2(r-1)(c-1); bend: r(c-2) + (r-2)c.
  EXPECT_EQ(t.limited_count, std::size_t(5 * 6 + 4 * 7 + 2 * 4 * 6));
  EXPECT_EQ(t.spring_count(), t.limited_count + std::size_t(5 * 5 + 3 * 7));
  EXPECT_EQ(t.triangles.size(), std::size_t(3 * 2 * 4 * 6));
  EXPECT_NEAR(t.rest_length[0], 0.2, 1e-15);  // (0,0)-(1,0): 0.8 / 4
  // A shear spring is the cell diagonal.
  EXPECT_NEAR(t.rest_length[t.limited_count - 1], std::hypot(0.2, 0.2), 1e-15);
}

TEST(Cloth, InvalidDefinitionNamesTheField) {
  ClothDef d;
  d.rows = 0;
  try {
    Cloth c(d);
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("ClothDef.rows"), std::string::npos) << e.what();
  }
  d = ClothDef{};
  d.pins.push_back({16, 0, {}});
  EXPECT_THROW(Cloth{d}, std::invalid_argument);
  d = ClothDef{};
  d.max_strain = -0.1;
  EXPECT_THROW(Cloth{d}, std::invalid_argument);
}

// §3.9.2: no stretch or shear spring ends a step above (1 + max_strain) L. The same scene without
// the pass exceeds the limit, so the check has teeth.
TEST(Cloth, MaxDeformationHoldsInGaleFlag) {
  {
    World w(WorldDef{kFrame, 7, 0.05});
    const ClothHandle h = w.add_cloth(gale_flag(0.10));
    EXPECT_LE(max_strain_over_run(w, h, 120), 0.10 + kStrainEps);
  }
  {
    World w(WorldDef{kFrame, 7, 0.05});
    const ClothHandle h = w.add_cloth(gale_flag(std::numeric_limits<double>::infinity()));
    EXPECT_GT(max_strain_over_run(w, h, 120), 0.10);
  }
}

ClothDef drop_cloth(double max_strain) {
  ClothDef d = flat_cloth(20, 1.2, 0.3, 0.8);
  d.max_strain = max_strain;
  d.stretch = {300.0, 0.2};  // soft, so the pass has work to do
  d.shear = {50.0, 0.05};
  return d;
}

BoxDef table() {
  BoxDef b;
  b.transform.translation = Vec3(0.1, 0.05, 0.25);
  b.half_extents = Vec3(0.3, 0.3, 0.25);
  return b;
}

TEST(Cloth, MaxDeformationHoldsInDropOntoBox) {
  double with = 0.0, without = 0.0;
  for (double ms : {0.10, std::numeric_limits<double>::infinity()}) {
    World w(WorldDef{kFrame, 1, 0.05});
    w.add_plane(PlaneDef{});
    w.add_box(table());
    const ClothHandle h = w.add_cloth(drop_cloth(ms));
    (std::isfinite(ms) ? with : without) = max_strain_over_run(w, h, 150);
  }
  EXPECT_LE(with, 0.10 + kStrainEps);
  EXPECT_GT(without, 0.10);
}

TEST(Cloth, DrapeOverBoxLeavesNoVertexInside) {
  World w(WorldDef{kFrame, 1, 0.05});
  w.add_plane(PlaneDef{});
  const BoxDef box = table();
  w.add_box(box);
  const ClothDef def = drop_cloth(0.10);
  const ClothHandle h = w.add_cloth(def);
  std::size_t on_top = 0;
  for (int f = 0; f < 150; ++f) {
    w.advance(kFrame);
    const ClothView v = w.cloth(h);
    on_top = 0;
    for (std::size_t i = 0; i < v.vertex_count; ++i) {
      const Vec3 p(v.positions[3 * i], v.positions[3 * i + 1], v.positions[3 * i + 2]);
      const Vec3 q = p - box.transform.translation;
      // Inside the box grown by thickness (less a float-rounding hair) = a violation.
      const Vec3 e = box.half_extents + Vec3::Constant(def.thickness - 1e-5);
      const bool inside = std::abs(q.x()) < e.x() && std::abs(q.y()) < e.y() && std::abs(q.z()) < e.z();
      ASSERT_FALSE(inside) << "vertex " << i << " inside the box at frame " << f;
      ASSERT_GE(p.z(), def.thickness - 1e-5) << "vertex " << i << " below the ground";
      if (std::abs(p.z() - (2 * box.half_extents.z() + def.thickness)) < 1e-3) ++on_top;
    }
  }
  // The cloth really lies on the box top (the rows next to the box's edges are lifted by the
  // triangles resting on those edges, issue 16).
  EXPECT_GT(on_top, std::size_t(40));
}

Vec3 vertex(const ClothView& v, std::size_t i) {
  return {v.positions[3 * i], v.positions[3 * i + 1], v.positions[3 * i + 2]};
}

// A cloth dropped over a sphere resting on the ground: at every step no vertex is inside the
// sphere grown by the thickness (less a hair for float positions and the chord of a slide step),
// the maximum deformation holds, and the cloth really drapes (it touches the sphere and the
// ground).
TEST(Cloth, NoVertexInsideSphereAfterDrape) {
  World w(WorldDef{kFrame, 1, 0.05});
  w.add_plane(PlaneDef{});
  SphereDef ball;
  ball.radius = 0.2;
  ball.transform.translation = Vec3(0.05, -0.03, 0.2);
  w.add_sphere(ball);
  const ClothDef def = drop_cloth(0.10);
  const ClothHandle h = w.add_cloth(def);
  const double limit = ball.radius + def.thickness - 1e-4;
  double closest = std::numeric_limits<double>::infinity();
  std::size_t on_ground = 0;
  for (int f = 0; f < 150; ++f) {
    w.advance(kFrame);
    const ClothView v = w.cloth(h);
    on_ground = 0;
    for (std::size_t i = 0; i < v.vertex_count; ++i) {
      const double d = (vertex(v, i) - ball.transform.translation).norm();
      closest = std::min(closest, d);
      ASSERT_GE(d, limit) << "vertex " << i << " inside the sphere at frame " << f;
      if (vertex(v, i).z() < def.thickness + 1e-3) ++on_ground;
    }
    ASSERT_LE(w.cloth_stats(h).max_strain, 0.10 + kStrainEps) << "frame " << f;
  }
  // It rests on the sphere: since issue 16 the triangles touch it, so the vertices stand off by
  // up to the chord's sag, spacing² / (8 r) = 2.5 mm here.
  EXPECT_LT(closest, ball.radius + def.thickness + 3.5e-3);
  EXPECT_GT(on_ground, std::size_t(20));                    // and its hem on the ground
}

// A cloth dropped across a horizontal cylinder (a rail, axis along world y): at every step no
// vertex is inside the cylinder grown by the thickness (round side; the square rims are the
// cylinder's own convention) and the sheet hangs over it.
TEST(Cloth, DropOverCylinderLeavesNoVertexInside) {
  World w(WorldDef{kFrame, 1, 0.05});
  CylinderDef rail;
  rail.radius = 0.1;
  rail.half_height = 1.0;
  rail.transform.translation = Vec3(0.03, 0.0, 0.3);
  rail.transform.rotation = upright();  // local z -> world -y
  w.add_cylinder(rail);
  const ClothDef def = drop_cloth(0.10);
  const ClothHandle h = w.add_cloth(def);
  std::size_t on_rail = 0;
  for (int f = 0; f < 90; ++f) {
    w.advance(kFrame);
    const ClothView v = w.cloth(h);
    on_rail = 0;
    for (std::size_t i = 0; i < v.vertex_count; ++i) {
      const Vec3 q = vertex(v, i) - rail.transform.translation;
      const double rho = std::hypot(q.x(), q.z());  // distance from the axis
      ASSERT_GE(rho, rail.radius + def.thickness - 1e-4) << "vertex " << i << " frame " << f;
      // Triangles rest on the rail (issue 16): vertices stand off by up to the chord's sag,
      // spacing² / (8 r) = 5 mm here.
      if (rho < rail.radius + def.thickness + 6e-3) ++on_rail;
    }
    ASSERT_LE(w.cloth_stats(h).max_strain, 0.10 + kStrainEps) << "frame " << f;
  }
  EXPECT_GT(on_rail, std::size_t(10));
  EXPECT_LT(w.cloth_stats(h).min_z, 0.0);  // both halves hang below the rail
}

/// A closed box-shaped triangle mesh (12 triangles) of half extents e in its local frame.
MeshDef box_mesh(const Vec3& e) {
  MeshDef m;
  for (int k = 0; k < 8; ++k)
    m.vertices.emplace_back((k & 1) ? e.x() : -e.x(), (k & 2) ? e.y() : -e.y(), (k & 4) ? e.z() : -e.z());
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

// A cloth falling onto a rotated box-shaped mesh on the ground: no vertex ends inside the mesh
// grown by the thickness (round edges) at any step (tested in the mesh frame), and part of the cloth lies on
// its top face.
TEST(Cloth, FallOntoMeshLeavesNoVertexInside) {
  World w(WorldDef{kFrame, 1, 0.05});
  w.add_plane(PlaneDef{});
  const Vec3 e(0.3, 0.25, 0.25);
  MeshDef mesh = box_mesh(e);
  mesh.transform.translation = Vec3(0.05, 0.0, 0.25);
  mesh.transform.rotation = Quat(Eigen::AngleAxisd(0.5, Vec3::UnitZ()));
  w.add_mesh(mesh);
  const ClothDef def = drop_cloth(0.10);
  const ClothHandle h = w.add_cloth(def);
  const Mat3 Rt = mesh.transform.rotation.toRotationMatrix().transpose();
  std::size_t on_top = 0;
  for (int f = 0; f < 150; ++f) {
    w.advance(kFrame);
    const ClothView v = w.cloth(h);
    on_top = 0;
    for (std::size_t i = 0; i < v.vertex_count; ++i) {
      const Vec3 q = Rt * (vertex(v, i) - mesh.transform.translation);
      // Distance to the solid box (0 inside): the mesh grown by the thickness has round edges.
      const double gap = (q - q.cwiseMax(-e).cwiseMin(e)).norm();
      ASSERT_GE(gap, def.thickness - 1e-4) << "vertex " << i << " inside the mesh at frame " << f;
      if (std::abs(q.z() - (e.z() + def.thickness)) < 1e-3) ++on_top;
    }
    ASSERT_LE(w.cloth_stats(h).max_strain, 0.10 + kStrainEps) << "frame " << f;
  }
  EXPECT_GT(on_top, std::size_t(40));
}

// Tunnelling: a cloth thrown down at ~60 m/s (one step moves it ~1 m) onto a zero-thickness
// plate made of two mesh triangles. A test of end positions alone would let every vertex through;
// the swept path stops them on the plate.
TEST(Cloth, FastClothDoesNotTunnelThroughThinMesh) {
  World w(WorldDef{kFrame, 1, 0.05});
  MeshDef plate;
  plate.vertices = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  plate.triangles = {{0, 1, 2}, {0, 2, 3}};
  w.add_mesh(plate);
  ClothDef def = flat_cloth(8, 0.5, 0.1, 1.0);
  def.gravity = Vec3(0, 0, -2000.0);
  const ClothHandle h = w.add_cloth(def);
  double fastest = 0.0;
  for (int f = 0; f < 30; ++f) {
    w.advance(kFrame);
    const ClothView v = w.cloth(h);
    for (std::size_t i = 0; i < v.vertex_count; ++i) {
      ASSERT_GE(v.positions[3 * i + 2], def.thickness - 1e-4) << "vertex " << i << " frame " << f;
      fastest = std::max(fastest, (double)std::abs(v.velocities[3 * i + 2]));
    }
  }
  EXPECT_GT(fastest * kFrame, 0.2);  // a step really moves vertices far past the thickness
}

/// A weightless, undamped flat cloth at z = 0 (no force acts on it before it is hit, so its own
/// solve cannot change its momentum) and drops fired down at it, without gravity.
struct Pelted {
  World w{WorldDef{kFrame, 1, 0.05}};
  ClothHandle cloth;
  ParticleSystemHandle rain;
  explicit Pelted(double restitution) {
    ClothDef d = flat_cloth(8, 1.0, 0.2, 0.0);
    d.gravity = Vec3::Zero();
    d.damping = 0.0;
    d.aero.air_density = 0.0;
    d.restitution = restitution;
    cloth = w.add_cloth(d);
    ParticleSystemDef ps = test::spawn_only_system("rain");
    ps.gravity = Vec3::Zero();
    rain = w.add_particle_system(ps);
    for (int k = 0; k < 6; ++k)
      w.spawn_particle(rain, Vec3(-0.37 + 0.13 * k, 0.29 - 0.11 * k, 0.05),
                       Vec3(0.5, -0.3 * k, -6.0), 0.002 + 0.001 * k, 0.004, 100);
  }
  [[nodiscard]] Vec3 particle_momentum() const {
    const ParticleView v = w.particles(rain);
    Vec3 p = Vec3::Zero();
    for (std::size_t i = 0; i < v.count; ++i) p += double(v.mass[i]) * test::velocity_of(v, i);
    return p;
  }
};

// Drops hitting a free sheet: the impulse each drop receives is taken from the triangle's three
// vertices by barycentric weight, so particles + cloth keep their total momentum (to rounding),
// the sheet is pushed along the rain, and the drops leave the surface (relative normal speed
// -e times the incoming one, so they end above the sheet, slowed).
TEST(Cloth, ParticleImpulsesConserveMomentumWithTheCloth) {
  for (double e : {0.0, 0.5}) {
    Pelted s(e);
    const Vec3 before = s.particle_momentum() + s.w.cloth_stats(s.cloth).momentum;
    s.w.advance(kFrame);
    const Vec3 cloth_p = s.w.cloth_stats(s.cloth).momentum;
    const Vec3 after = s.particle_momentum() + cloth_p;
    EXPECT_LE((after - before).norm(), 1e-9 * before.norm()) << "e = " << e;
    EXPECT_LT(cloth_p.z(), 0.3 * before.z()) << "the sheet takes a real share of the momentum";
    const ParticleView v = s.w.particles(s.rain);
    for (std::size_t i = 0; i < v.count; ++i) {
      EXPECT_GT(v.position[3 * i + 2], 0.0) << "drop " << i << " went through";
      EXPECT_GT(v.velocity[3 * i + 2], -6.0 + 1.0) << "drop " << i << " not slowed";
    }
  }
}

// Opt-out: with collide_particles = false the drops pass straight through the sheet.
TEST(Cloth, ParticlesPassThroughWhenCollisionIsOff) {
  World w{WorldDef{kFrame, 1, 0.05}};
  ClothDef d = flat_cloth(8, 1.0, 0.2, 0.0);
  d.gravity = Vec3::Zero();
  d.collide_particles = false;
  w.add_cloth(d);
  ParticleSystemDef ps = test::spawn_only_system("rain");
  ps.gravity = Vec3::Zero();
  const ParticleSystemHandle rain = w.add_particle_system(ps);
  w.spawn_particle(rain, Vec3(0.1, 0.1, 0.05), Vec3(0, 0, -6.0), 0.003, 0.004, 100);
  w.advance(kFrame);
  EXPECT_LT(w.particles(rain).position[2], -0.01);
}

// Dropped flat on the ground, the cloth comes to rest flat: every vertex at the thickness height
// and no kinetic energy left.
TEST(Cloth, DroppedClothRestsFlatOnGround) {
  World w(WorldDef{kFrame, 1, 0.05});
  w.add_plane(PlaneDef{});
  ClothDef d = flat_cloth(16, 1.0, 0.2, 0.3);
  const ClothHandle h = w.add_cloth(d);
  for (int f = 0; f < 180; ++f) w.advance(kFrame);
  const ClothStats s = w.cloth_stats(h);
  EXPECT_NEAR(s.min_z, d.thickness, 1e-6);
  EXPECT_NEAR(s.max_z, d.thickness, 1e-6);
  EXPECT_LT(s.kinetic_energy, 1e-8);
}

// Stiff springs at the frame step: implicit Euler stays bounded, explicit Euler blows up.
TEST(Cloth, ImplicitStableWhereExplicitBlowsUp) {
  auto run = [](ClothIntegrator integ) {
    ClothDef d = flat_cloth(16, 1.0, 0.5, 1.0);
    d.transform.rotation = upright();
    d.stretch = {2e4, 2.0};
    d.shear = {5e3, 1.0};
    d.bend = {100.0, 0.1};
    d.pins = {{0, 0, {}}, {0, 15, {}}};
    d.max_strain = std::numeric_limits<double>::infinity();  // the integrator alone
    d.integrator = integ;
    Cloth c(d);
    double extent = 0.0;
    for (int f = 0; f < 120; ++f) {
      if (!c.step(f * kFrame, (f + 1) * kFrame)) return std::numeric_limits<double>::infinity();
      for (const Vec3& p : c.positions()) extent = std::max(extent, (p - Vec3(0, 0, 1)).norm());
    }
    return extent;
  };
  const double implicit = run(ClothIntegrator::implicit_euler);
  const double explicit_ = run(ClothIntegrator::explicit_euler);
  EXPECT_LT(implicit, 2.5);   // a 1 m sheet hanging from its top corners stays near its pins
  EXPECT_GT(explicit_, 1e3);  // forward Euler at h = 1/60 with k h² / m ≈ 170: divergence
}

// A 1-column cloth pinned at the top is a spring chain; at rest each spring's extension is the
// weight below it over k_s. Implicit Euler's fixed point is exactly the static equilibrium.
TEST(Cloth, HangingChainReachesStaticSag) {
  ClothDef d;
  d.rows = 10;
  d.columns = 1;
  d.height = 0.9;  // L = 0.1 m
  d.mass = 0.1;    // 0.01 kg per vertex
  d.transform.translation = Vec3(0, 0, 2);
  d.transform.rotation = upright();
  d.pins = {{0, 0, {}}};
  d.stretch = {50.0, 0.5};
  d.bend = {0.0, 0.0};
  d.damping = 0.02;
  d.max_strain = std::numeric_limits<double>::infinity();
  d.aero.air_density = 0.0;
  d.cg_tolerance = 1e-12;
  Cloth c(d);
  for (int f = 0; f < 1200; ++f) ASSERT_TRUE(c.step(f * kFrame, (f + 1) * kFrame));
  const std::vector<Vec3>& x = c.positions();
  const double m = d.mass / 10, g = 9.81, k = d.stretch.stiffness;
  for (std::size_t i = 0; i + 1 < 10; ++i) {
    const double expected = 0.1 + double(10 - 1 - i) * m * g / k;
    EXPECT_NEAR((x[i + 1] - x[i]).norm(), expected, 1e-9) << "spring " << i;
    EXPECT_NEAR(x[i + 1].x(), 0.0, 1e-12);
  }
}

// With damping and no external forces, kinetic + spring energy never increases under implicit
// Euler; with no damping, semi-implicit Euler at a small step keeps it within 1 % (the forces are
// the gradient of the energy the test sums).
TEST(Cloth, EnergyDecreasesWithDampingAndIsKeptWithout) {
  ClothDef d = flat_cloth(8, 0.7, 0.1, 0.0);
  d.gravity = Vec3::Zero();
  d.aero.air_density = 0.0;
  d.max_strain = std::numeric_limits<double>::infinity();
  d.cg_tolerance = 1e-10;
  Cloth probe(d);
  std::vector<Vec3> x = probe.positions(), v(x.size(), Vec3::Zero());
  for (std::size_t i = 0; i < x.size(); ++i) {  // a deterministic stretch + ripple
    x[i] *= 1.08;
    x[i].z() = 0.02 * std::sin(7.0 * x[i].x() + 3.0 * x[i].y());
  }
  {
    Cloth c(d);
    c.set_state(x, v);
    double e = c.stats().kinetic_energy + c.stats().spring_energy;
    const double e0 = e;
    for (int f = 0; f < 200; ++f) {
      ASSERT_TRUE(c.step(f * kFrame, (f + 1) * kFrame));
      const double e1 = c.stats().kinetic_energy + c.stats().spring_energy;
      EXPECT_LE(e1, e * (1 + 1e-9)) << "step " << f;
      e = e1;
    }
    EXPECT_LT(e, 0.01 * e0);
  }
  {
    ClothDef u = d;
    u.stretch.damping = u.shear.damping = u.bend.damping = 0.0;
    u.damping = 0.0;
    u.integrator = ClothIntegrator::semi_implicit_euler;
    Cloth c(u);
    c.set_state(x, v);
    const double e0 = c.stats().kinetic_energy + c.stats().spring_energy;
    const double h = 2e-5;
    for (int s = 0; s < 5000; ++s) ASSERT_TRUE(c.step(s * h, (s + 1) * h));
    const ClothStats st = c.stats();
    EXPECT_GT(st.kinetic_energy, 0.05 * e0);  // it really oscillates
    EXPECT_NEAR(st.kinetic_energy + st.spring_energy, e0, 0.01 * e0);
  }
}

// A plate square to a steady wind: the pressure force is ½ ρ C_d A |u|² along the wind (cos θ = 1,
// no lift), so one semi-implicit step gives every vertex the mean acceleration F / M.
TEST(Cloth, AerodynamicPressureOnPlateSquareToWind) {
  ClothDef d = flat_cloth(6, 0.5, 0.05, 1.0);
  d.gravity = Vec3::Zero();
  d.damping = 0.0;
  d.wind.velocity = Vec3(0, 0, 12.0);
  d.aero = {1.1, 0.7, 1.2};
  d.integrator = ClothIntegrator::semi_implicit_euler;
  Cloth c(d);
  ASSERT_TRUE(c.step(0.0, 1e-3));
  Vec3 p = Vec3::Zero();
  for (const Vec3& v : c.velocities()) p += v * (d.mass / 36);
  const double F = 0.5 * 1.2 * 1.1 * 0.25 * 144.0;
  EXPECT_NEAR(p.z(), F * 1e-3, 1e-12);
  EXPECT_NEAR(p.x(), 0.0, 1e-15);
  EXPECT_NEAR(p.y(), 0.0, 1e-15);
}

TEST(Cloth, KeyframedPinFollowsItsPath) {
  ClothDef d = flat_cloth(6, 0.5, 0.05, 1.0);
  ClothPin pin{0, 0, {}};
  pin.path.keys = {{0.0, Vec3(-0.25, 0.25, 1.0), Quat::Identity()},
                   {1.0, Vec3(0.5, 0.25, 1.5), Quat::Identity()}};
  pin.path.smooth = false;
  d.pins = {pin, {0, 5, {}}};
  d.max_strain = 0.5;
  World w(WorldDef{kFrame, 0, 0.05});
  const ClothHandle h = w.add_cloth(d);
  for (int f = 1; f <= 30; ++f) {
    w.advance(kFrame);
    const ClothView v = w.cloth(h);
    const Vec3 want = pin.path.sample(w.time()).translation;
    EXPECT_NEAR(v.positions[0], want.x(), 1e-6);
    EXPECT_NEAR(v.positions[2], want.z(), 1e-6);
    EXPECT_NEAR(v.positions[3 * 5 + 0], 0.25, 1e-6);  // the fixed pin stays
  }
}

// The particles' divergence bounds hold for cloth vertices too: a pin yanked at 60 km/s drags its
// vertex past simulation.max_speed at the first step, which stops the run as diverged (naming
// the cloth, vertex and bound) instead of stepping a sheet torn kilometres wide, whose contact
// rounds then test every pair of triangles (650 ms a frame here, minutes in a larger sheet).
// The same yank at 600 m/s runs.
TEST(Cloth, YankedPinPastTheSpeedBoundStopsTheRunAsDiverged) {
  for (const double seconds : {0.1, 10.0}) {
    ClothDef d = flat_cloth(6, 0.5, 0.05, 1.0);
    ClothPin pin{0, 0, {}};
    pin.path.keys = {{0.0, Vec3(-0.25, 0.25, 1.0), Quat::Identity()},
                     {seconds, Vec3(-0.25, 0.25, 6000.0), Quat::Identity()}};
    pin.path.smooth = false;
    d.pins = {pin, {0, 5, {}}};
    World w(WorldDef{kFrame, 0, 0.05});
    w.add_cloth(d);
    std::string error;
    try {
      for (int f = 0; f < 3; ++f) w.advance(kFrame);
    } catch (const NonFiniteState& e) {
      error = e.what();
    }
    if (seconds < 1.0) {
      EXPECT_NE(error.find("cloth '" + d.name + "' (index 0): diverged (vertex 0 at"), std::string::npos) << error;
      EXPECT_NE(error.find("simulation.max_speed = 10000 m/s"), std::string::npos) << error;
      EXPECT_NE(error.find("at internal step 1,"), std::string::npos) << error;
    } else {
      EXPECT_EQ(error, "");
    }
  }
}

TEST(Cloth, ViewHasUnitNormalsAndFixedTriangles) {
  World w;
  const ClothHandle h = w.add_cloth(flat_cloth(5, 1.0, 0.1, 1.0));
  const ClothView v = w.cloth(h);
  ASSERT_EQ(v.vertex_count, 25u);
  ASSERT_EQ(v.triangle_count, 32u);
  for (std::size_t i = 0; i < v.vertex_count; ++i)
    EXPECT_NEAR(v.normals[3 * i + 2], 1.0f, 1e-6f);  // flat in xy, facing +z
  EXPECT_EQ(v.uvs[2 * 24], 1.0f);
  EXPECT_EQ(v.uvs[2 * 24 + 1], 1.0f);
}

TEST(Cloth, GustsAreDeterministicFromSeed) {
  auto state = [](std::uint64_t seed) {
    World w(WorldDef{kFrame, seed, 0.05});
    const ClothHandle h = w.add_cloth(gale_flag(0.1));
    for (int f = 0; f < 20; ++f) w.advance(kFrame);
    const ClothView v = w.cloth(h);
    return std::vector<float>(v.positions, v.positions + 3 * v.vertex_count);
  };
  const auto a = state(3), b = state(3), c = state(4);
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float)));
  EXPECT_NE(0, std::memcmp(a.data(), c.data(), a.size() * sizeof(float)));
  // The gust is smooth: wind changes little over a millisecond.
  Cloth cl(gale_flag(0.1), 5, 0);
  EXPECT_LT((cl.wind_at(Vec3::Zero(), 1.0) - cl.wind_at(Vec3::Zero(), 1.001)).norm(), 0.1);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Issue 16: triangles and edges collide, not just vertices.

/// The cloth's vertices as doubles.
std::vector<Vec3> positions_of(const ClothView& v) {
  std::vector<Vec3> x(v.vertex_count);
  for (std::size_t i = 0; i < v.vertex_count; ++i) x[i] = vertex(v, i);
  return x;
}

/// Height (m) at which segment a-b crosses the plane y = 0, or NaN if it does not cross it.
double crossing_height(const Vec3& a, const Vec3& b) {
  if ((a.y() < 0.0) == (b.y() < 0.0) || a.y() == b.y()) return std::nan("");
  const double s = a.y() / (a.y() - b.y());
  return a.z() + s * (b.z() - a.z());
}

// A 24 x 24 cloth of 2.6 m (vertex spacing 11.3 cm) dropped on a 6 cm-thick box ridge (a wall
// along x, between rows 11 and 12): the cloth's middle line never goes below the ridge's top at
// any frame, and at the end the cloth hangs over it on both sides. With vertex-only collisions
// the vertices miss the ridge and the cloth falls flat through it.
TEST(Cloth, DropOnThinRidgeDrapesOverIt) {
  World w(WorldDef{kFrame, 1, 0.05});
  w.add_plane(PlaneDef{});
  BoxDef ridge;
  ridge.half_extents = Vec3(1.6, 0.03, 0.25);
  ridge.transform.translation = Vec3(0.0, 0.0, 0.25);
  w.add_box(ridge);
  const double top = 0.5;
  ClothDef def = flat_cloth(24, 2.6, 0.5, 0.8);
  const ClothHandle h = w.add_cloth(def);
  double lowest_middle = std::numeric_limits<double>::infinity();
  for (int f = 0; f < 120; ++f) {
    w.advance(kFrame);
    const std::vector<Vec3> x = positions_of(w.cloth(h));
    for (std::size_t c = 0; c < def.columns; ++c) {
      // The stretch edge and both diagonals of the cells between rows 11 and 12.
      const std::size_t i = 11 * def.columns + c, j = 12 * def.columns + c;
      for (const double z : {crossing_height(x[i], x[j]),
                             c + 1 < def.columns ? crossing_height(x[i], x[j + 1]) : std::nan(""),
                             c + 1 < def.columns ? crossing_height(x[i + 1], x[j]) : std::nan("")})
        if (std::isfinite(z) && std::abs(x[i].x()) < 1.2) lowest_middle = std::min(lowest_middle, z);
    }
    // (A millimetre of the 5 mm thickness may be given up to the strain limit, never more.)
    ASSERT_GE(lowest_middle, top - 1e-3) << "the cloth passed through the ridge by frame " << f;
  }
  const ClothStats st = w.cloth_stats(h);
  EXPECT_LT(lowest_middle, top + def.thickness + 0.01);  // it rests on the ridge
  EXPECT_LT(st.min_z, 0.05);                             // and its sides reach the ground
  EXPECT_LE(st.max_strain, 0.10 + kStrainEps);
}

/// Distance (m) from p to triangle (a, b, c) (brute force on the closest point).
double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a).normalized();
  const Vec3 q = p - n.dot(p - a) * n;
  const Vec3 e[3] = {b - a, c - b, a - c};
  const Vec3 o[3] = {a, b, c};
  bool inside = true;
  for (int k = 0; k < 3; ++k) inside = inside && e[k].cross(q - o[k]).dot(n) >= 0.0;
  if (inside) return std::abs(n.dot(p - a));
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const double s = std::clamp((p - o[k]).dot(e[k]) / e[k].squaredNorm(), 0.0, 1.0);
    best = std::min(best, (p - (o[k] + s * e[k])).norm());
  }
  return best;
}

// A kinematic sphere (radius 8 cm, less than two vertex spacings) pushed at 2 m/s down through a
// horizontal 1 m sheet pinned on its four sides: at every frame the sphere's centre stays above
// the sheet and no triangle comes within radius + thickness / 2 of it, and the sheet
// stretches under it (far past the strain limit: the kinematic body wins). With vertex-only
// collisions the sphere slips between the vertices.
TEST(Cloth, KinematicSphereStretchesPinnedSheetNeverThrough) {
  World w(WorldDef{kFrame, 1, 0.05});
  ClothDef def = flat_cloth(24, 1.0, 0.2, 0.0);
  for (std::size_t k = 0; k < 24; ++k) {
    def.pins.push_back({0, k, {}});
    def.pins.push_back({23, k, {}});
    if (k > 0 && k < 23) {
      def.pins.push_back({k, 0, {}});
      def.pins.push_back({k, 23, {}});
    }
  }
  def.gravity = Vec3::Zero();
  SphereDef ball;
  ball.radius = 0.08;
  ball.path.smooth = false;
  ball.path.keys = {{0.0, Vec3(0.021, 0.013, 0.3), Quat::Identity()},
                    {0.35, Vec3(0.021, 0.013, -0.4), Quat::Identity()}};
  ball.transform.translation = ball.path.keys[0].position;
  w.add_sphere(ball);
  const ClothHandle h = w.add_cloth(def);
  const ClothView v0 = w.cloth(h);
  const std::vector<std::uint32_t> tri(v0.triangles, v0.triangles + 3 * v0.triangle_count);
  double deepest = 0.0;
  for (int f = 0; f < 30; ++f) {
    w.advance(kFrame);
    const Vec3 centre = ball.path.sample(w.time()).translation;
    const std::vector<Vec3> x = positions_of(w.cloth(h));
    double closest = std::numeric_limits<double>::infinity(), below = std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; 3 * t < tri.size(); ++t)
      closest = std::min(closest, point_triangle_distance(centre, x[tri[3 * t]], x[tri[3 * t + 1]],
                                                          x[tri[3 * t + 2]]));
    for (const Vec3& p : x) below = std::min(below, p.z());
    deepest = std::min(deepest, below);
    // Contact rounds stop once no pair is closer than half the thickness (cloth_contacts.hpp).
    ASSERT_GE(closest, ball.radius + 0.5 * def.thickness) << "frame " << f;
    ASSERT_LT(below, centre.z()) << "the sphere is below the sheet at frame " << f;
  }
  EXPECT_LT(deepest, -0.3);  // the sheet went down with the sphere
}

// ---------------------------------------------------------------------------------------------
// Issue 16: self-collision and cloth–cloth.

double orient(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).cross(c - a).dot(d - a);
}

/// Does segment pq cross triangle abc (proper crossing, general position)?
bool segment_crosses_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                              const Vec3& c) {
  const double sp = orient(a, b, c, p), sq = orient(a, b, c, q);
  if ((sp > 0.0) == (sq > 0.0) || sp == 0.0 || sq == 0.0) return false;
  const double s1 = orient(p, q, a, b), s2 = orient(p, q, b, c), s3 = orient(p, q, c, a);
  return (s1 > 0.0 && s2 > 0.0 && s3 > 0.0) || (s1 < 0.0 && s2 < 0.0 && s3 < 0.0);
}

/// Do triangles A and B (no shared vertex) intersect? Two triangles in general position meet iff
/// an edge of one crosses the other (the exact test of the issue, in double precision).
bool triangles_intersect(const Vec3 A[3], const Vec3 B[3]) {
  for (int k = 0; k < 3; ++k) {
    if (segment_crosses_triangle(A[k], A[(k + 1) % 3], B[0], B[1], B[2])) return true;
    if (segment_crosses_triangle(B[k], B[(k + 1) % 3], A[0], A[1], A[2])) return true;
  }
  return false;
}

/// A triangle of a cloth view: its corners, vertex indices, cloth (index in the views) and box.
struct ViewTriangle {
  Vec3 p[3];
  std::uint32_t id[3];
  std::size_t cloth;
  Vec3 lo, hi;
};

/// Every triangle of the given cloth views, in view and triangle order.
std::vector<ViewTriangle> view_triangles(const std::vector<ClothView>& views) {
  std::vector<ViewTriangle> ts;
  for (std::size_t k = 0; k < views.size(); ++k) {
    const ClothView& v = views[k];
    for (std::size_t t = 0; t < v.triangle_count; ++t) {
      ViewTriangle x;
      x.cloth = k;
      x.lo = Vec3::Constant(1e300);
      x.hi = -x.lo;
      for (int j = 0; j < 3; ++j) {
        x.id[j] = v.triangles[3 * t + std::size_t(j)];
        x.p[j] = vertex(v, x.id[j]);
        x.lo = x.lo.cwiseMin(x.p[j]);
        x.hi = x.hi.cwiseMax(x.p[j]);
      }
      ts.push_back(x);
    }
  }
  return ts;
}

/// Intersecting pairs among the triangles of the given cloth views (pairs sharing a vertex of
/// the same cloth excluded), by sweep over x then the exact test. `self`: count pairs within a
/// cloth; `across`: pairs between cloths.
std::size_t intersecting_pairs(const std::vector<ClothView>& views, bool self, bool across) {
  std::vector<ViewTriangle> ts = view_triangles(views);
  std::sort(ts.begin(), ts.end(), [](const ViewTriangle& a, const ViewTriangle& b) { return a.lo.x() < b.lo.x(); });
  std::size_t count = 0;
  for (std::size_t i = 0; i < ts.size(); ++i)
    for (std::size_t j = i + 1; j < ts.size() && ts[j].lo.x() <= ts[i].hi.x(); ++j) {
      const ViewTriangle &a = ts[i], &b = ts[j];
      if (a.cloth == b.cloth ? !self : !across) continue;
      if (((a.lo.array() > b.hi.array()) || (b.lo.array() > a.hi.array())).any()) continue;
      if (a.cloth == b.cloth) {
        bool shared = false;
        for (auto u : a.id)
          for (auto w : b.id) shared = shared || u == w;
        if (shared) continue;
      }
      if (triangles_intersect(a.p, b.p)) ++count;
    }
  return count;
}

/// The smallest distance (m) from a vertex of `v` to a triangle of `v` that does not hold it,
/// or `reach` (m) if none is nearer (brute force, boxes first).
double closest_self_approach(const ClothView& v, double reach) {
  const std::vector<ViewTriangle> ts = view_triangles({v});
  double best = reach;
  for (std::uint32_t i = 0; i < v.vertex_count; ++i) {
    const Vec3 p = vertex(v, i);
    for (const ViewTriangle& t : ts) {
      if (t.id[0] == i || t.id[1] == i || t.id[2] == i) continue;
      if (((p.array() < t.lo.array() - best) || (p.array() > t.hi.array() + best)).any()) continue;
      const Vec3 w = detail::cg::closest_on_triangle(p, t.p[0], t.p[1], t.p[2]);  // (weights)
      best = std::min(best, (p - (w[0] * t.p[0] + w[1] * t.p[1] + w[2] * t.p[2])).norm());
    }
  }
  return best;
}

// A 48 x 48 cloth of 1.5 m dropped standing on one edge, tilted, so it folds onto itself on the
// ground: with self-collision no two triangles intersect after any frame; without it, they do.
// Also with a collider thickness of 10 cm, past the self contacts' cap of a quarter edge (8 mm):
// the self pairs then have a tree of their own, whose boxes grow by the cap only (sharing the
// colliders' boxes grown by 10 cm made the step 3-5x slower); a box grown too little would let
// folds cross.
TEST(Cloth, SelfCollisionFoldsNeverIntersect) {
  for (const double thickness : {0.005, 0.1}) {
    std::size_t worst[2] = {0, 0};
    for (int on = 0; on < 2; ++on) {
      World w(WorldDef{kFrame, 1, 0.05});
      w.add_plane(PlaneDef{});
      ClothDef d;
      d.rows = d.columns = 48;
      d.width = d.height = 1.5;
      d.mass = 0.4;
      d.thickness = thickness;
      d.transform.rotation = Quat(Eigen::AngleAxisd(std::numbers::pi / 2 - 0.35, Vec3::UnitX()));
      d.transform.translation = Vec3(0.0, 0.0, 0.73 + thickness);
      d.self_collision = on == 1;
      const ClothHandle h = w.add_cloth(d);
      for (int f = 0; f < 45; ++f) {
        w.advance(kFrame);
        const std::size_t n = intersecting_pairs({w.cloth(h)}, true, false);
        worst[on] = std::max(worst[on], n);
        if (on == 1) {
          ASSERT_EQ(n, 0u) << "thickness " << thickness << ", frame " << f;
        }
      }
    }
    EXPECT_GT(worst[0], 0u) << thickness;  // the scene does fold through itself without the pass
  }
}

// One mesh cloth of two parallel 0.5 m layers, the lower pinned, the upper 5 cm above it and
// falling onto it, with self-collision: the self contacts reach a quarter of the shortest edge
// (10 cm cells: 2.5 cm), so the upper layer comes to rest that far above the lower. With a
// collider thickness above the cap (10 cm), the self pairs are found in a tree of their own
// whose boxes grow by the cap; grown by nothing, it found the pairs only once they crossed.
TEST(Cloth, SelfContactsReachTheirCapWhateverTheColliderThickness) {
  for (const double thickness : {0.1, 0.04, 0.015}) {
    ClothDef d;
    for (int layer = 0; layer < 2; ++layer)
      for (int j = 0; j < 6; ++j)
        for (int i = 0; i < 6; ++i) d.mesh.vertices.emplace_back(0.1 * i, 0.1 * j, 0.05 * layer);
    for (std::uint32_t layer = 0; layer < 2; ++layer)
      for (std::uint32_t j = 0; j < 5; ++j)
        for (std::uint32_t i = 0; i < 5; ++i) {
          const std::uint32_t a = 36 * layer + 6 * j + i;
          for (const std::uint32_t v : {a, a + 1, a + 7, a, a + 7, a + 6}) d.mesh.triangles.push_back(v);
        }
    for (std::size_t v = 0; v < 36; ++v) d.pins.push_back(ClothPin{0, v, {}});
    d.mass = 0.2;
    d.thickness = thickness;
    d.self_collision = true;
    World w(WorldDef{kFrame, 1, 0.05});
    const ClothHandle h = w.add_cloth(d);
    for (int f = 0; f < 30; ++f) w.advance(kFrame);
    const double cap = std::min(thickness, 0.25 * 0.1);
    const ClothView v = w.cloth(h);
    double top = 1.0;  // the upper layer's lowest vertex
    for (std::size_t k = 36; k < 72; ++k) top = std::min(top, double(v.positions[3 * k + 2]));
    EXPECT_LT(top, 1.5 * cap) << "thickness " << thickness << ": the upper layer fell onto the lower";
    EXPECT_GT(closest_self_approach(v, 0.2), 0.9 * cap) << "thickness " << thickness;
  }
}

// Two 32 x 32 cloths dropped on each other onto the ground, the upper one turned by 30 degrees:
// no triangle of one ever intersects a triangle of the other; with collide_cloths off they pass
// through each other.
TEST(Cloth, TwoClothsDroppedOnEachOtherNeverIntersect) {
  std::size_t worst[2] = {0, 0};
  for (int on = 0; on < 2; ++on) {
    World w(WorldDef{kFrame, 1, 0.05});
    w.add_plane(PlaneDef{});
    SphereDef ball;  // the lower cloth drapes over it, the upper one onto the lower
    ball.radius = 0.25;
    ball.transform.translation = Vec3(0.0, 0.0, 0.25);
    w.add_sphere(ball);
    ClothDef lower = flat_cloth(32, 1.0, 0.2, 0.6);
    ClothDef upper = flat_cloth(32, 1.0, 0.2, 0.9);
    upper.transform.rotation = Quat(Eigen::AngleAxisd(std::numbers::pi / 6, Vec3::UnitZ()));
    upper.transform.translation = Vec3(0.1, 0.05, 0.9);
    lower.collide_cloths = upper.collide_cloths = on == 1;
    std::vector<ClothHandle> hs = {w.add_cloth(lower), w.add_cloth(upper)};
    for (int f = 0; f < 45; ++f) {
      w.advance(kFrame);
      const std::size_t n = intersecting_pairs({w.cloth(hs[0]), w.cloth(hs[1])}, false, true);
      worst[on] = std::max(worst[on], n);
      if (on == 1) {
        ASSERT_EQ(n, 0u) << "frame " << f;
      }
    }
  }
  EXPECT_GT(worst[0], 0u);
}


// Issue 16: a kinematic ball (radius 0.3 m) rising out of the floor under a 1.6 m sheet lying on
// it lifts the sheet, whose sides slide in over the floor: after every frame no stretch or shear
// spring is past the strain limit (10%), and the sheet is on top of the ball. Before the fix
// the pass froze the sheet around the ball, which stretched it to 4.2 times the limit (strain
// 4.21; the demo saw it twice its size).
TEST(Cloth, SphereRisingUnderSheetOnFloorKeepsStrainLimit) {
  World w(WorldDef{kFrame, 1, 0.05});
  w.add_plane(PlaneDef{});
  ClothDef def = flat_cloth(32, 1.6, 0.3, 0.006);
  SphereDef ball;
  ball.radius = 0.3;
  ball.path.keys = {{0.0, Vec3(0.05, 0.03, -0.32), Quat::Identity()},
                    {1.5, Vec3(0.05, 0.03, 0.5), Quat::Identity()}};
  ball.transform.translation = ball.path.keys[0].position;
  w.add_sphere(ball);
  const ClothHandle h = w.add_cloth(def);
  double worst = 0.0;
  for (int f = 0; f < 100; ++f) {
    w.advance(kFrame);
    worst = std::max(worst, w.cloth_stats(h).max_strain);
  }
  EXPECT_LE(worst, 0.10 + kStrainEps);
  EXPECT_GT(w.cloth_stats(h).max_z, 0.8);  // on the ball's top (0.5 + 0.3 m)
}
