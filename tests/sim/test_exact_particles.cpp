// Issue 15, "physics that must become exact", against closed forms at several step sizes:
// bounce apexes e^{2n} H for every integrator (the response reflects the velocity at the time of
// impact and the forces act over the rest of the step, Coutinho §3.6.1), ballistic arcs exact
// with the default semi-implicit Euler (App. B), and sliding on every collider kind at several
// orientations moving by the integral of its velocity (no stall re-hitting the face it slides
// on, §3.4).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "sim_test_util.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

using test::position_of;
using test::velocity_of;

constexpr double kG = 9.81;
constexpr double kR = 0.01;  // particle radius (m)

ParticleSystemDef probe(Integrator in) {
  ParticleSystemDef def = test::spawn_only_system();
  def.integrator = in;
  def.gravity = Vec3(0, 0, -kG);
  return def;
}

/// Centre heights above the plane of the first `count` apexes of a ball dropped from H onto a
/// plane with restitution e, stepping h (one advance per internal step).
std::vector<double> apexes(Integrator in, double h, double H, double e, int count) {
  World world(WorldDef{h, 0, 0.05});
  PlaneDef plane;
  plane.material = Material(e, 0.0);
  world.add_plane(plane);
  const auto ps = world.add_particle_system(probe(in));
  world.spawn_particle(ps, Vec3(0, 0, kR + H), Vec3::Zero(), 0.01, kR, 100);
  std::vector<double> out;
  // An apex: the highest point of a flight between two bounces (v_z from > 0 to <= 0).
  double top = 0.0;
  bool up = false;
  for (int k = 0; k < int(6.0 / h) && int(out.size()) < count; ++k) {
    world.advance(h);
    const ParticleView v = world.particles(ps);
    const double z = position_of(v, 0).z(), vz = velocity_of(v, 0).z();
    if (vz > 0.0) {
      top = up ? std::max(top, z) : z;
      up = true;
    } else if (up) {
      out.push_back(std::max(top, z) - kR);
      up = false;
    }
  }
  return out;
}

TEST(ExactBounce, ApexesFollowRestitutionSquaredForEveryIntegrator) {
  // Dropped from H = 1 m, e = 0.6: apex n at e^{2n} H (0.36, 0.1296, 0.0467 m) within 0.5% at
  // the default step. The sampled maximum lies within g h² / 8 (2e-5 m) of the true apex.
  const double H = 1.0, e = 0.6;
  for (const Integrator in : {Integrator::semi_implicit_euler, Integrator::rk4, Integrator::rk2,
                              Integrator::implicit_euler, Integrator::adaptive}) {
    const std::vector<double> a = apexes(in, 1.0 / 240, H, e, 3);
    ASSERT_EQ(a.size(), 3u) << int(in);
    for (int n = 1; n <= 3; ++n) {
      const double expected = std::pow(e, 2 * n) * H;
      EXPECT_NEAR(a[std::size_t(n - 1)] / expected, 1.0, 5e-3) << "integrator " << int(in)
                                                                << " bounce " << n;
    }
  }
}

TEST(ExactBounce, ExplicitEulerIsWithinItsOwnFirstOrderError) {
  // Explicit Euler gains energy in free flight (x += h v0 leaves it ~g h t / 2 high): its
  // apexes converge to e^{2n} H at first order — within 0.5% at h = 1/5000 s.
  const std::vector<double> a = apexes(Integrator::explicit_euler, 1.0 / 5000, 1.0, 0.6, 2);
  ASSERT_EQ(a.size(), 2u);
  EXPECT_NEAR(a[0] / 0.36, 1.0, 5e-3);
  EXPECT_NEAR(a[1] / 0.1296, 1.0, 5e-3);
}

TEST(ExactBounce, FrameRateDoesNotChangeTheBounce) {
  // The same drop advanced per frame at 24, 25, 60 and 100 fps (internal steps 1/240, 1/250,
  // 1/240, 1/200 s): the energy after the first bounce, z + v_z² / 2g, is e² H in every case.
  for (const double fps : {24.0, 25.0, 60.0, 100.0}) {
    for (const Integrator in : {Integrator::semi_implicit_euler, Integrator::rk4}) {
      World world;
      PlaneDef plane;
      plane.material = Material(0.6, 0.0);
      world.add_plane(plane);
      const auto ps = world.add_particle_system(probe(in));
      world.spawn_particle(ps, Vec3(0, 0, kR + 1.0), Vec3::Zero(), 0.01, kR, 100);
      const double t_bounce = std::sqrt(2.0 / kG);  // 0.4515 s; back down 0.542 s later
      while (world.time() < t_bounce + 0.2) world.advance(1.0 / fps);
      const ParticleView v = world.particles(ps);
      const double apex = position_of(v, 0).z() - kR + std::pow(velocity_of(v, 0).z(), 2) / (2 * kG);
      EXPECT_NEAR(apex / 0.36, 1.0, 2e-3) << "fps " << fps << " integrator " << int(in);
    }
  }
}

TEST(ExactBallistics, DefaultIntegratorPeaksAtTheClosedFormApex) {
  // A fountain jet straight up at 5 m/s: apex v0² / 2g = 1.27421 m, to 0.05%, at 1/60, 1/240
  // and 1/1000 s (the sampled maximum is within g h² / 8 of it: < 0.03% at 1/60 s).
  for (const double h : {1.0 / 60, 1.0 / 240, 1.0 / 1000}) {
    World world(WorldDef{h, 0, 0.05});
    const auto ps = world.add_particle_system(probe(Integrator::semi_implicit_euler));
    world.spawn_particle(ps, Vec3::Zero(), Vec3(1, 0, 5), 0.01, kR, 100);
    double top = 0.0;
    for (int k = 0; k < int(1.0 / h); ++k) {
      world.advance(h);
      top = std::max(top, double(position_of(world.particles(ps), 0).z()));
    }
    EXPECT_NEAR(top / (25.0 / (2 * kG)), 1.0, 5e-4) << h;
    // Exact at every sample: z(t) = 5 t - g t² / 2 at t = 1 s.
    EXPECT_NEAR(position_of(world.particles(ps), 0).z(), 5.0 - 0.5 * kG, 1e-5) << h;
  }
}

TEST(ExactBallistics, StaysStableAndKeepsTheTerminalVelocityInHeavyDrag) {
  // h k_d / m = 10 (far past explicit drag's limit 2): no oscillation, the velocity settles at
  // m g / k_d and the particle then moves by exactly that speed times the time.
  const double h = 1.0 / 60, m = 0.01, kd = 10.0 * m / h;
  World world(WorldDef{h, 0, 0.05});
  ParticleSystemDef def = probe(Integrator::semi_implicit_euler);
  def.drag = kd;
  const auto ps = world.add_particle_system(def);
  world.spawn_particle(ps, Vec3(0, 0, 0), Vec3(0, 0, 30), m, kR, 100);  // near 0: float ulps small
  world.advance(1.0);
  const double vt = m * kG / kd;
  const double z1 = position_of(world.particles(ps), 0).z();
  EXPECT_NEAR(velocity_of(world.particles(ps), 0).z(), -vt, 1e-6);
  world.advance(1.0);
  EXPECT_NEAR(position_of(world.particles(ps), 0).z() - z1, -vt, 1e-5);
}

// -- Sliding: displacement = integral of velocity on every collider kind ----------------------

/// Steps a probe for T seconds at step h and returns |x(T) - x(0) - ∫v dt| / |x(T) - x(0)| with
/// the integral by the trapezoid rule over the steps (exact for a constant acceleration), and the
/// distance travelled.
std::pair<double, double> slide_error(World& world, ParticleSystemHandle ps, double h, double T) {
  const Vec3 x0 = position_of(world.particles(ps), 0);
  Vec3 v_prev = velocity_of(world.particles(ps), 0), integral = Vec3::Zero();
  for (int k = 0; k < int(std::lround(T / h)); ++k) {
    world.advance(h);
    const Vec3 v = velocity_of(world.particles(ps), 0);
    integral += 0.5 * h * (v_prev + v);
    v_prev = v;
  }
  EXPECT_EQ(world.particles(ps).count, 1u);
  const Vec3 d = position_of(world.particles(ps), 0) - x0;
  return {(d - integral).norm() / d.norm(), d.norm()};
}

/// A rotation taking +z onto the unit normal n.
Quat onto(const Vec3& n) { return Quat::FromTwoVectors(Vec3::UnitZ(), n); }

TEST(ExactSliding, DisplacementIsTheIntegralOfVelocityOnEveryColliderKind) {
  const double mu = 0.1, T = 0.5;
  // Slopes of 30 and 45 degrees turned about y and about a skew axis.
  const std::vector<Vec3> normals = {
      Vec3(std::sin(std::numbers::pi / 6), 0, std::cos(std::numbers::pi / 6)),
      Vec3(0.5, 0.5, std::sqrt(0.5)),
      Vec3(-0.3, 0.2, 0.9).normalized()};
  enum Kind { plane, box, mesh, sphere, cylinder, capsule };
  for (const double h : {1.0 / 240, 1.0 / 1000}) {
    for (const Kind kind : {plane, box, mesh, sphere, cylinder, capsule}) {
      for (const Vec3& n : normals) {
        World world(WorldDef{h, 0, 0.05});
        BodyDef b;
        Vec3 start = (kR + 0.0) * n;  // on the surface through the origin with normal n
        switch (kind) {
          case plane: b.shapes = {ShapeDef::plane(n)}; break;
          case box:
            b.pose.rotation = onto(n);
            b.pose.translation = -0.5 * n;
            b.shapes = {ShapeDef::box(Vec3(3, 3, 0.5))};
            break;
          case mesh: {
            b.pose.rotation = onto(n);
            ShapeDef s;
            s.type = ShapeType::mesh;
            s.vertices = {Vec3(-3, -3, 0), Vec3(3, -3, 0), Vec3(3, 3, 0), Vec3(-3, 3, 0)};
            s.triangles = {{0, 1, 2}, {0, 2, 3}};
            b.shapes = {s};
            break;
          }
          case sphere:  // on a sphere of 5 m whose surface point under the probe has normal n
            b.pose.translation = -5.0 * n;
            b.shapes = {ShapeDef::sphere(5.0)};
            break;
          case cylinder:
          case capsule: {
            // The axis along the steepest descent of the slope with normal n: the probe on the
            // round top slides down along it.
            const Vec3 down = (Vec3(0, 0, -1) - Vec3(0, 0, -1).dot(n) * n).normalized();
            b.pose.rotation = onto(down);
            b.pose.translation = -0.3 * n;
            b.shapes = {kind == cylinder ? ShapeDef::cylinder(0.3, 4.0) : ShapeDef::capsule(0.3, 4.0)};
            break;
          }
        }
        b.shapes[0].material = Material(0.0, mu);
        world.add_body(b);
        const auto ps = world.add_particle_system(probe(Integrator::semi_implicit_euler));
        world.spawn_particle(ps, start, Vec3::Zero(), 0.01, kR, 100);
        const auto [err, dist] = slide_error(world, ps, h, T);
        EXPECT_LT(err, 5e-3) << "kind " << kind << " n " << n.transpose() << " h " << h;
        if (kind != sphere) {
          // A straight incline: s(T) = g (sin θ - mu cos θ) T² / 2.
          const double c = n.z(), s = std::sqrt(1.0 - c * c);
          const double closed = 0.5 * kG * (s - mu * c) * T * T;
          EXPECT_NEAR(dist / closed, 1.0, 5e-3) << "kind " << kind << " n " << n.transpose()
                                                << " h " << h;
        } else {
          EXPECT_GT(dist, 0.1);
        }
      }
    }
  }
}

}  // namespace
}  // namespace simreel::sim

namespace simreel::sim {
namespace {

// -- Divergence (issue 15): a blow-up stops the run like NaN does ------------------------------

TEST(Divergence, ExplicitEulerOnAStiffRopeStopsNamingSystemStepAndTime) {
  // A 10-link rope of 10 g beads and 1e5 N/m springs, stretched 10%: h ω = (1/240) sqrt(1e5 /
  // 0.01) = 13, far past explicit Euler's stability. Before, it reached 1e26 m and went on.
  World world;
  ParticleSystemDef def = test::spawn_only_system("rope");
  def.integrator = Integrator::explicit_euler;
  for (int k = 0; k < 10; ++k) {
    InitialParticle p;
    p.position = Vec3(0.11 * k, 0, 1);
    p.mass = 0.01;
    def.initial_particles.push_back(p);
  }
  for (std::uint64_t k = 0; k + 1 < 10; ++k)
    def.springs.push_back(SpringDef{k, k + 1, 1e5, 0.0, 0.1});
  world.add_particle_system(def);
  try {
    for (int f = 0; f < 120; ++f) world.advance(1.0 / 60);
    FAIL() << "no NonFiniteState";
  } catch (const NonFiniteState& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("'rope'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("diverged"), std::string::npos) << msg;
    EXPECT_NE(msg.find("max_speed"), std::string::npos) << msg;
    EXPECT_NE(msg.find("internal step"), std::string::npos) << msg;
    EXPECT_LT(world.time(), 1.0) << msg;
  }
}

TEST(Divergence, BoundsAreConfigurableAndAFastButSaneParticleRuns) {
  // A 2 km/s bullet is fine under the default 1e4 m/s; with max_speed = 1000 it stops.
  for (const double vmax : {1e4, 1e3}) {
    WorldDef wd;
    wd.max_speed = vmax;
    World world(wd);
    const auto ps = world.add_particle_system(test::spawn_only_system("bullet"));
    world.spawn_particle(ps, Vec3::Zero(), Vec3(2000, 0, 0), 0.01, 0.01, 100);
    bool stopped = false;
    try {
      world.advance(0.1);
    } catch (const NonFiniteState&) {
      stopped = true;
    }
    EXPECT_EQ(stopped, vmax < 2000) << vmax;
  }
}

}  // namespace
}  // namespace simreel::sim
