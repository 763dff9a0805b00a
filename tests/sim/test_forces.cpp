// Forces against closed forms (Coutinho §3.3): viscous drag, damped springs (eq. 3.6), Coulomb
// and gravitational pair forces with a cut-off (§3.3.4), field drop-off, attractor springs
// (§3.3.5), curl noise (Bridson et al. 2007), and bit-identical results at 1 and 2 threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <utility>
#include <vector>

#include "particles/forces.hpp"  // private: curl noise is checked directly
#include "particles/integrators.hpp"
#include "particles/particle_store.hpp"
#include "sim_test_util.hpp"
#include "simreel/sim/random.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

using test::position_of;
using test::velocity_of;

ParticleSystemDef probe_system(Integrator integrator, const Vec3& gravity = Vec3::Zero()) {
  ParticleSystemDef def = test::spawn_only_system();
  def.integrator = integrator;
  def.gravity = gravity;
  def.collide = false;
  return def;
}

InitialParticle particle(const Vec3& x, double m = 1.0, double q = 0.0, const Vec3& v = Vec3::Zero()) {
  InitialParticle p;
  p.position = x;
  p.velocity = v;
  p.mass = m;
  p.charge = q;
  return p;
}

/// Accelerations at the initial state: one explicit Euler step from rest gives Δv = h a(x0).
std::vector<Vec3> initial_accelerations(World& world, ParticleSystemHandle ps, double h) {
  world.advance(h);
  const ParticleView v = world.particles(ps);
  std::vector<Vec3> a;
  for (std::size_t i = 0; i < v.count; ++i) a.push_back(velocity_of(v, i) / h);
  return a;
}

/// Initial accelerations of `particles` under pair forces alone (G, K, cut-off; the default
/// softening), from one explicit Euler step of 1e-4 s.
std::vector<Vec3> pair_accelerations(double G, double K, double cutoff,
                                     std::vector<InitialParticle> particles) {
  const double h = 1e-4;
  World world(WorldDef{h, 1, 0.05});
  auto d = probe_system(Integrator::explicit_euler);
  d.pair_forces.gravitational_G = G;
  d.pair_forces.coulomb_K = K;
  d.pair_forces.cutoff = cutoff;
  d.initial_particles = std::move(particles);
  const auto ps = world.add_particle_system(d);
  return initial_accelerations(world, ps, h);
}

// ---------------------------------------------------------------------------------------------
// Drag (§3.3.2)

TEST(SimForces, DragDecaysVelocityExponentially) {
  // No gravity: v(t) = v0 exp(-k t / m), for the general (rk2) and the fast (rk4) paths.
  const double k = 0.3, m = 0.2, T = 1.0;
  for (Integrator in : {Integrator::rk2, Integrator::rk4, Integrator::adaptive}) {
    World world(WorldDef{1.0 / 200, 1, 0.05});
    const auto ps = world.add_particle_system([&] {
      auto d = probe_system(in);
      d.drag = k;
      return d;
    }());
    world.spawn_particle(ps, Vec3::Zero(), Vec3(2, 0, -1), m, 0.01, 100);
    for (int i = 0; i < 200; ++i) world.advance(1.0 / 200);
    const Vec3 v = velocity_of(world.particles(ps), 0);
    const double e = std::exp(-k * T / m);
    EXPECT_NEAR(v.x(), 2.0 * e, 2e-5) << int(in);
    EXPECT_NEAR(v.z(), -1.0 * e, 2e-5) << int(in);
  }
}

TEST(SimForces, DragGivesTerminalVelocityMgOverK) {
  const double k = 0.05, m = 0.01, g = 9.81;
  for (Integrator in : {Integrator::semi_implicit_euler, Integrator::explicit_euler,
                        Integrator::implicit_euler}) {
    World world(WorldDef{1.0 / 240, 1, 0.05});
    auto d = probe_system(in, Vec3(0, 0, -g));
    d.drag = k;
    d.initial_particles = {particle(Vec3(0, 0, 100), m)};
    const auto ps = world.add_particle_system(d);
    world.advance(3.0);  // 15 time constants m/k
    EXPECT_NEAR(velocity_of(world.particles(ps), 0).z(), -m * g / k, 1e-4) << int(in);
  }
}

// ---------------------------------------------------------------------------------------------
// Springs (§3.3.3)

struct PairRun {
  std::vector<double> t, extension;
  Vec3 com_error_max = Vec3::Zero();
};

PairRun spring_pair(double m1, double m2, double ks, double kd, double T, double h) {
  World world(WorldDef{h, 1, 0.05});
  auto d = probe_system(Integrator::rk4);
  d.initial_particles = {particle(Vec3(0, 0, 0), m1, 0, Vec3(0.3, 0.1, 0)),
                         particle(Vec3(1.2, 0, 0), m2, 0, Vec3(-0.1, 0.2, 0))};
  d.springs = {SpringDef{0, 1, ks, kd, 1.0}};
  const auto ps = world.add_particle_system(d);
  const double M = m1 + m2;
  const Vec3 com0 = Vec3(1.2 * m2, 0, 0) / M;
  const Vec3 vcom = (m1 * Vec3(0.3, 0.1, 0) + m2 * Vec3(-0.1, 0.2, 0)) / M;
  PairRun r;
  const int n = int(std::lround(T / h));
  for (int i = 1; i <= n; ++i) {
    world.advance(h);
    const ParticleView v = world.particles(ps);
    const Vec3 a = position_of(v, 0), b = position_of(v, 1);
    r.t.push_back(i * h);
    r.extension.push_back((a - b).norm() - 1.0);
    const Vec3 com = (m1 * a + m2 * b) / M;
    r.com_error_max = r.com_error_max.cwiseMax((com - com0 - vcom * (i * h)).cwiseAbs());
  }
  return r;
}

TEST(SimForces, SpringPairOscillatesWithReducedMassPeriod) {
  // T = 2π sqrt(μ / k_s), μ = m1 m2 / (m1 + m2): measured between upward zero crossings of the
  // extension (the spinning pair adds a small centrifugal term; the spin here is slow).
  const double m1 = 1.0, m2 = 3.0, ks = 30.0, mu = m1 * m2 / (m1 + m2);
  const PairRun r = spring_pair(m1, m2, ks, 0.0, 4.0, 1e-3);
  std::vector<double> up;
  for (std::size_t i = 1; i < r.t.size(); ++i)
    if (r.extension[i - 1] < 0 && r.extension[i] >= 0) {
      const double w = r.extension[i - 1] / (r.extension[i - 1] - r.extension[i]);
      up.push_back(r.t[i - 1] + w * (r.t[i] - r.t[i - 1]));
    }
  ASSERT_GE(up.size(), 3u);
  const double period = (up.back() - up.front()) / double(up.size() - 1);
  EXPECT_NEAR(period, 2 * std::numbers::pi * std::sqrt(mu / ks), 5e-3);
}

TEST(SimForces, SpringDampingLeavesTheCentreOfMassAlone) {
  const PairRun r = spring_pair(1.0, 3.0, 30.0, 2.0, 3.0, 1e-3);
  EXPECT_LT(r.com_error_max.maxCoeff(), 2e-5);
  EXPECT_LT(std::abs(r.extension.back()), 0.2 * std::abs(r.extension.front()));  // damped
}

TEST(SimForces, AddSpringBetweenLiveIdsUsesCurrentDistance) {
  World world(WorldDef{1e-3, 1, 0.05});
  const auto ps = world.add_particle_system(probe_system(Integrator::semi_implicit_euler));
  const auto a = world.spawn_particle(ps, Vec3(0, 0, 0), Vec3(-1, 0, 0), 1, 0.01, 100);
  const auto b = world.spawn_particle(ps, Vec3(0.5, 0, 0), Vec3(1, 0, 0), 1, 0.01, 100);
  world.add_spring(ps, SpringDef{a, b, 100.0, 0.0, -1.0});
  EXPECT_THROW(world.add_spring(ps, SpringDef{a, 99, 1.0, 0.0, -1.0}), std::invalid_argument);
  // Pulled back: the separation never exceeds rest + v_rel / ω by much, ω = sqrt(k / μ).
  double max_sep = 0;
  for (int i = 0; i < 1000; ++i) {
    world.advance(1e-3);
    const ParticleView v = world.particles(ps);
    max_sep = std::max(max_sep, (position_of(v, 0) - position_of(v, 1)).norm());
  }
  EXPECT_NEAR(max_sep, 0.5 + 2.0 / std::sqrt(100.0 / 0.5), 2e-3);
}

// ---------------------------------------------------------------------------------------------
// Pair forces (§3.3.4)

TEST(SimForces, CoulombLikeRepelUnlikeAttractInverseSquare) {
  auto run = [&](double q1, double q2, double r) {
    return pair_accelerations(0.0, 2.0, 1.0,
                              {particle(Vec3(0, 0, 0), 1.0, q1), particle(Vec3(r, 0, 0), 0.5, q2)});
  };
  const auto like = run(1.0, 1.0, 0.5);
  EXPECT_NEAR(like[0].x(), -2.0 / 0.25, 1e-4);  // pushed to -x, K q q / r² / m
  EXPECT_NEAR(like[1].x(), 2.0 / 0.25 / 0.5, 2e-4);
  EXPECT_NEAR(like[0].y(), 0.0, 1e-9);
  const auto unlike = run(1.0, -1.0, 0.5);
  EXPECT_NEAR(unlike[0].x(), 2.0 / 0.25, 1e-4);  // pulled to +x
  const auto far = run(1.0, 1.0, 0.25);
  EXPECT_NEAR(far[0].x() / like[0].x(), 4.0, 1e-4);  // 1 / r²
  const auto beyond = run(1.0, 1.0, 1.01);
  EXPECT_EQ(beyond[0].x(), 0.0);
  EXPECT_EQ(beyond[1].x(), 0.0);
}

// 600 km from the origin (within the default max_distance of 1,000 km) a 0.5 m cut-off puts
// the particles 1.2 million cells out, beyond the cell keys' +-2^20: the pair must still meet
// once (the keys once clamped its neighbour columns onto one another: it met nine times).
TEST(SimForces, CoulombPairFarFromTheOriginMeetsOnce) {
  const Vec3 o(6e5, -6e5, 6e5);  // (0.25 m apart stays exact in float out there)
  const auto a = pair_accelerations(0.0, 2.0, 0.5,
                                    {particle(o, 1.0, 1.0), particle(o + Vec3(0.25, 0, 0), 0.5, 1.0)});
  EXPECT_NEAR(a[0].x(), -2.0 / 0.0625, 1e-3);  // K q q / r² / m
  EXPECT_NEAR(a[1].x(), 2.0 / 0.0625 / 0.5, 2e-3);
}

TEST(SimForces, GravitationalPairAttracts) {
  const auto a = pair_accelerations(3.0, 0.0, 5.0,
                                    {particle(Vec3(0, 0, 0), 2.0), particle(Vec3(0, 0, 2), 1.0)});
  EXPECT_NEAR(a[0].z(), 3.0 * 1.0 / 4.0, 1e-5);   // G m2 / r², toward the other
  EXPECT_NEAR(a[1].z(), -3.0 * 2.0 / 4.0, 1e-5);
}

TEST(SimForces, CutoffGridEqualsBruteForce) {
  const double h = 1e-4, K = 0.7, G = 0.4, cutoff = 0.45;
  auto d = probe_system(Integrator::explicit_euler);
  d.emitter.max_particles = 400;
  d.pair_forces = {G, K, cutoff, 0.0};
  Rng rng(7);
  for (int i = 0; i < 400; ++i)
    d.initial_particles.push_back(particle(Vec3(rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5),
                                                rng.uniform(-1.5, 1.5)),
                                           rng.uniform(0.5, 2.0), rng.uniform(-1.0, 1.0)));
  World world(WorldDef{h, 1, 0.05});
  const auto ps = world.add_particle_system(d);
  const ParticleView v0 = world.particles(ps);
  std::vector<Vec3> x;
  std::vector<double> q, m;
  for (std::size_t i = 0; i < v0.count; ++i) {
    x.push_back(position_of(v0, i));
    q.push_back(v0.charge[i]);
    m.push_back(d.initial_particles[i].mass);
  }
  const auto a = initial_accelerations(world, ps, h);
  int interacting = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    Vec3 f = Vec3::Zero();
    for (std::size_t j = 0; j < x.size(); ++j) {
      const Vec3 r = x[i] - x[j];
      const double r2 = r.squaredNorm();
      if (i == j || !(r2 < cutoff * cutoff)) continue;
      f += (K * q[i] * q[j] - G * float(m[i]) * float(m[j])) * r / (r2 * std::sqrt(r2));
    }
    const Vec3 expected = f / double(float(m[i]));
    interacting += expected.norm() > 0;
    EXPECT_LT((a[i] - expected).norm(), 1e-5 * (1 + expected.norm())) << i;
  }
  EXPECT_GT(interacting, 300);  // the cloud is dense enough to test something
}

// ---------------------------------------------------------------------------------------------
// Fields

TEST(SimForces, FieldFalloffNoneLinearQuadratic) {
  // A uniform 1 m/s² field in a sphere of radius 2 and a box of half extents (2, 4, 4): the
  // weight at normalised distance d is 1, 1 - d, (1 - d)² inside and 0 outside.
  const double h = 1e-3;
  const std::vector<double> dist = {0.0, 1.0, 2.0, 3.0};  // centre, half, boundary, outside
  for (RegionShape shape : {RegionShape::sphere, RegionShape::box}) {
    for (Falloff fo : {Falloff::none, Falloff::linear, Falloff::quadratic}) {
      World world(WorldDef{h, 1, 0.05});
      auto d = probe_system(Integrator::explicit_euler);
      for (double r : dist) d.initial_particles.push_back(particle(Vec3(5 + r, 0, 0)));
      const auto ps = world.add_particle_system(d);
      ForceFieldDef f;
      f.kind = FieldKind::uniform;
      f.shape = shape;
      f.radius = 2.0;
      f.half_extents = Vec3(2, 4, 4);
      f.falloff = fo;
      f.transform.translation = Vec3(5, 0, 0);
      f.acceleration = Vec3(0, 0, 1);
      world.add_force_field(f);
      const auto a = initial_accelerations(world, ps, h);
      const double expect[3][4] = {{1, 1, 1, 0}, {1, 0.5, 0, 0}, {1, 0.25, 0, 0}};
      for (std::size_t k = 0; k < dist.size(); ++k)
        EXPECT_NEAR(a[k].z(), expect[int(fo)][k], 1e-6) << int(shape) << " " << int(fo) << " " << k;
    }
  }
}

TEST(SimForces, AttractorAndVortexDirections) {
  const double h = 1e-3;
  World world(WorldDef{h, 1, 0.05});
  auto d = probe_system(Integrator::explicit_euler);
  d.initial_particles = {particle(Vec3(2, 0, 0)), particle(Vec3(0, 3, 1))};
  const auto ps = world.add_particle_system(d);
  ForceFieldDef at;
  at.kind = FieldKind::attractor;
  at.strength = 2.0;
  world.add_force_field(at);
  ForceFieldDef vx;
  vx.kind = FieldKind::vortex;
  vx.strength = 1.0;
  vx.inward_strength = 0.5;
  world.add_force_field(vx);
  const auto a = initial_accelerations(world, ps, h);
  // Particle 0 at (2,0,0): attractor -2 x̂; vortex z × x̂ = ŷ, inward -0.5 x̂.
  EXPECT_NEAR(a[0].x(), -2.5, 1e-6);
  EXPECT_NEAR(a[0].y(), 1.0, 1e-6);
  // Particle 1 at (0,3,1): attractor 2 (0,-3,-1)/sqrt(10); vortex z × ŷ = -x̂, inward -0.5 ŷ.
  EXPECT_NEAR(a[1].x(), -1.0, 1e-6);
  EXPECT_NEAR(a[1].y(), -6.0 / std::sqrt(10.0) - 0.5, 1e-6);
  EXPECT_NEAR(a[1].z(), -2.0 / std::sqrt(10.0), 1e-6);
}

TEST(SimForces, FieldFollowsItsPathAndItsSystemList) {
  const double h = 1e-3;
  World world(WorldDef{h, 1, 0.05});
  auto d = probe_system(Integrator::explicit_euler);
  d.initial_particles = {particle(Vec3(10, 0, 0))};
  const auto inside = world.add_particle_system(d);
  const auto other = world.add_particle_system(d);
  ForceFieldDef f;
  f.shape = RegionShape::sphere;
  f.radius = 1.0;
  f.acceleration = Vec3(0, 0, 1);
  f.path.keys = {Keyframe{0.0, Vec3(10, 0, 0), Quat::Identity()}, Keyframe{1.0, Vec3(20, 0, 0), Quat::Identity()}};
  f.path.smooth = false;
  f.systems = {inside};
  world.add_force_field(f);
  EXPECT_NEAR(initial_accelerations(world, inside, h)[0].z(), 1.0, 1e-6);
  EXPECT_EQ(velocity_of(world.particles(other), 0).z(), 0.0);
  world.advance(0.5);  // the sphere moved to x = 15: the particle is left behind
  const double vz = velocity_of(world.particles(inside), 0).z();
  world.advance(h);
  EXPECT_EQ(velocity_of(world.particles(inside), 0).z(), vz);
}

// ---------------------------------------------------------------------------------------------
// Blast on particles (forces.hpp FieldKind::blast)

/// Δv of a particle of mass m and radius r at distance d from a blast of momentum Π: the share
/// Π π r² / (4π max(d, r)²) of the pulse over the particle's mass plus the added mass of a sphere
/// in air, ½ ρ_air (4/3)π r³.
double blast_dv(double Pi, double m, double r, double d) {
  const double reach = std::max(d, r);
  const double J = Pi * std::numbers::pi * r * r / (4.0 * std::numbers::pi * reach * reach);
  return J / (m + 0.5 * 1.225 * 4.0 / 3.0 * std::numbers::pi * r * r * r);
}

TEST(SimForces, BlastPushesParticlesOnceWithTheirShareOfThePulseAtAnyStep) {
  // Three particles at rest, no gravity or drag: after the blast each moves outward at the
  // closed-form speed, the same whatever the step (an impulse, not a force), and nothing changes
  // before or after the step holding the blast time.
  const double Pi = 50.0;
  const Vec3 centre(0.0, 0.0, 1.0);
  const std::vector<Vec3> at = {{3.0, 0.0, 1.0}, {0.0, -1.5, 2.0}, {0.02, 0.0, 1.0}};
  const std::vector<double> mass = {2e-4, 2e-4, 1e-3}, radius = {0.05, 0.8, 0.05};
  for (const double h : {1.0 / 60.0, 1.0 / 240.0, 1.0 / 1000.0}) {
    World world(WorldDef{h, 1, 0.05});
    auto d = probe_system(Integrator::semi_implicit_euler);
    for (std::size_t k = 0; k < at.size(); ++k) {
      InitialParticle p = particle(at[k], mass[k]);
      p.radius = radius[k];
      d.initial_particles.push_back(p);
    }
    const auto ps = world.add_particle_system(d);
    world.add_force_field(test::blast_field(centre, Pi, 0.1));
    world.advance(0.09);
    for (std::size_t k = 0; k < at.size(); ++k)
      EXPECT_EQ(velocity_of(world.particles(ps), k).norm(), 0.0) << "before the blast, h " << h;
    world.advance(0.05);
    const ParticleView v = world.particles(ps);
    for (std::size_t k = 0; k < at.size(); ++k) {
      const Vec3 out = at[k] - centre;
      const Vec3 expected = blast_dv(Pi, mass[k], radius[k], out.norm()) * out.normalized();
      EXPECT_NEAR((velocity_of(v, k) - expected).norm(), 0.0, 2e-6 * expected.norm())
          << "particle " << k << ", h " << h;
    }
    const Vec3 v0 = velocity_of(v, 0);
    world.advance(0.1);
    EXPECT_EQ(velocity_of(world.particles(ps), 0), v0) << "once only";
  }
  // The figures behind the model: a 0.2 g, 5 cm spark 3 m from a 50 N s blast takes 6.7 m/s; a
  // 0.2 g smoke puff of 0.8 m at 1.8 m is held back by the air it carries to 1.9 m/s, where its
  // own mass alone would have taken J / m = 12,000 m/s.
  EXPECT_NEAR(blast_dv(Pi, 2e-4, 0.05, 3.0), 6.67, 0.01);
  EXPECT_NEAR(blast_dv(Pi, 2e-4, 0.8, std::sqrt(1.5 * 1.5 + 1.0)), 1.87, 0.01);
}

TEST(SimForces, BlastLeavesItsOwnProductsOtherSystemsAndParticlesFalseAlone) {
  // An emitter bursting at the blast time (the explosion's fragments) is not pushed: its
  // particles are bit-identical to a run without the blast. A particle alive before it is.
  auto run = [](bool with_blast, bool particles_flag, bool list_other) {
    const double h = 1.0 / 240.0;
    World world(WorldDef{h, 1, 0.05});
    ParticleSystemDef burst = probe_system(Integrator::semi_implicit_euler);
    burst.name = "fragments";
    burst.emitter.bursts = {Burst{0.25, 50, 0.0, 1}};
    burst.emitter.start_speed = Distribution{5.0, 1.0, 0.0};
    burst.emitter.spread_deg = Distribution{0.0, 60.0, 0.0, 180.0};
    burst.emitter.transform.translation = Vec3(0.0, 0.0, 1.0);
    const auto fragments = world.add_particle_system(burst);
    auto d = probe_system(Integrator::semi_implicit_euler);
    d.name = "dust";
    d.initial_particles = {particle(Vec3(1.0, 0.0, 1.0), 1e-3)};
    const auto dust = world.add_particle_system(d);
    if (with_blast) {
      ForceFieldDef blast = test::blast_field(Vec3(0.0, 0.0, 1.0), 20.0, 0.25);
      blast.particles = particles_flag;
      if (list_other) blast.systems = {fragments};
      world.add_force_field(blast);
    }
    world.advance(0.5);
    const ParticleView f = world.particles(fragments);
    std::vector<float> state(f.velocity, f.velocity + 3 * f.count);
    state.insert(state.end(), f.position, f.position + 3 * f.count);
    return std::make_pair(state, velocity_of(world.particles(dust), 0));
  };
  const auto [plain, dust_plain] = run(false, true, false);
  const auto [blasted, dust_blasted] = run(true, true, false);
  ASSERT_EQ(plain.size(), 2u * 3u * 50u);
  EXPECT_EQ(plain, blasted) << "the fragments born with the blast are its products";
  EXPECT_EQ(dust_plain.norm(), 0.0);
  EXPECT_NEAR(dust_blasted.x(), blast_dv(20.0, 1e-3, 0.01, 1.0), 1e-6);
  EXPECT_EQ(run(true, false, false).second.norm(), 0.0) << "particles: false";
  EXPECT_EQ(run(true, true, true).second.norm(), 0.0) << "a blast listing another system";
}

TEST(SimForces, AttractorSpringPullsChosenParticlesToAMovingAnchor) {
  World world(WorldDef{1e-3, 1, 0.05});
  auto d = probe_system(Integrator::implicit_euler);
  d.initial_particles = {particle(Vec3(0, 0, 0)), particle(Vec3(1, 0, 0))};
  const auto ps = world.add_particle_system(d);
  AttractorSpringDef s;
  s.system = ps;
  s.ids = {1};
  s.stiffness = 100.0;
  s.damping = 20.0;  // critical: 2 sqrt(k m)
  s.path.smooth = false;
  s.path.keys = {Keyframe{0.0, Vec3(0, 2, 0), Quat::Identity()}, Keyframe{4.0, Vec3(0, 6, 0), Quat::Identity()}};
  world.add_attractor_spring(s);
  world.advance(2.0);
  const ParticleView v = world.particles(ps);
  EXPECT_EQ(position_of(v, 0), Vec3(0, 0, 0));  // not chosen
  // Following a ramp at 1 m/s with zero-rest spring and matched velocity damping: no lag.
  EXPECT_LT((position_of(v, 1) - Vec3(0, 4, 0)).norm(), 2e-3);
}

// ---------------------------------------------------------------------------------------------
// Curl noise (Bridson et al. 2007)

TEST(SimForces, BatchedCurlIsBitIdenticalToTheCurlOfSample) {
  // GradientNoise::curl() (the vectorised batch eval() uses for curl-noise fields) must give the
  // curl of sample()'s three gradients bit for bit, including integer cells, negative
  // coordinates, far points (up to the 2^30 limit of its 32-bit cells) and beyond it (the
  // scalar path, whose 64-bit cells wrap to the same 32 bits).
  detail::GradientNoise noise(17);
  Rng rng(23);
  std::vector<double> px, py, pz;
  for (int i = 0; i < 1000; ++i) {
    const double scale = i < 900 ? 50.0 : 1e9;
    px.push_back(rng.uniform(-scale, scale));
    py.push_back(i % 7 == 0 ? std::floor(py.empty() ? 0.0 : py.back()) : rng.uniform(-scale, scale));
    pz.push_back(rng.uniform(-scale, scale));
  }
  px.push_back(3e9);  // past the limit: its batch of 64 goes through the scalar path
  py.push_back(0.5);
  pz.push_back(-0.25);
  for (std::size_t n : {px.size() - 1, px.size()}) {
    std::vector<double> ux(n), uy(n), uz(n);
    noise.curl(n, px.data(), py.data(), pz.data(), ux.data(), uy.data(), uz.data());
    for (std::size_t k = 0; k < n; ++k) {
      const Vec3 p(px[k], py[k], pz[k]);
      Vec3 g1, g2, g3;
      noise.sample(0, p, g1);
      noise.sample(1, p, g2);
      noise.sample(2, p, g3);
      auto minus = [](double a, double b) { return double(float(a) - float(b)); };  // in float
      const Vec3 u(minus(g3.y(), g2.z()), minus(g1.z(), g3.x()), minus(g2.x(), g1.y()));
      ASSERT_EQ(std::memcmp(&u[0], &ux[k], sizeof(double)), 0) << k;
      ASSERT_EQ(std::memcmp(&u[1], &uy[k], sizeof(double)), 0) << k;
      ASSERT_EQ(std::memcmp(&u[2], &uz[k], sizeof(double)), 0) << k;
      const Vec3 one = detail::curl_noise(noise, p);
      ASSERT_EQ(std::memcmp(one.data(), u.data(), sizeof u), 0) << k;
    }
  }
}

TEST(SimForces, CurlNoiseFormsGiveTheSameBits) {
  // GradientNoise::curl()'s AVX-512 form (sixteen points a register, lanes 16, on CPUs that have
  // it) and the compiler's clones (lanes 1) must give the same bits at every length, the masked
  // tail of each chunk of 64 included: points over a few cells either side of zero, integer
  // coordinates and ±0 among them.
  detail::GradientNoise noise(5);
  Rng rng(29);
  for (std::size_t n : {0, 1, 7, 8, 9, 15, 16, 17, 31, 33, 63, 64, 65, 100, 257}) {
    std::vector<double> px(n), py(n), pz(n);
    for (std::size_t k = 0; k < n; ++k) {
      px[k] = rng.uniform(-4, 4);
      py[k] = k % 5 == 0 ? std::floor(rng.uniform(-4, 4)) : rng.uniform(-4, 4);
      pz[k] = k % 9 == 0 ? (k % 2 == 0 ? 0.0 : -0.0) : rng.uniform(-4, 4);
    }
    std::vector<double> a(3 * n + 1, 7.0), b(3 * n + 1, 7.0);  // (+1: nothing past the end)
    noise.curl(n, px.data(), py.data(), pz.data(), a.data(), a.data() + n, a.data() + 2 * n, 1);
    noise.curl(n, px.data(), py.data(), pz.data(), b.data(), b.data() + n, b.data() + 2 * n, 16);
    ASSERT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0) << "n = " << n;
  }
}

/// FNV-1a over the bits of the curl (lanes 1 and 16) and of sample()'s values and gradients at
/// 4,000 points of seed 11's noise: the realisation CurlNoiseKeepsItsRealisation pins.
std::uint64_t curl_noise_fingerprint() {
  detail::GradientNoise noise(11);
  Rng rng(31);
  const std::size_t n = 4000;
  std::vector<double> px(n), py(n), pz(n), u(3 * n);
  for (std::size_t k = 0; k < n; ++k) {
    const double scale = k % 4 == 3 ? 1e6 : 20.0;
    px[k] = rng.uniform(-scale, scale);
    py[k] = k % 5 == 0 ? std::floor(rng.uniform(-4, 4)) : rng.uniform(-scale, scale);
    pz[k] = k % 9 == 0 ? (k % 2 == 0 ? 0.0 : -0.0) : rng.uniform(-scale, scale);
  }
  std::uint64_t h = 0xcbf29ce484222325ull;
  const auto mix = [&h](double v) {
    std::uint64_t b;
    std::memcpy(&b, &v, sizeof b);
    for (int i = 0; i < 8; ++i) h = (h ^ ((b >> (8 * i)) & 0xffu)) * 0x100000001b3ull;
  };
  for (int lanes : {1, 16}) {
    noise.curl(n, px.data(), py.data(), pz.data(), u.data(), u.data() + n, u.data() + 2 * n, lanes);
    for (double v : u) mix(v);
  }
  for (std::size_t k = 0; k < n; k += 3)
    for (int c = 0; c < 3; ++c) {
      Vec3 g;
      mix(noise.sample(c, Vec3(px[k], py[k], pz[k]), g));
      mix(g.x());
      mix(g.y());
      mix(g.z());
    }
  return h;
}

TEST(SimForces, CurlNoiseKeepsItsRealisation) {
  // The noise's bits, pinned: a faster form of potential() (another order of its statements,
  // another register use) must give exactly these, or every curl-noise scene changes. Recorded
  // at stop 78 from the build before its reordering of potential(), and unchanged by it. Change
  // the constant only with a deliberate change of the noise, and re-record the smoke and fire
  // goldens from frames looked at.
  EXPECT_EQ(curl_noise_fingerprint(), 0xb608b5f5a9180ca3ull);
}

TEST(SimForces, NoiseGradientIsTheDerivativeOfTheNoise) {
  // Single precision: central differences over 2e-3 (truncation ~1e-6, rounding ~5e-5).
  detail::GradientNoise noise(3);
  Rng rng(5);
  const double e = 1e-3;
  double max_grad = 0;
  for (int i = 0; i < 50; ++i) {
    const Vec3 p(rng.uniform(-4, 4), rng.uniform(-4, 4), rng.uniform(-4, 4));
    for (int c = 0; c < 3; ++c) {
      Vec3 g, unused;
      noise.sample(c, p, g);
      max_grad = std::max(max_grad, g.cwiseAbs().maxCoeff());
      for (int k = 0; k < 3; ++k) {
        Vec3 dp = Vec3::Zero();
        dp[k] = e;
        const double num =
            (noise.sample(c, p + dp, unused) - noise.sample(c, p - dp, unused)) / (2 * e);
        EXPECT_NEAR(g[k], num, 1e-3) << i << " " << c << " " << k;
      }
    }
  }
  EXPECT_GT(max_grad, 1.0);  // a real slope, not a flat field
}

TEST(SimForces, NoisePotentialsAreDecorrelated) {
  // The three potentials share a lattice but not their gradients: their values at random points
  // correlate by less than 0.1 (copies of one noise would give 1).
  detail::GradientNoise noise(8);
  Rng rng(4);
  double s[3] = {0, 0, 0}, c01 = 0, c02 = 0, c12 = 0;
  for (int i = 0; i < 4000; ++i) {
    const Vec3 p(rng.uniform(-40, 40), rng.uniform(-40, 40), rng.uniform(-40, 40));
    Vec3 g;
    const double a = noise.sample(0, p, g), b = noise.sample(1, p, g), c = noise.sample(2, p, g);
    s[0] += a * a, s[1] += b * b, s[2] += c * c;
    c01 += a * b, c02 += a * c, c12 += b * c;
  }
  EXPECT_GT(s[0], 4000 * 0.02);  // non-trivial variance
  EXPECT_LT(std::abs(c01) / std::sqrt(s[0] * s[1]), 0.1);
  EXPECT_LT(std::abs(c02) / std::sqrt(s[0] * s[2]), 0.1);
  EXPECT_LT(std::abs(c12) / std::sqrt(s[1] * s[2]), 0.1);
}

TEST(SimForces, CurlNoiseIsDivergenceFree) {
  detail::GradientNoise noise(11);
  Rng rng(9);
  const double e = 2e-3;  // single precision: rounding ~1e-4 in each difference quotient
  double mean_speed = 0, max_div = 0, max_partial = 0;
  for (int i = 0; i < 200; ++i) {
    const Vec3 p(rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-5, 5));
    mean_speed += detail::curl_noise(noise, p).norm() / 200;
    double div = 0;
    for (int k = 0; k < 3; ++k) {
      Vec3 dp = Vec3::Zero();
      dp[k] = e;
      const double dk = (detail::curl_noise(noise, p + dp)[k] - detail::curl_noise(noise, p - dp)[k]) / (2 * e);
      div += dk;
      max_partial = std::max(max_partial, std::abs(dk));
    }
    max_div = std::max(max_div, std::abs(div));
  }
  EXPECT_GT(mean_speed, 0.3);    // a real flow, not zero
  EXPECT_GT(max_partial, 0.5);   // with real shear
  EXPECT_LT(max_div, 2e-3);      // O(e²) and rounding of the central differences
}

TEST(SimForces, CurlNoiseDragsParticlesTowardTheFlow) {
  World world(WorldDef{1e-2, 3, 0.05});
  auto d = probe_system(Integrator::semi_implicit_euler);
  d.initial_particles = {particle(Vec3(0.3, 0.2, 0.1), 1e-3)};
  const auto ps = world.add_particle_system(d);
  ForceFieldDef f;
  f.kind = FieldKind::curl_noise;
  f.amplitude = 2.0;
  f.frequency = 0.05;  // nearly uniform around the particle over the test
  f.drag = 0.1;        // relaxation time m / k = 0.01 s
  world.add_force_field(f);
  world.advance(0.2);
  const Vec3 v = velocity_of(world.particles(ps), 0);
  EXPECT_GT(v.norm(), 0.1);
  // Speed should be about amplitude |curl ψ| at the particle, well under 2 amplitude * sqrt(3).
  EXPECT_LT(v.norm(), 2.0 * 2.0 * 3.0 * 0.05 / 0.05);
}

// Semi-implicit Euler with pair forces as the only forces between particles takes them block
// by block with the integration (Dynamics::pair_blocks); the general path computes every
// acceleration first. The same bits either way: 3,000 charged particles at ~16 per m³ (about
// 8 neighbours each), with a uniform wind and a curl-noise field, linear and quadratic drag,
// three steps, at 1 and 2 threads (the split is from 2,048 particles); near the origin, and
// 600 km out (beyond the 32-bit cell coordinates' 472 km at 0.45 m: the grid's 64-bit form,
// from the float store's positions on the blocked path). Varied masses and charges, then one
// mass and one charge for all (an emitter's default: the blocked path then binds no per-particle
// mass or charge, Dynamics::one_mass_charge).
TEST(SimForces, SemiImplicitPairBlocksEqualTheGeneralPathBitForBit) {
  const std::size_t n = 3000;
  const double side = std::cbrt(double(n) / 16.0), h = 1.0 / 240;
  Rng rng(11);
  detail::ParticleStore start;
  start.has_charge = true;
  start.reserve(n);
  start.append(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      start.position[3 * i + std::size_t(k)] = float(rng.uniform(0.0, side));
      start.velocity[3 * i + std::size_t(k)] = float(rng.uniform(-2.0, 2.0));
    }
    start.mass[i] = float(rng.uniform(0.5, 2.0));
    start.charge[i] = float(rng.uniform(-0.2, 0.2));
  }
  ForceFieldDef wind;
  wind.kind = FieldKind::uniform;
  wind.acceleration = Vec3(0.3, -0.2, 0.1);
  ForceFieldDef curl;
  curl.kind = FieldKind::curl_noise;
  curl.amplitude = 1.5;
  curl.frequency = 0.4;
  curl.drag = 0.2;
  // one: 0 varied, 1 one mass and one charge, 2 the same but the last particle twice as heavy
  // (past the first 64 a check looks at first: the blocked path must not take mass0 for it).
  const auto run = [&](bool pair_blocks, double drag_quadratic, int threads, float offset, int one) {
    detail::ParticleStore s = start;
    for (std::size_t i = 0; i < n; ++i) {
      s.position[3 * i] += offset;
      if (one != 0) {
        s.mass[i] = 1.25f;
        s.charge[i] = -0.15f;
      }
    }
    if (one == 2) s.mass[n - 1] = 2.5f;
    detail::FieldState f1{wind, detail::GradientNoise(3)}, f2{curl, detail::GradientNoise(3)};
    detail::Dynamics dyn;
    dyn.gravity = Vec3(0.0, 0.0, -9.81);
    dyn.drag = 0.05;
    dyn.drag_quadratic = drag_quadratic;
    dyn.pair = PairForceDef{0.2, 5.0, 0.45, 1e-3};
    dyn.fields = {&f1, &f2};
    dyn.threads = threads;
    dyn.pair_blocks = pair_blocks;
    detail::IntegratorState state;
    detail::IntegratorWorkspace w;
    for (int step = 0; step < 3; ++step)
      EXPECT_FALSE(detail::integrate_system(s, 0, n, step * h, h, dyn,
                                            Integrator::semi_implicit_euler, 1e-6, state, w));
    std::vector<float> out(s.position.data(), s.position.data() + 3 * n);
    out.insert(out.end(), s.velocity.data(), s.velocity.data() + 3 * n);
    out.insert(out.end(), s.age.data(), s.age.data() + n);  // (each advanced by h, 3 times)
    return out;
  };
  for (const int one : {0, 1, 2})
    for (const float offset : {0.0f, 6e5f})
      for (const double c2 : {0.0, 0.01}) {
        const std::vector<float> general = run(false, c2, 1, offset, one);
        int moved = 0;
        for (std::size_t k = 1; k < 3 * n; k += 3) moved += general[k] != start.position[k];
        ASSERT_GT(moved, int(n) / 2);
        for (int threads : {1, 2}) {
          const std::vector<float> blocks = run(true, c2, threads, offset, one);
          for (std::size_t k = 0; k < general.size(); ++k)
            ASSERT_EQ(blocks[k], general[k]) << "entry " << k << ", c_2 " << c2 << ", " << threads
                                             << " threads, offset " << offset << ", one mass "
                                             << one;
        }
      }
}

// ---------------------------------------------------------------------------------------------
// Threads

// With pair forces the step takes integrate_system()'s general path (the forces of all
// particles first, then each one's update), whose linear-drag update runs in vectorised blocks
// of Dynamics::kBlock: each particle must still get the scalar semi-implicit step (drag at the
// new velocity, Integrator::semi_implicit_euler) bit for bit, in every block and at any thread
// count. 3 blocks and 5 particles, 2 m apart (no pair within the cut-off: a = g exactly).
TEST(SimForces, SemiImplicitStepWithPairForcesIsTheScalarStepPerParticle) {
  const double h = 1.0 / 240, drag = 0.3;
  const Vec3 g(0.5, -0.25, -9.81);
  const std::size_t n = 3 * detail::Dynamics::kBlock + 5;
  for (int threads : {1, 2}) {
    World world(WorldDef{h, 1, 0.05, threads});
    auto d = probe_system(Integrator::semi_implicit_euler, g);
    d.drag = drag;
    d.pair_forces.coulomb_K = 2.0;
    d.pair_forces.cutoff = 0.5;
    d.emitter.max_particles = n;
    for (std::size_t i = 0; i < n; ++i) {
      const double u = double(i);
      d.initial_particles.push_back(particle(Vec3(2.0 * u, 0.1 * double(i % 7), 3.0), 0.5 + 0.01 * u,
                                             1.0, Vec3(1.0 - 0.03 * u, 0.2, 0.5 * double(i % 5))));
    }
    const auto ps = world.add_particle_system(d);
    const ParticleView before = world.particles(ps);
    ASSERT_EQ(before.count, n);
    std::vector<float> x0(before.position, before.position + 3 * n),
        v0(before.velocity, before.velocity + 3 * n), m(before.mass, before.mass + n);
    world.advance(h);
    const ParticleView after = world.particles(ps);
    for (std::size_t i = 0; i < n; ++i) {
      const double c = drag / double(m[i]);
      const double damp = 1.0 / (1.0 + h * c);
      for (int k = 0; k < 3; ++k) {
        const std::size_t e = 3 * i + std::size_t(k);
        const double v = (double(v0[e]) + h * g[k]) * damp;
        const double x = double(x0[e]) + (h * v - 0.5 * h * h * (g[k] - c * v) * damp * damp);
        ASSERT_EQ(after.velocity[e], float(v)) << "particle " << i << " axis " << k << " " << threads;
        ASSERT_EQ(after.position[e], float(x)) << "particle " << i << " axis " << k << " " << threads;
      }
    }
  }
}

/// A particle system's dynamics with pair forces alone, over the caller's mass and charge
/// arrays (n each), for add_pair_forces().
detail::Dynamics pair_dynamics(const std::vector<double>& mass, const std::vector<double>& charge,
                               const PairForceDef& pf, int threads = 1) {
  detail::Dynamics dyn;
  dyn.n = mass.size();
  dyn.mass = mass.data();
  dyn.charge = charge.data();
  dyn.pair = pf;
  dyn.threads = threads;
  return dyn;
}

// Dense grids take each pair once, in one defined order: the particles ordered by (cell, index)
// over cells of side = cut-off (x-major keys); in a first pass the particles whose cell's x is
// even, then those whose cell's x is odd, each meets the particles after it in that order within
// its 27 cells, and the pair's force F = coef (x_i - x_j) is added to i and subtracted from j.
// This is that order as a brute-force loop over all particles: 0.25 + F_i / m_i for each
// component (charge null: every charge 0).
std::vector<double> ordered_pair_accelerations(const std::vector<double>& x,
                                               const std::vector<double>& mass,
                                               const double* charge, const PairForceDef& pf) {
  const std::size_t n = mass.size();
  const double inv = 1.0 / pf.cutoff;
  auto cell = [&](std::size_t i, int d) { return std::int64_t(std::floor(x[3 * i + std::size_t(d)] * inv)); };
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t p, std::size_t q) {
    for (int d = 0; d < 3; ++d)
      if (cell(p, d) != cell(q, d)) return cell(p, d) < cell(q, d);
    return p < q;
  });
  std::vector<double> f(3 * n, 0.0);
  const double cut2 = pf.cutoff * pf.cutoff, eps2 = pf.softening * pf.softening;
  const auto q = [&](std::size_t i) { return charge != nullptr ? charge[i] : 0.0; };
  for (std::int64_t pass = 0; pass < 2; ++pass)
    for (std::size_t a = 0; a < n; ++a) {
      const std::size_t i = order[a];
      if ((cell(i, 0) & 1) != pass) continue;
      for (std::size_t b = a + 1; b < n; ++b) {
        const std::size_t j = order[b];
        if (std::abs(cell(j, 0) - cell(i, 0)) > 1 || std::abs(cell(j, 1) - cell(i, 1)) > 1 ||
            std::abs(cell(j, 2) - cell(i, 2)) > 1)
          continue;
        const double dx = x[3 * i] - x[3 * j], dy = x[3 * i + 1] - x[3 * j + 1],
                     dz = x[3 * i + 2] - x[3 * j + 2];
        const double r2 = dx * dx + dy * dy + dz * dz;
        if (!(r2 < cut2)) continue;
        const double s2 = r2 + eps2;
        const double coef = (pf.coulomb_K * q(i) * q(j) - pf.gravitational_G * mass[i] * mass[j]) /
                            (s2 * std::sqrt(s2));
        const double fx = coef * dx, fy = coef * dy, fz = coef * dz;
        f[3 * i] += fx;
        f[3 * i + 1] += fy;
        f[3 * i + 2] += fz;
        f[3 * j] -= fx;
        f[3 * j + 1] -= fy;
        f[3 * j + 2] -= fz;
      }
    }
  std::vector<double> want(3 * n, 0.25);  // the pair forces add to what is there
  for (std::size_t k = 0; k < 3 * n; ++k) want[k] += f[k] / mass[k / 3];
  return want;
}

// add_pair_forces() gives ordered_pair_accelerations()' bits at 1, 2, 3 and 4 threads, eight,
// four and one candidate at a time (as the CPU allows), with the neighbour runs read in place
// (AVX-512 or AVX2 CPUs) or copied first (3,000 particles: above the split threshold; cells of
// both signs, so both parities; plus a clump of 200 in a few cells, whose runs are longer than a
// block of eight).
TEST(SimForces, PairForcesEqualOrderedBruteForceBitForBit) {
  const std::size_t n = 3200;
  Rng rng(5);
  std::vector<double> x(3 * n), mass(n), charge(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d)
      x[3 * i + std::size_t(d)] = i < 3000 ? rng.uniform(-2.3, 2.9) : rng.uniform(0.1, 0.6);
    mass[i] = rng.uniform(0.5, 2.0);
    charge[i] = rng.uniform(-1.0, 1.0);
  }
  const PairForceDef pf{0.7, 1.3, 0.45, 1e-3};
  const std::vector<double> want = ordered_pair_accelerations(x, mass, charge.data(), pf);
  for (const int lanes : {8, 4, 1})
    for (const bool in_place : {true, false})
      for (int threads : {1, 2, 3, 4}) {
        detail::Dynamics dyn = pair_dynamics(mass, charge, pf, threads);
        dyn.pair_runs_in_place = in_place;
        dyn.pair_lanes = lanes;
        std::vector<double> got(3 * n, 0.25);
        dyn.add_pair_forces(x.data(), got.data());
        ASSERT_EQ(std::memcmp(got.data(), want.data(), got.size() * sizeof(double)), 0)
            << threads << " threads, runs in place " << in_place << ", lanes " << lanes;
      }
}

// Where every particle has one mass and one charge (bit for bit) the grid writes them instead
// of gathering them and gives every dense-grid pair one numerator: the same bits as the
// brute-force order, on a dense grid and a sparse one (two clouds 1 km apart), with and without
// charges, and where one particle's mass or charge is one ulp off (the first, the last, one in
// the middle), which must take each particle's own.
TEST(SimForces, PairForcesOfOneMassAndChargeEqualOrderedBruteForceBitForBit) {
  const std::size_t n = 2400;  // (above the split threshold at 2 threads)
  const PairForceDef pf{0.7, 1.3, 0.45, 1e-3};
  enum class Odd { none, first_mass, last_mass, middle_charge, first_charge, last_charge };
  for (const double apart : {0.0, 1000.0})
    for (const bool charged : {true, false})
      for (const Odd odd : {Odd::none, Odd::first_mass, Odd::last_mass, Odd::middle_charge,
                            Odd::first_charge, Odd::last_charge}) {
        if (!charged && odd >= Odd::middle_charge) continue;
        Rng rng(8);
        std::vector<double> x(3 * n), mass(n, 1.75), charge(n, -0.6);
        for (std::size_t i = 0; i < n; ++i) {
          for (int d = 0; d < 3; ++d) x[3 * i + std::size_t(d)] = rng.uniform(-2.0, 2.5);
          if (i % 2 == 1) x[3 * i] += apart;
        }
        const auto up = [](double& v) { v = std::nextafter(v, 10.0); };
        if (odd == Odd::first_mass) up(mass[0]);
        if (odd == Odd::last_mass) up(mass[n - 1]);
        if (odd == Odd::middle_charge) up(charge[n / 2]);
        if (odd == Odd::first_charge) up(charge[0]);
        if (odd == Odd::last_charge) up(charge[n - 1]);
        const std::vector<double> want =
            ordered_pair_accelerations(x, mass, charged ? charge.data() : nullptr, pf);
        for (int threads : {1, 2}) {
          detail::Dynamics dyn = pair_dynamics(mass, charge, pf, threads);
          if (!charged) dyn.charge = nullptr;
          std::vector<double> got(3 * n, 0.25);
          dyn.add_pair_forces(x.data(), got.data());
          if (apart == 0.0) {
            ASSERT_EQ(std::memcmp(got.data(), want.data(), got.size() * sizeof(double)), 0)
                << "charged " << charged << ", odd " << int(odd) << ", threads " << threads;
          } else {
            // The sparse grid gathers each particle's own sum (a different order): against the
            // brute force within rounding, and each particle's own mass must divide it.
            for (std::size_t k = 0; k < 3 * n; ++k)
              ASSERT_NEAR(got[k], want[k], 1e-9 * (1.0 + std::abs(want[k])))
                  << "charged " << charged << ", odd " << int(odd) << ", component " << k;
          }
        }
      }
}

// The same bits at 1, 2, 3 and 4 threads for a system well above the split threshold: 60,000
// particles at ~16 per m³ around the origin (cells of both signs) plus a tight clump of 600 in
// a few cells, so the thread shares are uneven in planes. (The state hash of a world step
// rarely sees a changed summation order: positions and velocities are stored as floats.)
TEST(SimForces, PairForcesBitIdenticalAtOneToFourThreads) {
  const std::size_t n = 60600;
  Rng rng(3);
  const double side = std::cbrt(60000.0 / 16.0);
  std::vector<double> x(3 * n), mass(n), charge(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d)
      x[3 * i + std::size_t(d)] = i < 60000 ? rng.uniform(-side / 2, side / 2) : rng.uniform(1.0, 1.6);
    mass[i] = rng.uniform(0.5, 2.0);
    charge[i] = rng.uniform(-1.0, 1.0);
  }
  const PairForceDef pf{0.3, 1.1, 0.5, 1e-3};
  std::vector<double> one;
  for (int threads : {1, 2, 3, 4}) {
    detail::Dynamics dyn = pair_dynamics(mass, charge, pf, threads);
    std::vector<double> got(3 * n, 0.5);
    dyn.add_pair_forces(x.data(), got.data());
    dyn.add_pair_forces(x.data(), got.data());  // scratch reused: the same again
    if (threads == 1)
      one = got;
    else
      ASSERT_EQ(std::memcmp(got.data(), one.data(), got.size() * sizeof(double)), 0) << threads;
  }
}

// Against the O(n²) sum (long double) for 2,000 particles with charges of both signs and
// softening, on a dense grid (one cloud), a sparse one (two clouds 1 km apart), and beyond
// the 32-bit cell coordinates' +-2^20 (0.5 m cells: 524 km): one cloud 10,000 km from the origin
// and two clouds 10,000 km apart (their cells more than the keys' 2^21 apart): every
// component within 1e-12 of the sum of its terms' magnitudes (the scale its rounding is
// relative to; the sum itself can cancel to near zero).
TEST(SimForces, PairForcesMatchBruteForce) {
  const std::size_t n = 2000;
  const PairForceDef pf{0.9, 1.7, 0.5, 2e-2};
  const std::pair<double, double> cases[] = {{0.0, 0.0}, {1000.0, 0.0}, {0.0, 1e7}, {1e7, 0.0}};
  for (const auto& [apart, shift] : cases) {
    Rng rng(11);
    std::vector<double> x(3 * n), mass(n), charge(n);
    for (std::size_t i = 0; i < n; ++i) {
      for (int d = 0; d < 3; ++d) x[3 * i + std::size_t(d)] = rng.uniform(-2.0, 2.5);
      x[3 * i + 1] += shift;
      if (i % 2 == 1) x[3 * i] += apart;
      mass[i] = rng.uniform(0.5, 2.0);
      charge[i] = rng.uniform(-1.0, 1.0);
    }
    detail::Dynamics dyn = pair_dynamics(mass, charge, pf);
    std::vector<double> got(3 * n, 0.0);
    dyn.add_pair_forces(x.data(), got.data());
    const double cut2 = pf.cutoff * pf.cutoff, eps2 = pf.softening * pf.softening;
    int interacting = 0;
    for (std::size_t i = 0; i < n; ++i) {
      long double sum[3] = {0, 0, 0}, mag[3] = {0, 0, 0};
      for (std::size_t j = 0; j < n; ++j) {
        long double d[3];
        for (int c = 0; c < 3; ++c) d[c] = (long double)x[3 * i + std::size_t(c)] - x[3 * j + std::size_t(c)];
        const long double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if (j == i || !(r2 < cut2)) continue;
        const long double s2 = r2 + eps2;
        const long double coef =
            ((long double)pf.coulomb_K * charge[i] * charge[j] - (long double)pf.gravitational_G * mass[i] * mass[j]) /
            (s2 * std::sqrt(s2));
        for (int c = 0; c < 3; ++c) {
          sum[c] += coef * d[c];
          mag[c] += std::abs(coef * d[c]);
        }
      }
      interacting += mag[0] > 0;
      for (int c = 0; c < 3; ++c)
        ASSERT_LE(std::abs((long double)got[3 * i + std::size_t(c)] - sum[c] / mass[i]), 1e-12L * mag[c] / mass[i])
            << "apart " << apart << " shift " << shift << " particle " << i << " component " << c;
    }
    EXPECT_GT(interacting, 1800) << apart << " " << shift;  // dense enough to test something
  }
}

std::uint64_t fnv(const void* data, std::size_t bytes, std::uint64_t h) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 0x100000001b3ULL;
  return h;
}

std::uint64_t busy_scene_hash(int threads) {
  World world(WorldDef{1.0 / 60, 42, 0.05, threads});
  ParticleSystemDef d = test::spawn_only_system("busy");
  d.integrator = Integrator::rk2;
  d.drag = 1e-4;
  d.emitter.rate = 2000;
  d.emitter.max_particles = 30000;
  d.charge = Distribution{1e-4, 5e-4};
  d.pair_forces = {1e-3, 50.0, 0.4, 1e-3};
  d.collide = false;
  const auto ps = world.add_particle_system(d);
  Rng rng(1);
  for (int i = 0; i < 20000; ++i)
    world.spawn_particle(ps, Vec3(rng.uniform(-8, 8), rng.uniform(-8, 8), rng.uniform(0, 8)),
                         Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)), 1e-3,
                         0.01, 1e9);
  ForceFieldDef noise;
  noise.kind = FieldKind::curl_noise;
  noise.amplitude = 1.5;
  noise.frequency = 0.7;
  noise.scroll = Vec3(0, 0, 0.5);
  world.add_force_field(noise);
  ForceFieldDef vortex;
  vortex.kind = FieldKind::vortex;
  vortex.shape = RegionShape::sphere;
  vortex.radius = 6;
  vortex.falloff = Falloff::quadratic;
  vortex.strength = 3;
  world.add_force_field(vortex);
  for (int i = 0; i < 3; ++i) world.advance(1.0 / 60);
  const ParticleView v = world.particles(ps);
  std::uint64_t h = 0xcbf29ce484222325ULL;
  h = fnv(v.position, 3 * v.count * sizeof(float), h);
  h = fnv(v.velocity, 3 * v.count * sizeof(float), h);
  h = fnv(v.id, v.count * sizeof(std::uint64_t), h);
  h = fnv(v.charge, v.count * sizeof(float), h);
  return fnv(&v.count, sizeof v.count, h);
}

// The whole step (pair forces split over the threads from 2,048 particles, the other stages from
// 16,384). Its float state seldom shows a double-precision summation order, which
// PairForcesBitIdenticalAtOneToFourThreads checks directly.
TEST(SimForces, StateIsBitIdenticalAtOneTwoAndFourThreads) {
  const std::uint64_t one = busy_scene_hash(1);
  EXPECT_EQ(one, busy_scene_hash(2));
  EXPECT_EQ(one, busy_scene_hash(4));
}

}  // namespace
}  // namespace simreel::sim
