// Two-way coupling of dynamic bodies (the rigid-body issue, Coutinho §3.7): particles, cloth and
// force fields push bodies. Checked against conservation and closed forms: a jet's momentum
// change equals the box's within 1%, an off-centre jet's angular impulse is r × J, absorbed rain
// hands over all its momentum, a body in wind or a uniform force accelerates at F/m, a blast
// pushes bodies radially with the 1/d² share, cloth falling on a floating box conserves the
// total momentum, and the same state comes out at 1, 2 and 4 threads.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "sim_test_util.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

WorldDef def_with_step(double h, int threads = 1) {
  WorldDef d;
  d.max_step = h;
  d.threads = threads;
  return d;
}

/// A floating (no gravity) dynamic box of half extents e at p.
BodyDef floating_box(const Vec3& e, const Vec3& p, double mass, const Material& m) {
  BodyDef b;
  b.type = BodyType::dynamic;
  b.pose.translation = p;
  b.mass = mass;
  b.gravity = Vec3::Zero();
  ShapeDef s = ShapeDef::box(e);
  s.material = m;
  b.shapes.push_back(s);
  return b;
}

/// A particle system with no emission, no gravity, no drag: particles come from spawn_particle.
ParticleSystemDef quiet_system() {
  ParticleSystemDef p;
  p.name = "jet";
  p.emitter.rate = 0.0;
  p.emitter.max_particles = 100000;
  p.gravity = Vec3::Zero();
  p.drag = 0.0;
  return p;
}

/// Σ m v of a system's live particles (kg m/s).
Vec3 particle_momentum(const World& w, ParticleSystemHandle h) {
  const ParticleView v = w.particles(h);
  Vec3 p = Vec3::Zero();
  for (std::size_t i = 0; i < v.count; ++i)
    p += double(v.mass[i]) * Vec3(v.velocity[3 * i], v.velocity[3 * i + 1], v.velocity[3 * i + 2]);
  return p;
}

/// A jet along +x at height y0 on the box's face: `frames` frames of `per_frame` particles each
/// (mass m, speed u), spread over a 2 cm square around (x0, y0, 0).
struct Jet {
  double m = 2e-3, u = 8.0, x0 = -0.8, y0 = 0.0;
  int frames = 20, per_frame = 16;
};

/// Runs the jet against a floating box at the origin; returns {box momentum, particles' momentum
/// change, box angular momentum}.
struct JetResult {
  Vec3 box_p, particles_dp, box_L;
  double box_mass;
};
JetResult run_jet(const Jet& jet, double box_mass, double h, int threads = 1) {
  World w(def_with_step(h, threads));
  const BodyHandle box =
      w.add_body(floating_box({0.2, 0.2, 0.2}, Vec3::Zero(), box_mass, Material{0.6, 0.0}));
  const ParticleSystemHandle ps = w.add_particle_system(quiet_system());
  Vec3 sent = Vec3::Zero();
  for (int f = 0; f < jet.frames + 30; ++f) {
    if (f < jet.frames)
      for (int k = 0; k < jet.per_frame; ++k) {
        const double dy = 0.005 * double(k % 4) - 0.0075, dz = 0.005 * double(k / 4) - 0.0075;
        w.spawn_particle(ps, {jet.x0, jet.y0 + dy, dz}, {jet.u, 0.0, 0.0}, jet.m, 0.01, 100.0);
        sent += jet.m * Vec3(jet.u, 0.0, 0.0);
      }
    w.advance(1.0 / 60.0);
  }
  const BodyMotion bm = w.motion(box);
  return {bm.linear_momentum, particle_momentum(w, ps) - sent, bm.angular_momentum, bm.mass};
}

TEST(BodyCoupling, JetMomentumChangeEqualsBoxMomentumWithinOnePercent) {
  // Every particle bounces off the face (e = 0.6) and flies back: the box's momentum must be the
  // particles' loss, P_box = -Σ m Δv (the issue asks for 1%; the float storage of the particle
  // velocities is the only difference).
  for (double h : {1.0 / 120.0, 1.0 / 480.0}) {
    const JetResult r = run_jet(Jet{}, 20.0, h);
    const double lost = -r.particles_dp.x();
    ASSERT_GT(lost, 0.0);
    // An immovable wall would take m u (1 + e) per particle; the box recedes (to ~0.4 m/s), so
    // a little less.
    const double wall = 20 * 16 * 2e-3 * 8.0 * 1.6;
    EXPECT_GT(lost, 0.9 * wall);
    EXPECT_LE(lost, wall * (1.0 + 1e-6));
    RecordProperty("balance_error_h" + std::to_string(int(std::lround(1.0 / h))),
                   std::to_string(std::abs(r.box_p.x() - lost) / lost));
    EXPECT_NEAR(r.box_p.x(), lost, 0.01 * lost) << "h = " << h;
    EXPECT_NEAR(r.box_p.x(), lost, 1e-5 * lost) << "h = " << h;  // in fact to float rounding
    EXPECT_NEAR(r.box_p.y(), -r.particles_dp.y(), 1e-6 * lost);
    EXPECT_NEAR(r.box_p.z(), -r.particles_dp.z(), 1e-6 * lost);
    // A jet at the centre of the face turns nothing (the spread is symmetric).
    EXPECT_LT(r.box_L.norm(), 1e-3 * lost * 0.2);
  }
}

TEST(BodyCoupling, AParticleAsHeavyAsTheBodyCollidesAsTwoFreeBodies) {
  // A 0.2 kg ball at 2 m/s hits a free 0.05 kg box head on: the impact is a collision of two
  // free bodies (closed form: momentum kept, relative velocity reversed times e), not a bounce
  // off a wall with the box thrown at m (1 + e) u / M. Held fixed, e = 1 would send the ball
  // back at 2 m/s and the box off at 16 m/s, creating 16 times the energy there was.
  const double mp = 0.2, mb = 0.05, u = 2.0;
  for (const double e : {1.0, 0.5}) {
    for (const double h : {1.0 / 120.0, 1.0 / 480.0}) {
      World w(def_with_step(h));
      const BodyHandle box =
          w.add_body(floating_box({0.05, 0.05, 0.05}, Vec3::Zero(), mb, Material{e, 0.0}));
      ParticleSystemDef def = quiet_system();
      def.particle_restitution = e;
      const ParticleSystemHandle ps = w.add_particle_system(def);
      w.spawn_particle(ps, {-0.3, 0.0, 0.0}, {u, 0.0, 0.0}, mp, 0.01, 100.0);
      for (int f = 0; f < 30; ++f) w.advance(1.0 / 60.0);
      // m_p v_p + M v_b = m_p u and v_b - v_p = e u.
      const double vp = (mp - e * mb) * u / (mp + mb), vb = mp * (1.0 + e) * u / (mp + mb);
      const ParticleView v = w.particles(ps);
      ASSERT_EQ(v.count, 1u);
      EXPECT_NEAR(v.velocity[0], vp, 0.01 * u) << "e = " << e << ", h = " << h;
      EXPECT_NEAR(w.velocity(box).first.x(), vb, 0.01 * u) << "e = " << e << ", h = " << h;
      EXPECT_NEAR(mp * v.velocity[0] + w.motion(box).linear_momentum.x(), mp * u, 1e-6 * mp * u);
      if (e == 1.0) {
        const double energy = 0.5 * mp * v.velocity[0] * v.velocity[0] +
                              0.5 * mb * w.velocity(box).first.squaredNorm();
        EXPECT_NEAR(energy, 0.5 * mp * u * u, 0.01 * 0.5 * mp * u * u) << "h = " << h;
      }
    }
  }
}

TEST(BodyCoupling, OffCentreJetSpinsTheBoxWithRCrossJ) {
  // The jet hits the face x = -0.2 at y = 0.1: the impulse J (along +x) acts at r = (-0.2, 0.1, 0)
  // from the centre of mass, so L = r × J = (0, 0, -0.1 J). A short jet (two frames) on a heavy
  // box: it turns by ~1e-3 rad while hit, so the lever stays 0.1 m to well within 1%.
  Jet jet;
  jet.y0 = 0.1;
  jet.frames = 2;
  const JetResult r = run_jet(jet, 100.0, 1.0 / 240.0);
  const double J = r.box_p.x();
  ASSERT_GT(J, 0.0);
  EXPECT_NEAR(r.box_L.z(), -0.1 * J, 0.01 * 0.1 * J);
  EXPECT_LT(std::abs(r.box_L.x()) + std::abs(r.box_L.y()), 0.01 * 0.1 * J);
  RecordProperty("lever_error", std::to_string(std::abs(r.box_L.z() / (-0.1 * J)) - 1.0));
}

/// A heavy floating box whose top holds 25 columns of three beads (a system with
/// collide_particles, so the upper ones' weight reaches the box through the particle solve's
/// contacts) at one corner, and when `far` 200 more
/// of the system's beads falling 5 m away, spawned first. Returns the box's angular momentum
/// after `frames` frames and the beads' weight impulse per second with its moment about the
/// box's centre, m g (-Σ y, Σ x, 0).
std::pair<Vec3, Vec3> beads_on_a_box(bool far, int frames) {
  World w(def_with_step(1.0 / 240));
  const BodyHandle box =
      w.add_body(floating_box({0.5, 0.5, 0.05}, Vec3::Zero(), 1000.0, Material{0.0, 0.5}));
  ParticleSystemDef def = quiet_system();
  def.gravity = Vec3(0, 0, -9.81);
  def.collide_particles = true;
  const ParticleSystemHandle ps = w.add_particle_system(def);
  const double m = 0.01, r = 0.01;
  if (far)
    for (int k = 0; k < 200; ++k)
      w.spawn_particle(ps, {5.0 + 0.03 * (k % 10), 0.03 * (k / 10), 1.0}, Vec3::Zero(), m, r, 100.0);
  Vec3 moment = Vec3::Zero();
  for (int k = 0; k < 75; ++k) {
    // Columns of three, 3 cm apart (not touching), spawned y-major against the grid's x-major
    // cell order: the upper beads' weight reaches the box through the particle solve.
    const int c = k % 25;
    const Vec3 p(0.2 + 0.03 * (c / 5), 0.25 + 0.03 * (c % 5), 0.05 + r + 2 * r * (k / 25));
    w.spawn_particle(ps, p, Vec3::Zero(), m, r, 100.0);
    moment += m * 9.81 * Vec3(-p.y(), p.x(), 0.0);
  }
  for (int f = 0; f < frames; ++f) w.advance(1.0 / 60.0);
  return {w.motion(box).angular_momentum, moment};
}

TEST(BodyCoupling, BeadsRestingOnABodyPushAtTheirOwnContactPoints) {
  // §3.7: each bead's contact impulse acts on the box at the surface point under that bead. 25
  // columns of three beads resting at one corner of a heavy floating box for 0.5 s hand it their
  // weight's moment about its centre, L = T m g (-Σ y, Σ x, 0) (the box barely moves: 0.75 kg
  // on 1000 kg); and
  // other beads of the system falling 5 m away change nothing (the collider contacts name the
  // particles in the grid's cell order, and their points must be read in that order too).
  const double T = 0.5;
  const auto [L, moment] = beads_on_a_box(false, 30);
  EXPECT_NEAR(L.x(), T * moment.x(), 0.02 * T * moment.norm());
  EXPECT_NEAR(L.y(), T * moment.y(), 0.02 * T * moment.norm());
  EXPECT_NEAR(L.z(), 0.0, 1e-3 * T * moment.norm());
  const Vec3 L_far = beads_on_a_box(true, 30).first;
  EXPECT_NEAR((L_far - L).norm(), 0.0, 1e-6 * L.norm()) << "with beads far away: " << L_far.transpose()
                                                        << " against " << L.transpose();
}

TEST(BodyCoupling, AbsorbedRainHandsOverAllItsMomentum) {
  // Particles killed on the plank (HitAction::kill, rain soaking in) give it their whole
  // momentum: P = N m v. Gravity-free, so every drop arrives with its start velocity.
  World w(def_with_step(1.0 / 240.0));
  Material soak{0.0, 0.3};
  soak.on_hit = HitAction::kill;
  const BodyHandle plank = w.add_body(floating_box({0.5, 0.1, 0.02}, Vec3::Zero(), 1.5, soak));
  const ParticleSystemHandle ps = w.add_particle_system(quiet_system());
  const Vec3 v(0.5, 0.0, -6.0);
  const double m = 1e-3;
  int n = 0;
  for (int i = 0; i < 40; ++i, ++n)
    w.spawn_particle(ps, {-0.4 + 0.02 * i, 0.0, 0.5}, v, m, 0.004, 100.0);
  for (int f = 0; f < 12; ++f) w.advance(1.0 / 60.0);
  EXPECT_EQ(w.particles(ps).count, 0u);  // all soaked in
  const BodyMotion bm = w.motion(plank);
  const Vec3 expected = double(n) * double(float(m)) * Vec3(double(float(v.x())), 0.0, double(float(v.z())));
  EXPECT_NEAR((bm.linear_momentum - expected).norm(), 0.0, 1e-9);
}

TEST(BodyCoupling, BodyInUniformWindAcceleratesAtFOverM) {
  // A sphere at rest in wind u: F = ½ ρ C_d A |u| u with A = π r² (a quarter of 4π r²); after
  // one step v = h F / M (semi-implicit Euler, the force evaluated at the start of the step).
  const double h = 1.0 / 120.0, r = 0.3, u = 12.0, Cd = 0.47;
  World w(def_with_step(h));
  BodyDef b;
  b.type = BodyType::dynamic;
  b.gravity = Vec3::Zero();
  b.drag_coefficient = Cd;
  b.shapes.push_back(ShapeDef::sphere(r));
  b.shapes.back().density = 200.0;
  const BodyHandle body = w.add_body(b);
  ForceFieldDef wind;
  wind.kind = FieldKind::uniform;
  wind.wind = {u, 0.0, 0.0};
  w.add_force_field(wind);
  w.advance(h);
  const BodyMotion m = w.motion(body);
  const double F = 0.5 * 1.225 * Cd * kPi * r * r * u * u;
  EXPECT_NEAR(m.linear_velocity.x() / h, F / m.mass, 1e-12 * F / m.mass);
  EXPECT_NEAR(m.linear_velocity.y(), 0.0, 1e-15);
  // It then approaches the wind speed, the force falling as (u - v)²: with a0 = F / M,
  // u - v = u / (1 + a0 t / u) (first-order error in h: within 1% at this step).
  const double T = 20.0;
  for (int i = 0; i < 600; ++i) w.advance(T / 600.0);
  const double v = w.motion(body).linear_velocity.x();
  const double a0 = F / m.mass, exact = u - u / (1.0 + a0 * (T + h) / u);
  EXPECT_NEAR(v, exact, 0.01 * exact);
  EXPECT_LT(v, u);
}

TEST(BodyCoupling, UniformForceFieldGivesForceOverMassAndAccelerationAsIs) {
  const double h = 1.0 / 60.0;
  World w(def_with_step(h));
  BodyDef b = floating_box({0.1, 0.2, 0.3}, Vec3::Zero(), 3.0, Material{});
  const BodyHandle body = w.add_body(b);
  ForceFieldDef f;
  f.kind = FieldKind::uniform;
  f.force = {6.0, 0.0, 0.0};          // a = F / m = 2 m/s²
  f.acceleration = {0.0, 0.0, 1.5};   // on every mass alike
  w.add_force_field(f);
  ForceFieldDef off = f;              // one that leaves bodies alone
  off.bodies = false;
  off.force = {100.0, 100.0, 100.0};
  w.add_force_field(off);
  for (int i = 0; i < 30; ++i) w.advance(h);
  const Vec3 v = w.motion(body).linear_velocity;
  EXPECT_NEAR(v.x(), 2.0 * 0.5, 1e-12);
  EXPECT_NEAR(v.y(), 0.0, 1e-15);
  EXPECT_NEAR(v.z(), 1.5 * 0.5, 1e-12);
}

TEST(BodyCoupling, BlastPushesBodiesRadiallyWithTheOneOverDSquaredShare) {
  // Π spreads over the sphere of radius d: a body of mean projected area A takes Π A / (4π d²)
  // along the outward direction, once, in the step holding the blast time.
  const double h = 1.0 / 120.0, Pi = 400.0;
  World w(def_with_step(h));
  const Vec3 centre(0.0, 0.0, 1.0);
  const Vec3 e(0.1, 0.1, 0.1);
  const double A = 0.25 * 8.0 * 3.0 * 0.01;  // a quarter of the cube's surface
  std::vector<BodyHandle> bodies;
  std::vector<Vec3> at = {{2.0, 0.0, 1.0}, {0.0, -4.0, 1.0}, {1.0, 1.0, 2.0}};
  for (const Vec3& p : at) bodies.push_back(w.add_body(floating_box(e, p, 1.0, Material{})));
  w.add_force_field(test::blast_field(centre, Pi, 0.05));
  for (int i = 0; i < 6; ++i) w.advance(h);  // before the blast
  for (const BodyHandle b : bodies) EXPECT_EQ(w.motion(b).linear_momentum.norm(), 0.0);
  for (int i = 0; i < 12; ++i) w.advance(h);
  for (std::size_t k = 0; k < at.size(); ++k) {
    const Vec3 d = at[k] - centre;
    const Vec3 expected = Pi * A / (4.0 * kPi * d.squaredNorm()) * d.normalized();
    const Vec3 p = w.motion(bodies[k]).linear_momentum;
    EXPECT_NEAR((p - expected).norm(), 0.0, 1e-9 * expected.norm()) << "body " << k;
    EXPECT_LT(w.motion(bodies[k]).angular_momentum.norm(), 1e-12);
  }
}

TEST(BodyCoupling, ClothFallingOnALightBoxPushesItDownAndConservesMomentum) {
  // A floating (gravity-free) 1 kg box, wider than the 0.2 kg cloth falling onto it from
  // 0.2 m: the cloth lands (inelastic) and presses it down. Gravity acts on the cloth only, so
  // P_cloth + P_box = M_cloth g t, and once the two move together the box holds its mass share,
  // P_box = M_box / (M_box + M_cloth) M_cloth g t. (Semi-implicit cloth without damping, drag or
  // the strain limit, whose internal forces cancel exactly.) The vertices are responded to with
  // the box held fixed (§3.7), which is right while what lands in one step is much lighter than
  // the box; a box lighter than the cloth would be thrown off with all of its momentum.
  const double h = 1.0 / 480.0;
  World w(def_with_step(h));
  const BodyHandle box = w.add_body(floating_box({0.3, 0.3, 0.05}, Vec3::Zero(), 1.0, Material{}));
  ClothDef c;
  c.rows = c.columns = 9;
  c.width = c.height = 0.5;
  c.mass = 0.2;
  c.transform.translation = {0.0, 0.0, 0.25};  // the grid is centred on its frame
  c.integrator = ClothIntegrator::semi_implicit_euler;
  c.stretch = {200.0, 0.0};
  c.shear = {50.0, 0.0};
  c.bend = {2.0, 0.0};
  c.max_strain = std::numeric_limits<double>::infinity();
  c.damping = 0.0;
  c.aero.air_density = 0.0;
  c.friction = 0.3;
  const ClothHandle cloth = w.add_cloth(c);
  const double T = 0.6;
  const int frames = 36;
  for (int i = 0; i < frames; ++i) w.advance(T / frames);
  const Vec3 pc = w.cloth_stats(cloth).momentum;
  const BodyMotion bm = w.motion(box);
  const Vec3 expected(0.0, 0.0, -0.2 * 9.81 * T);
  EXPECT_LT(bm.linear_momentum.z(), -0.05);  // pushed down
  EXPECT_LT(bm.center_of_mass.z(), -0.01);
  EXPECT_NEAR((pc + bm.linear_momentum - expected).norm(), 0.0, 0.01 * expected.norm());
  const double share = 1.0 / 1.2 * expected.z();
  EXPECT_NEAR(bm.linear_momentum.z(), share, 0.05 * -share);
  RecordProperty("box_share_error", std::to_string(bm.linear_momentum.z() / share - 1.0));
  RecordProperty("total_momentum_error",
                 std::to_string((pc + bm.linear_momentum - expected).norm() / expected.norm()));
}

/// A dynamic ball (radius 8 cm, `mass`, gravity on) thrown down at 8 m/s from 0.3 m onto a
/// 1 m, 0.2 kg, 24 x 24 sheet at z = 0 pinned along its border (a trampoline) or at its corners
/// (a hammock), stepped at h for 1 s (60 frames).
struct CatchResult {
  bool through = false;  ///< the ball's centre went below the sheet's lowest vertex
  std::string where;
  double max_strain = 0.0;  ///< over every frame
  double lowest = 0.0;      ///< (m) the ball centre's lowest height
  double final_speed = 0.0, final_drift = 0.0;  ///< (m/s, m) at 1 s; drift: horizontal distance
  double final_poke = 0.0;  ///< (m) at 1 s: how far the ball's bottom is below the sheet's lowest vertex
};
CatchResult throw_ball_at_sheet(double mass, double h, bool border) {
  World w(def_with_step(h));
  BodyDef b;
  b.type = BodyType::dynamic;
  b.pose.translation = {0.0, 0.0, 0.3};
  b.mass = mass;
  b.linear_velocity = {0.0, 0.0, -8.0};
  b.shapes.push_back(ShapeDef::sphere(0.08));
  const BodyHandle ball = w.add_body(b);
  ClothDef c;
  c.rows = c.columns = 24;
  c.width = c.height = 1.0;
  c.mass = 0.2;
  for (std::size_t i = 0; i < 24; ++i)
    for (std::size_t j = 0; j < 24; ++j) {
      const bool edge = i == 0 || j == 0 || i == 23 || j == 23;
      const bool corner = (i == 0 || i == 23) && (j == 0 || j == 23);
      if (border ? edge : corner) c.pins.push_back({i, j, {}});
    }
  const ClothHandle cloth = w.add_cloth(c);
  CatchResult r;
  r.lowest = std::numeric_limits<double>::infinity();
  for (int f = 0; f < 60; ++f) {
    w.advance(1.0 / 60.0);
    const ClothStats st = w.cloth_stats(cloth);
    const BodyMotion m = w.motion(ball);
    const Vec3& x = m.center_of_mass;
    r.max_strain = std::max(r.max_strain, st.max_strain);
    r.lowest = std::min(r.lowest, x.z());
    if (!r.through && x.z() < st.min_z) {
      r.through = true;
      r.where = "frame " + std::to_string(f) + ": ball at (" + std::to_string(x.x()) + ", " +
                std::to_string(x.y()) + ", " + std::to_string(x.z()) +
                ") below the sheet's lowest vertex " + std::to_string(st.min_z);
    }
    r.final_speed = m.linear_velocity.norm();
    r.final_drift = x.head<2>().norm();
    r.final_poke = st.min_z - (x.z() - 0.08);
  }
  return r;
}

TEST(BodyCoupling, ABallIsCaughtByAPinnedSheetNeverThrough) {
  // Issue 16: a sheet held by its pins holds whatever lands in it. The strain pass pulls the
  // vertices under the ball back into it; those vertices then hold the ball (its approach is
  // cancelled at them, hold_dynamic_bodies), so balls of 25 and 1/4 times the sheet's mass at
  // 8 m/s stay on it, the heavy one at rest in it. Before, the 5 kg ball went through in the first
  // frames at both step sizes, and a light ball was thrown about by the sheet's tension handed
  // to it once per contact round. Two step sizes, trampoline and hammock.
  for (const double h : {1.0 / 240.0, 1.0 / 600.0})
    for (const bool border : {true, false})
      for (const double mass : {5.0, 0.05}) {
        const CatchResult r = throw_ball_at_sheet(mass, h, border);
        SCOPED_TRACE("h = 1/" + std::to_string(int(std::lround(1.0 / h))) +
                     (border ? ", border pinned" : ", corners pinned") + ", ball mass " +
                     std::to_string(mass));
        EXPECT_FALSE(r.through) << r.where;
        EXPECT_LE(r.max_strain, 0.10 + 0.02);
        // A sheet 10% longer, held at its border or corners, cannot let the ball's centre
        // sag below about 0.45 m.
        EXPECT_GT(r.lowest, -0.45);
        // Its bottom in the sheet after 1 s (within two thicknesses of its lowest vertex), not
        // poking through it.
        EXPECT_LT(r.final_poke, 2 * 0.005);
        // The heavy ball is held where it landed: of its 8 m/s, less than 0.2 m/s is left, and
        // it is within 0.2 m of where it hit. (A sheet hung at its corners still swings with
        // it like a hammock: at 1 s its speed is anywhere in 0.01-0.15 m/s as h and the ball's
        // mass vary, in this build and the one before. The light one still bobs on the
        // vibrating sheet at the small step and wanders: README, known limits.)
        if (mass >= 5.0) {
          EXPECT_LT(r.final_speed, 0.2);
          EXPECT_LT(r.final_drift, 0.2);
        }
      }
}

TEST(BodyCoupling, SameStateAtOneTwoAndFourThreads) {
  // An emitted jet (thread-split integration over 20 000 particles) against two boxes on a plane,
  // with a wind field: the body impulses are summed in particle order whatever the split.
  std::vector<std::uint64_t> hashes;
  for (int threads : {1, 2, 4}) {
    World w(def_with_step(1.0 / 120.0, threads));
    BodyDef ground;
    ground.shapes.push_back(ShapeDef::plane());
    w.add_body(ground);
    BodyDef a = floating_box({0.2, 0.2, 0.2}, {0.0, 0.0, 0.2}, 1.0, Material{0.3, 0.4});
    a.gravity = {0.0, 0.0, -9.81};
    w.add_body(a);
    a.pose.translation = {0.0, 0.0, 0.6};
    w.add_body(a);
    ParticleSystemDef p = quiet_system();
    p.emitter.rate = 6000.0;
    p.emitter.transform.translation = {-1.5, 0.0, 0.3};
    p.emitter.transform.rotation = Quat::FromTwoVectors(Vec3::UnitZ(), Vec3(1.0, 0.0, 0.3));
    p.emitter.start_speed = {7.0, 0.5, 0.0};
    p.emitter.spread_deg = {4.0, 1.0, 0.0, 180.0};
    p.emitter.lifetime = {5.0, 0.0, 0.0};
    p.gravity = {0.0, 0.0, -9.81};
    w.add_particle_system(p);
    ForceFieldDef f;
    f.wind = {0.0, 3.0, 0.0};
    w.add_force_field(f);
    for (int i = 0; i < 60; ++i) w.advance(1.0 / 30.0);
    hashes.push_back(w.state_hash());
  }
  EXPECT_EQ(hashes[0], hashes[1]);
  EXPECT_EQ(hashes[0], hashes[2]);
}

}  // namespace
}  // namespace simreel::sim
