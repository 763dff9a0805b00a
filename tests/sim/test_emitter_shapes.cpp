// Emitters, second part (Coutinho §3.8): parameter statistics (normal and uniform), the emitting
// shapes (quad grid, cube, sphere, box, mesh), bursts, moving emitters, inherited velocity,
// colour variation and size over lifetime.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <tuple>
#include <vector>

#include "sim_test_util.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

using test::position_of;
using test::velocity_of;

constexpr double kPi = std::numbers::pi;

/// Weightless, drag-free system releasing one burst of n particles at t = 0 and nothing else.
ParticleSystemDef burst_system(std::size_t n) {
  ParticleSystemDef def;
  def.name = "burst";
  def.gravity = Vec3::Zero();
  def.emitter.rate = 0.0;
  def.emitter.bursts = {Burst{0.0, n, 0.0, 1}};
  def.emitter.shape = EmitterShape::point;
  def.emitter.lifetime = {100.0, 0.0, 0.0};
  def.emitter.max_particles = 1'000'000;
  def.collide = false;
  return def;
}

/// Sample mean and standard deviation.
struct Stats {
  double mean = 0.0, sd = 0.0;
  std::size_t n = 0;
};
Stats stats(const std::vector<double>& x) {
  Stats s;
  s.n = x.size();
  for (double v : x) s.mean += v;
  s.mean /= double(s.n);
  for (double v : x) s.sd += (v - s.mean) * (v - s.mean);
  s.sd = std::sqrt(s.sd / double(s.n - 1));
  return s;
}

/// The sample mean is within 5 standard errors of mu, and the sample deviation within 5 of its
/// own standard errors (sigma / sqrt(2 n) for a normal sample) of sigma.
void expect_normal(const std::vector<double>& x, double mu, double sigma, const char* what) {
  const Stats s = stats(x);
  const double n = double(s.n);
  EXPECT_NEAR(s.mean, mu, 5.0 * sigma / std::sqrt(n)) << what;
  EXPECT_NEAR(s.sd, sigma, 5.0 * sigma / std::sqrt(2.0 * n)) << what;
}

TEST(SimEmitterStats, NormalParametersHaveTheirMeanAndDeviation) {
  constexpr std::size_t kN = 20000;
  World world(WorldDef{1.0 / 60, 21, 0.05});
  ParticleSystemDef def = burst_system(kN);
  def.emitter.start_speed = {5.0, 0.7, 0.0};
  def.emitter.mass = {2e-3, 3e-4, 1e-12};
  def.emitter.radius = {0.02, 0.003, 1e-6};
  def.emitter.lifetime = {10.0, 1.5, 0.0};
  def.emitter.spread_deg = {30.0, 4.0, 0.0, 180.0};
  const auto ps = world.add_particle_system(def);
  world.advance(1.0 / 60);
  const ParticleView v = world.particles(ps);
  ASSERT_EQ(v.count, kN);
  std::vector<double> speed, mass, radius, life, theta;
  for (std::size_t i = 0; i < v.count; ++i) {
    const Vec3 u = velocity_of(v, i);
    speed.push_back(u.norm());
    theta.push_back(std::acos(std::clamp(u.normalized().z(), -1.0, 1.0)) * 180.0 / kPi);
    mass.push_back(v.mass[i]);
    radius.push_back(v.radius[i]);
    life.push_back(v.lifetime[i]);
  }
  // Every mean is >= 6 deviations from its clamp, so the clamps do not bias these moments.
  expect_normal(speed, 5.0, 0.7, "start_speed");
  expect_normal(mass, 2e-3, 3e-4, "mass");
  expect_normal(radius, 0.02, 0.003, "radius");
  expect_normal(life, 10.0, 1.5, "lifetime");
  expect_normal(theta, 30.0, 4.0, "spread_deg");
}

TEST(SimEmitterStats, UniformMinMaxHasFlatMomentsAndStaysInRange) {
  constexpr std::size_t kN = 20000;
  World world(WorldDef{1.0 / 60, 22, 0.05});
  ParticleSystemDef def = burst_system(kN);
  Distribution u;
  u.uniform = true;
  u.min = 2.0;
  u.max = 6.0;
  def.emitter.start_speed = u;
  u.min = 0.01;
  u.max = 0.03;
  def.emitter.radius = u;
  def.emitter.radius.mean = 0.02;  // the engine requires mean > 0; ignored by a uniform draw
  const auto ps = world.add_particle_system(def);
  world.advance(1.0 / 60);
  const ParticleView v = world.particles(ps);
  ASSERT_EQ(v.count, kN);
  for (const auto& [lo, hi, which] : {std::tuple{2.0, 6.0, 0}, std::tuple{0.01, 0.03, 1}}) {
    std::vector<double> x;
    for (std::size_t i = 0; i < v.count; ++i) {
      const double xi = which == 0 ? velocity_of(v, i).norm() : double(v.radius[i]);
      ASSERT_GE(xi, lo - 1e-6 * hi);
      ASSERT_LE(xi, hi + 1e-6 * hi);
      x.push_back(xi);
    }
    const Stats s = stats(x);
    const double var = (hi - lo) * (hi - lo) / 12.0;
    EXPECT_NEAR(s.mean, 0.5 * (lo + hi), 5.0 * std::sqrt(var / kN));
    // Var of the sample variance of U(a, b): (4/5) var^2 / n (excess kurtosis -6/5).
    EXPECT_NEAR(s.sd * s.sd, var, 5.0 * std::sqrt(0.8 / kN) * var);
  }
}

TEST(SimEmitterShapes, QuadAndCubeReleasesNeverOverlapWithMixedSizes) {
  // The grid is sized from the largest diameter of each release (eq. 3.100 with d_max).
  for (EmitterShape shape : {EmitterShape::quad, EmitterShape::cube}) {
    World world(WorldDef{1.0 / 60, 9, 0.05});
    ParticleSystemDef def = burst_system(150);
    def.emitter.shape = shape;
    def.emitter.quad_size = {1.2, 0.9};
    def.emitter.cube_size = 1.1;
    def.emitter.radius = {0.02, 0.01, 0.005, 0.03};
    def.emitter.transform.translation = Vec3(1, 2, 3);
    def.emitter.start_speed = {0.0, 0.0, 0.0};
    def.emitter.bursts = {Burst{0.25, 150, 0.5, 3}};  // three separate releases
    const auto ps = world.add_particle_system(def);
    for (int release = 0; release < 3; ++release) {
      world.advance(0.5);
      const ParticleView v = world.particles(ps);
      ASSERT_EQ(v.count, 150u * std::size_t(release + 1));
      const std::size_t first = 150u * std::size_t(release);
      double r_max = 0.0;
      for (std::size_t i = first; i < v.count; ++i) {
        const Vec3 p = position_of(v, i) - Vec3(1, 2, 3);
        r_max = std::max(r_max, double(v.radius[i]));
        if (shape == EmitterShape::cube) {
          ASSERT_NEAR(p.z(), 0.55, 1e-5);  // the cube's top face
          ASSERT_LE(std::abs(p.x()), 0.55 + 1e-5);
          ASSERT_LE(std::abs(p.y()), 0.55 + 1e-5);
        } else {
          ASSERT_NEAR(p.z(), 0.0, 1e-5);
          ASSERT_LE(std::abs(p.x()), 0.6 + 1e-5);
          ASSERT_LE(std::abs(p.y()), 0.45 + 1e-5);
        }
        for (std::size_t j = first; j < i; ++j)
          ASSERT_GE((position_of(v, i) - position_of(v, j)).norm(),
                    double(v.radius[i]) + double(v.radius[j]) - 1e-5)
              << "release " << release << ": " << i << " " << j;
      }
      EXPECT_GT(r_max, 0.025);  // the mixed sizes are exercised
    }
  }
}

TEST(SimEmitterShapes, SphereEmitsRadiallyFromItsSurface) {
  constexpr std::size_t kN = 20000;
  World world(WorldDef{1.0 / 600, 3, 0.05});
  ParticleSystemDef def = burst_system(kN);
  def.emitter.shape = EmitterShape::sphere;
  def.emitter.sphere_radius = 0.5;
  def.emitter.transform.translation = Vec3(0, 0, 2);
  def.emitter.start_speed = {4.0, 0.0, 0.0};
  const auto ps = world.add_particle_system(def);
  world.advance(1.0 / 600);  // one step: each particle moved 4 m/s * (1/600) s radially
  const ParticleView v = world.particles(ps);
  ASSERT_EQ(v.count, kN);
  Vec3 mean_normal = Vec3::Zero();
  int upper = 0;
  for (std::size_t i = 0; i < v.count; ++i) {
    const Vec3 d = position_of(v, i) - Vec3(0, 0, 2);
    ASSERT_NEAR(d.norm(), 0.5 + 4.0 / 600, 2e-5);
    ASSERT_GT(velocity_of(v, i).normalized().dot(d.normalized()), 1.0 - 1e-6);
    mean_normal += d.normalized();
    upper += d.z() > 0.0;
  }
  // Uniform over the area: each normal component has mean 0 and variance 1/3.
  EXPECT_LT((mean_normal / double(kN)).norm(), 5.0 * std::sqrt(1.0 / 3.0 / kN));
  EXPECT_NEAR(double(upper) / kN, 0.5, 5.0 * 0.5 / std::sqrt(double(kN)));

  // With a spread, directions leave the radial direction by the spread angle.
  World w2(WorldDef{1.0 / 600, 4, 0.05});
  def.emitter.spread_deg = {20.0, 0.0, 0.0, 180.0};
  def.emitter.start_speed = {1e-3, 0.0, 0.0};
  const auto ps2 = w2.add_particle_system(def);
  w2.advance(1.0 / 600);
  const ParticleView v2 = w2.particles(ps2);
  for (std::size_t i = 0; i < v2.count; ++i) {
    const Vec3 d = (position_of(v2, i) - Vec3(0, 0, 2)).normalized();
    ASSERT_NEAR(velocity_of(v2, i).normalized().dot(d), std::cos(20.0 * kPi / 180.0), 1e-3);
  }
}

TEST(SimEmitterShapes, BoxFillsItsVolumeUniformly) {
  constexpr std::size_t kN = 20000;
  World world(WorldDef{1.0 / 60, 5, 0.05});
  ParticleSystemDef def = burst_system(kN);
  def.emitter.shape = EmitterShape::box;
  def.emitter.box_size = {2.0, 1.0, 0.5};
  def.emitter.transform.translation = Vec3(-1, 0, 1);
  def.emitter.start_speed = {0.0, 0.0, 0.0};
  const auto ps = world.add_particle_system(def);
  world.advance(1.0 / 60);
  const ParticleView v = world.particles(ps);
  ASSERT_EQ(v.count, kN);
  for (int c = 0; c < 3; ++c) {
    const double size = def.emitter.box_size[std::size_t(c)];
    std::vector<double> x;
    for (std::size_t i = 0; i < v.count; ++i) {
      const double xi = position_of(v, i)[c] - def.emitter.transform.translation[c];
      ASSERT_LE(std::abs(xi), 0.5 * size + 1e-6);
      x.push_back(xi);
    }
    const Stats s = stats(x);
    const double var = size * size / 12.0;
    EXPECT_NEAR(s.mean, 0.0, 5.0 * std::sqrt(var / kN)) << c;
    EXPECT_NEAR(s.sd * s.sd, var, 5.0 * std::sqrt(0.8 / kN) * var) << c;
  }
}

TEST(SimEmitterShapes, MeshSurfaceIsAreaWeightedWithFaceNormals) {
  constexpr std::size_t kN = 20000;
  World world(WorldDef{1.0 / 6000, 6, 0.05});
  ParticleSystemDef def = burst_system(kN);
  def.emitter.shape = EmitterShape::mesh;
  // Triangle A (area 1.5, normal +z) and triangle B (area 0.5, wound clockwise seen from +z, so
  // its normal is -z): counts should be 3 : 1.
  def.emitter.mesh_positions = {0, 0, 0, 3, 0, 0, 0, 1, 0, 10, 0, 0, 11, 0, 0, 10, 1, 0};
  def.emitter.mesh_triangles = {0, 1, 2, 3, 5, 4};
  def.emitter.start_speed = {1.0, 0.0, 0.0};
  const auto ps = world.add_particle_system(def);
  world.advance(1.0 / 6000);
  const ParticleView v = world.particles(ps);
  ASSERT_EQ(v.count, kN);
  std::size_t on_a = 0;
  for (std::size_t i = 0; i < v.count; ++i) {
    const Vec3 p = position_of(v, i);
    const Vec3 u = velocity_of(v, i);
    if (p.x() < 5.0) {
      ++on_a;
      ASSERT_NEAR(u.z(), 1.0, 1e-6);
      ASSERT_NEAR(p.z(), 1.0 / 6000, 1e-6);
      ASSERT_LE(p.x() / 3.0 + p.y(), 1.0 + 1e-6);  // inside the triangle
      ASSERT_GE(std::min(p.x(), p.y()), -1e-6);
    } else {
      ASSERT_NEAR(u.z(), -1.0, 1e-6);
      ASSERT_NEAR(p.z(), -1.0 / 6000, 1e-6);
      ASSERT_LE((p.x() - 10.0) + p.y(), 1.0 + 1e-6);
      ASSERT_GE(std::min(p.x() - 10.0, p.y()), -1e-6);
    }
  }
  // Binomial(n, 3/4): 5 standard deviations of the count.
  EXPECT_NEAR(double(on_a), 0.75 * kN, 5.0 * std::sqrt(kN * 0.75 * 0.25));
}

TEST(SimEmitterSchedule, RateAndBurstCountsDoNotDependOnFps) {
  // Bursts at 0.1 + 0.25 k forever and 3 bursts of 11 every 0.5 s from 0.3; plus 37.3/s.
  auto bursts_until = [](double t) {
    std::size_t n = 0;
    for (int k = 0; k < 100; ++k) n += 0.1 + 0.25 * k <= t + 1e-9 ? 7 : 0;
    for (int k = 0; k < 3; ++k) n += 0.3 + 0.5 * k <= t + 1e-9 ? 11 : 0;
    return n;
  };
  for (int fps : {24, 30, 60, 144}) {
    World world(WorldDef{1.0 / 240, 3, 0.05});
    ParticleSystemDef def = burst_system(0);
    def.emitter.rate = 37.3;
    def.emitter.bursts = {Burst{0.1, 7, 0.25, 0}, Burst{0.3, 11, 0.5, 3}};
    const auto ps = world.add_particle_system(def);
    for (int f = 1; f <= 2 * fps; ++f) {
      world.advance(1.0 / fps);
      const double t = double(f) / fps;
      const double rate_part = double(world.emitted_count(ps)) - double(bursts_until(t));
      ASSERT_LE(std::abs(rate_part - std::floor(37.3 * t)), 1.0) << "fps " << fps << " t " << t;
    }
    EXPECT_EQ(world.emitted_count(ps), 74u + 8u * 7u + 3u * 11u) << "fps " << fps;
  }
}

TEST(SimEmitterPath, FastMovingEmitterLeavesEvenlySpacedParticles) {
  // 50 m/s, 1000 particles/s, steps of 1/60 s: ~17 births per step, each at its own point on
  // the path, so consecutive particles are speed / rate = 5 cm apart — no gap per step.
  for (EmitterShape shape : {EmitterShape::point, EmitterShape::quad}) {
    World world(WorldDef{1.0 / 60, 0, 0.05});
    ParticleSystemDef def = burst_system(0);
    def.emitter.bursts.clear();
    def.emitter.shape = shape;
    def.emitter.quad_size = {0.01, 0.01};
    def.emitter.rate = 1000.0;
    def.emitter.start_speed = {0.0, 0.0, 0.0};
    def.emitter.path.smooth = false;
    def.emitter.path.keys = {Keyframe{0.0, Vec3(0, 0, 0)}, Keyframe{2.0, Vec3(100, 0, 0)}};
    const auto ps = world.add_particle_system(def);
    for (int f = 0; f < 30; ++f) world.advance(1.0 / 60);
    const ParticleView v = world.particles(ps);
    ASSERT_EQ(v.count, 500u);
    double max_gap = 0.0;
    for (std::size_t i = 1; i < v.count; ++i) {
      const double gap = v.position[3 * i] - v.position[3 * (i - 1)];
      max_gap = std::max(max_gap, gap);
      if (shape == EmitterShape::point) {
        ASSERT_NEAR(gap, 0.05, 1e-4) << i;
      }
    }
    EXPECT_LE(max_gap, 0.05 + 0.01 + 1e-4);  // + the quad's width for the quad
  }
}

TEST(SimEmitterPath, NewbornsInheritAFractionOfTheEmitterVelocity) {
  constexpr std::size_t kN = 20000;
  World world(WorldDef{1.0 / 240, 7, 0.05});
  ParticleSystemDef def = burst_system(0);
  def.emitter.bursts.clear();
  def.emitter.rate = 40000.0;
  def.emitter.start_speed = {2.0, 0.3, 0.0};
  def.emitter.spread_deg = {0.0, 25.0, 0.0, 180.0};
  def.emitter.inherit_velocity = 0.5;
  def.emitter.path.smooth = false;
  def.emitter.path.keys = {Keyframe{0.0, Vec3(0, 0, 0)}, Keyframe{10.0, Vec3(60, -30, 0)}};
  const auto ps = world.add_particle_system(def);
  world.advance(0.5);
  const ParticleView v = world.particles(ps);
  ASSERT_EQ(v.count, kN);
  Vec3 mean = Vec3::Zero();
  for (std::size_t i = 0; i < v.count; ++i) mean += velocity_of(v, i);
  mean /= double(kN);
  // Emitter velocity (6, -3, 0) m/s; the spread is symmetric about +z, so the emission part
  // averages to 0 in x and y (each component's deviation < 2.3 m/s).
  EXPECT_NEAR(mean.x(), 3.0, 5.0 * 2.3 / std::sqrt(double(kN)));
  EXPECT_NEAR(mean.y(), -1.5, 5.0 * 2.3 / std::sqrt(double(kN)));
  EXPECT_GT(mean.z(), 1.5);
}

TEST(SimEmitterCurves, SizeOverLifetimeScalesTheDrawnRadius) {
  World world(WorldDef{1.0 / 100, 2, 0.05});
  ParticleSystemDef def = burst_system(4000);
  def.emitter.lifetime = {2.0, 0.0, 0.0};
  def.emitter.radius = {0.02, 0.004, 0.005};
  def.emitter.size_over_lifetime = {SizeKey{0.0, 1.0}, SizeKey{0.5, 3.0}, SizeKey{1.0, 0.0}};
  const auto ps = world.add_particle_system(def);
  world.advance(0.01);
  // Age 0.01 s, u = 0.005: the curve is at 1 + (3 - 1) (0.005 / 0.5) = 1.02.
  std::vector<float> base(world.particles(ps).radius, world.particles(ps).radius + 4000);
  for (std::size_t i = 0; i < base.size(); ++i) base[i] /= 1.02f;
  for (int f = 1; f < 100; ++f) world.advance(0.01);  // t = 1 s: half of the 2 s lifetime
  const ParticleView v = world.particles(ps);
  ASSERT_EQ(v.count, 4000u);
  for (std::size_t i = 0; i < v.count; ++i) {
    ASSERT_NEAR(v.age[i], 1.0, 1e-5);
    ASSERT_NEAR(v.radius[i], 3.0 * base[i], 2e-5 * base[i]) << i;
  }
  for (int f = 0; f < 50; ++f) world.advance(0.01);  // u = 0.75: halfway 3 -> 0
  const ParticleView w = world.particles(ps);
  for (std::size_t i = 0; i < w.count; ++i) ASSERT_NEAR(w.radius[i], 1.5 * base[i], 2e-4 * base[i]);
}

TEST(SimEmitterCurves, ColorDeviationScalesBrightnessForLife) {
  constexpr std::size_t kN = 20000;
  World world(WorldDef{1.0 / 60, 12, 0.05});
  ParticleSystemDef def = burst_system(kN);
  def.emitter.lifetime = {2.0, 0.0, 0.0};
  def.emitter.color_deviation = 0.1;
  def.emitter.color_over_lifetime = {ColorKey{0.0, {0.5f, 0.4f, 0.2f, 1.f}},
                                     ColorKey{1.0, {0.25f, 0.2f, 0.1f, 0.f}}};
  const auto ps = world.add_particle_system(def);
  world.advance(1.0 / 60);
  const ParticleView v = world.particles(ps);
  std::vector<double> factor;
  for (std::size_t i = 0; i < v.count; ++i) factor.push_back(v.color[4 * i] / (0.5 * (1.0 - 0.5 * v.age[i] / 2.0)));
  expect_normal(factor, 1.0, 0.1, "brightness");
  std::vector<float> first(factor.begin(), factor.end());
  for (int f = 0; f < 60; ++f) world.advance(1.0 / 60);  // t ~ 1 s: the gradient moved on
  const ParticleView w = world.particles(ps);
  for (std::size_t i = 0; i < w.count; ++i) {
    const double expected = 0.5 * (1.0 - 0.5 * w.age[i] / 2.0) * first[i];
    ASSERT_NEAR(w.color[4 * i], expected, 1e-5) << i;          // the same factor, not compounded
    ASSERT_NEAR(w.color[4 * i + 1] / w.color[4 * i], 0.8, 1e-5);  // hue kept
    ASSERT_NEAR(w.color[4 * i + 3], 1.0 - w.age[i] / 2.0, 1e-5);  // alpha untouched
  }
}

}  // namespace
}  // namespace simreel::sim
