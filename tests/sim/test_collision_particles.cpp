// Particle–particle collisions: uniform and hashed grids (Coutinho §2.3.1–2.3.2), pair impulses (§3.6.1) and the
// simultaneous-impulse linear system (§3.6.2) reached by the sequential-impulse solver.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>

#include "collision/particle_collisions.hpp"
#include "sim_test_util.hpp"
#include "simreel/sim/random.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

using test::position_of;
using test::velocity_of;

ParticleSystemDef colliding(double e, double mu) {
  ParticleSystemDef def = test::spawn_only_system();
  def.gravity = Vec3::Zero();
  def.collide_particles = true;
  def.particle_restitution = e;
  def.particle_friction = mu;
  return def;
}

TEST(SimParticleCollision, PairConservesMomentumForAnyRestitutionAndEnergyForEOne) {
  for (double e : {0.0, 0.3, 0.7, 1.0})
    for (double mu : {0.0, 0.4}) {
      World world;
      const auto ps = world.add_particle_system(colliding(e, mu));
      const double m1 = 0.02, m2 = 0.05, r = 0.05;
      const Vec3 v1(1.0, 0.3, 0), v2(-0.5, 0, 0.1);
      // Off-centre: oblique impact, friction acts.
      world.spawn_particle(ps, Vec3(-0.3, 0, 0), v1, m1, r, 100);
      world.spawn_particle(ps, Vec3(0.0, 0.04, 0), v2, m2, r, 100);
      const Vec3 p0 = m1 * v1 + m2 * v2;
      const double ke0 = 0.5 * m1 * v1.squaredNorm() + 0.5 * m2 * v2.squaredNorm();
      world.advance(1.0);
      const ParticleView v = world.particles(ps);
      const Vec3 u1 = velocity_of(v, 0), u2 = velocity_of(v, 1);
      EXPECT_NE(u1, v1) << "no collision";
      EXPECT_LT((m1 * u1 + m2 * u2 - p0).norm(), 1e-6 * p0.norm()) << e << " " << mu;
      const double ke1 = 0.5 * m1 * u1.squaredNorm() + 0.5 * m2 * u2.squaredNorm();
      if (e == 1.0 && mu == 0.0) {
        EXPECT_NEAR(ke1, ke0, 1e-6 * ke0);
      } else {
        EXPECT_LT(ke1, ke0 * (1 - 1e-3)) << e << " " << mu;
      }
      // Head-on part: relative normal speed after = e x before (§3.6.1).
      const Vec3 n = (position_of(v, 1) - position_of(v, 0)).normalized();
      EXPECT_GE((u2 - u1).dot(n), -1e-6);  // separating
    }
}

TEST(SimParticleCollision, HeadOnRestitutionGivesTheTextbookVelocities) {
  for (double e : {0.0, 0.5, 1.0}) {
    World world;
    const auto ps = world.add_particle_system(colliding(e, 0.0));
    const double m1 = 1.0, m2 = 3.0;
    world.spawn_particle(ps, Vec3(-0.2, 0, 0), Vec3(2, 0, 0), m1, 0.05, 100);
    world.spawn_particle(ps, Vec3(0.2, 0, 0), Vec3(0, 0, 0), m2, 0.05, 100);
    world.advance(0.5);
    const ParticleView v = world.particles(ps);
    // v1' = (m1 - e m2) v / (m1 + m2), v2' = (1 + e) m1 v / (m1 + m2)
    EXPECT_NEAR(v.velocity[0], (m1 - e * m2) * 2 / (m1 + m2), 1e-5) << e;
    EXPECT_NEAR(v.velocity[3], (1 + e) * m1 * 2 / (m1 + m2), 1e-5) << e;
  }
}

TEST(SimParticleCollision, NewtonsCradleTransfersTheVelocityEndToEnd) {
  // Five equal balls 1 cm apart, e = 1: each impact is a separate pair collision, so the first
  // ball's velocity passes down the row and the last ball leaves with it.
  World world;
  const auto ps = world.add_particle_system(colliding(1.0, 0.0));
  const double r = 0.05, gap = 0.01;
  for (int k = 0; k < 5; ++k)
    world.spawn_particle(ps, Vec3(k * (2 * r + gap), 0, 0), Vec3(k == 0 ? 1.0 : 0.0, 0, 0), 0.1,
                         r, 100);
  world.advance(0.5);
  const ParticleView v = world.particles(ps);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(v.velocity[3 * k], 0.0, 1e-5) << k;
  EXPECT_NEAR(v.velocity[12], 1.0, 1e-5);
  EXPECT_GT(v.position[12], 4 * (2 * r + gap) + 0.2);
}

TEST(SimParticleCollision, SequentialImpulsesConvergeToTheSimultaneousLinearSystem) {
  // A cluster of 4 touching particles with different masses and velocities (§3.6.2): the
  // impulses P solve (J W J^T) P = target - J v, with J the contact normals and W = M^-1.
  detail::ParticleCollider pc;
  pc.x = {Vec3(0, 0, 0), Vec3(0.0999, 0, 0), Vec3(0.05, 0.0865, 0), Vec3(0.1999, 0.0, 0.0)};
  pc.v = {Vec3(1.0, 0.5, 0), Vec3(0, 0, 0), Vec3(0.1, -0.8, 0), Vec3(-0.6, 0.1, 0)};
  pc.inv_mass = {1.0, 0.5, 2.0, 1.0 / 3};
  pc.radius = {0.05, 0.05, 0.05, 0.05};
  pc.restitution = {0.6, 0.6, 0.6, 0.6};
  pc.friction = {0, 0, 0, 0};
  const std::vector<Vec3> v0 = pc.v;
  pc.find_contacts(0.0);
  const auto m = pc.contacts.size();
  ASSERT_EQ(m, 4u);  // 0-1, 0-2, 1-2, 1-3
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(Eigen::Index(m), 12);
  Eigen::VectorXd W(12), v(12);
  Eigen::VectorXd target = Eigen::VectorXd::Zero(Eigen::Index(m));
  for (int i = 0; i < 4; ++i) {
    W.segment<3>(3 * i).setConstant(pc.inv_mass[std::size_t(i)]);
    v.segment<3>(3 * i) = v0[std::size_t(i)];
  }
  for (std::size_t k = 0; k < m; ++k) {
    const auto& c = pc.contacts[k];
    J.block<1, 3>(Eigen::Index(k), 3 * c.i) = -c.n.transpose();
    J.block<1, 3>(Eigen::Index(k), 3 * c.j) = c.n.transpose();
    target[Eigen::Index(k)] = c.target;
  }
  const Eigen::MatrixXd A = J * W.asDiagonal() * J.transpose();
  const Eigen::VectorXd P = A.ldlt().solve(target - J * v);
  ASSERT_GT(P.minCoeff(), 0.0) << "the case must have all contacts compressive";
  const Eigen::VectorXd v_exact = v + W.asDiagonal() * J.transpose() * P;
  double prev = 1e300;
  for (int iters : {2, 8, 32, 200}) {
    pc.v = v0;
    for (auto& c : pc.contacts) {  // a cold start, as find_contacts() leaves them
      c.pn = 0.0;
      c.pt = Vec3::Zero();
    }
    pc.iterations = iters;
    pc.solve();
    double err = 0;
    for (int i = 0; i < 4; ++i)
      err = std::max(err, (pc.v[std::size_t(i)] - Vec3(v_exact.segment<3>(3 * i))).norm());
    EXPECT_LT(err, prev) << iters;
    prev = err;
  }
  EXPECT_LT(prev, 1e-10);
  for (std::size_t k = 0; k < m; ++k) EXPECT_NEAR(pc.contacts[k].pn, P[Eigen::Index(k)], 1e-10);
}

TEST(SimParticleCollision, GridFindsExactlyTheBruteForceContacts) {
  detail::ParticleCollider pc;
  Rng rng(3, 0);
  for (int i = 0; i < 3000; ++i) {
    pc.x.emplace_back(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-0.2, 0.2));
    pc.v.emplace_back(Vec3::Zero());
    pc.inv_mass.push_back(1.0);
    pc.radius.push_back(rng.uniform(0.005, 0.03));
    pc.restitution.push_back(0.5);
    pc.friction.push_back(0.1);
  }
  pc.find_contacts(0.05);
  std::size_t brute = 0;
  for (std::size_t i = 0; i < pc.x.size(); ++i)
    for (std::size_t j = i + 1; j < pc.x.size(); ++j)
      brute += (pc.x[i] - pc.x[j]).norm() < pc.radius[i] + pc.radius[j];
  EXPECT_GT(brute, 100u);
  EXPECT_EQ(pc.contacts.size(), brute);
  EXPECT_NEAR(pc.cell_size, 2 * 2 * 0.0175, 0.004);  // 2 x mean diameter (mean r = 17.5 mm)
}

TEST(SimParticleCollision, MultiLevelGridFindsExactlyTheBruteForcePairs) {
  // Sizes spread over two orders of magnitude (1 mm to 10 cm, log-uniform): one grid sized for
  // the largest would put hundreds of small particles in a cell, so the grid goes multi-level
  // (§2.3.2). Every overlapping pair must still be found, each once.
  detail::ParticleCollider pc;
  Rng rng(11, 0);
  for (int i = 0; i < 3000; ++i) {
    pc.x.emplace_back(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-0.2, 0.2));
    pc.v.emplace_back(Vec3::Zero());
    pc.inv_mass.push_back(1.0);
    pc.radius.push_back(0.001 * std::pow(100.0, rng.uniform()));
    pc.restitution.push_back(0.5);
    pc.friction.push_back(0.1);
  }
  for (double h : {0.0, 1.0 / 240}) {  // overlaps only, and with the speculative margin
    pc.find_contacts(0.05, h);
    EXPECT_GE(pc.levels, 4) << "the case must use several levels";
    const double m = h > 0.0 ? pc.pair_margin_fraction : 0.0;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> brute, found;
    for (std::uint32_t i = 0; i < pc.x.size(); ++i)
      for (std::uint32_t j = i + 1; j < pc.x.size(); ++j)
        if ((pc.x[i] - pc.x[j]).norm() <
            pc.radius[i] + pc.radius[j] + m * std::min(pc.radius[i], pc.radius[j]))
          brute.emplace_back(i, j);
    for (const auto& c : pc.contacts) found.emplace_back(std::min(c.i, c.j), std::max(c.i, c.j));
    std::sort(found.begin(), found.end());
    EXPECT_GT(brute.size(), 300u);
    EXPECT_EQ(found, brute);  // same pairs, none twice
  }
}

/// The pairs (smaller index first, sorted) brute force finds within the reach find_contacts()
/// uses (overlaps for h = 0, plus the speculative margin for h > 0).
std::vector<std::pair<std::uint32_t, std::uint32_t>> brute_pairs(const detail::ParticleCollider& pc,
                                                                  double h) {
  const double m = h > 0.0 ? pc.pair_margin_fraction : 0.0;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
  for (std::uint32_t i = 0; i < pc.x.size(); ++i)
    for (std::uint32_t j = i + 1; j < pc.x.size(); ++j)
      if ((pc.x[i] - pc.x[j]).norm() <
          pc.radius[i] + pc.radius[j] + m * std::min(pc.radius[i], pc.radius[j]))
        out.emplace_back(i, j);
  return out;
}

TEST(SimParticleCollision, SortedGridFindsExactlyTheBruteForcePairs) {
  // The uniform grid sorts particles by cell and tests each pair once (half stencil). Dense
  // boxes use a counting sort, a box with far more cells than particles (a few particles far
  // away) a comparison sort of the same keys, and one too wide for 21-bit cell coordinates the
  // hashed grid: every pair must be found exactly once in each case, at rest (speculative
  // contacts within the margin count) and overlapping.
  for (int spread : {0, 1, 2}) {
    detail::ParticleCollider pc;
    Rng rng(7, std::uint64_t(spread));
    for (int i = 0; i < 2500; ++i) {
      pc.x.emplace_back(rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(0.0, 0.2));
      pc.v.emplace_back(Vec3::Zero());
      pc.inv_mass.push_back(1.0);
      pc.radius.push_back(rng.uniform(0.008, 0.012));
      pc.restitution.push_back(0.5);
      pc.friction.push_back(0.1);
    }
    if (spread == 1) pc.x[17] = Vec3(40.0, -25.0, 90.0);  // sparse: comparison sort
    if (spread == 2) pc.x[17] = Vec3(1e5, 0.0, 0.0);      // > 2^21 cells: hashed grid
    for (double h : {0.0, 1.0 / 240}) {
      pc.find_contacts(0.05, h);
      EXPECT_EQ(pc.levels, 1);
      std::vector<std::pair<std::uint32_t, std::uint32_t>> found;
      for (const auto& c : pc.contacts) {
        found.emplace_back(std::min(c.i, c.j), std::max(c.i, c.j));
        // The normal points from i to j.
        EXPECT_GT(c.n.dot(pc.x[c.j] - pc.x[c.i]), 0.0);
      }
      std::sort(found.begin(), found.end());
      const auto brute = brute_pairs(pc, h);
      EXPECT_GT(brute.size(), 1000u);
      EXPECT_EQ(found, brute) << "spread " << spread << ", h " << h;
    }
  }
}

TEST(SimParticleCollision, SortedGridKeepsPairsAtTheEdgeOfReachInEveryDirection) {
  // The pair search skips candidates farther than the largest reach from the box around a cell's
  // particles along some axis. Pairs of the largest spheres set 1e-12 of their reach inside it,
  // and one ulp inside and outside it, along the 26 directions of a cube around a random point
  // (so across cell faces, edges and corners), among smaller filler particles: each pair 1e-12
  // inside must be found, and the pairs found must be those of the same squared-distance test
  // the search uses (rounding of the positions decides the ones an ulp from the edge).
  for (double h : {0.0, 1.0 / 240}) {
    detail::ParticleCollider pc;
    const double r_max = 0.012, margin = h > 0.0 ? pc.pair_margin_fraction : 0.0;
    const double reach = r_max + r_max + margin * r_max;
    Rng rng(23, 0);
    auto add = [&](const Vec3& p, double r) {
      pc.x.push_back(p);
      pc.v.emplace_back(Vec3::Zero());
      pc.inv_mass.push_back(1.0);
      pc.radius.push_back(r);
      pc.restitution.push_back(0.5);
      pc.friction.push_back(0.1);
    };
    for (int i = 0; i < 1500; ++i)
      add(Vec3(rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(0.0, 0.3)), 0.004);
    std::size_t edge_pairs = 0;
    for (int k = 0; k < 300; ++k) {
      const int d = 1 + k % 26;  // one of the 26 directions (dx, dy, dz) in {-1, 0, 1}^3 \ 0
      const int c = d < 14 ? d - 1 : d;
      Vec3 dir(double(c / 9 - 1), double(c / 3 % 3 - 1), double(c % 3 - 1));
      dir.normalize();
      const Vec3 a(rng.uniform(-0.25, 0.25), rng.uniform(-0.25, 0.25), rng.uniform(0.05, 0.25));
      const double dist = k % 3 == 0   ? reach * (1.0 - 1e-12)
                          : k % 3 == 1 ? std::nextafter(reach, 0.0)
                                       : std::nextafter(reach, 1.0);
      add(a, r_max);
      add(a + dist * dir, r_max);
      edge_pairs += k % 3 == 0;
    }
    pc.find_contacts(0.05, h);
    ASSERT_EQ(pc.levels, 1);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> found, brute;
    for (const auto& c : pc.contacts) found.emplace_back(std::min(c.i, c.j), std::max(c.i, c.j));
    std::sort(found.begin(), found.end());
    for (std::uint32_t i = 0; i < pc.x.size(); ++i)
      for (std::uint32_t j = i + 1; j < pc.x.size(); ++j) {
        const double dx = pc.x[j][0] - pc.x[i][0], dy = pc.x[j][1] - pc.x[i][1], dz = pc.x[j][2] - pc.x[i][2];
        const double e = dx * dx + dy * dy + dz * dz;
        const double ri = pc.radius[i], rj = pc.radius[j];
        const double rc = ri + rj + margin * (rj < ri ? rj : ri);
        if (e < rc * rc && e > 0.0) brute.emplace_back(i, j);
      }
    std::size_t edge_found = 0;
    for (const auto& [i, j] : found) edge_found += i >= 1500 && j == i + 1 && (i - 1500) % 6 == 0;
    EXPECT_EQ(edge_found, edge_pairs);
    EXPECT_EQ(found, brute) << "h " << h;
  }
}

TEST(SimParticleCollision, LargeCollidingSystemIsBitIdenticalAtAnyThreadCount) {
  // Above the parallel threshold the solve sweeps slabs of grid cells two at a time (even, then
  // odd), on as many threads as given: the state must not depend on the count.
  auto run = [](int threads) {
    World world(WorldDef{1.0 / 240, 3, 0.05, threads});
    PlaneDef ground;
    world.add_plane(ground);
    ParticleSystemDef def = test::spawn_only_system();
    def.collide_particles = true;
    def.emitter.max_particles = 20000;
    const auto ps = world.add_particle_system(def);
    Rng rng(5, 0);
    for (int i = 0; i < 20000; ++i)
      world.spawn_particle(ps, Vec3(rng.uniform(-0.4, 0.4), rng.uniform(-0.4, 0.4), rng.uniform(0.01, 0.3)),
                           Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)), 1e-3,
                           0.01, 100);
    for (int s = 0; s < 6; ++s) world.advance(1.0 / 240);
    const ParticleView v = world.particles(ps);
    std::vector<float> out(v.position, v.position + 3 * v.count);
    out.insert(out.end(), v.velocity, v.velocity + 3 * v.count);
    return out;
  };
  const auto one = run(1);
  EXPECT_EQ(one, run(2));
  EXPECT_EQ(one, run(3));
}

TEST(SimParticleCollision, LargeSystemRemovesOverlapsAsASmallOneDoes) {
  // A large system projects its overlaps band by band (even bands' pairs, odd bands', then
  // colliders), a small one in contact order: either way, particles dropped into one another at
  // rest come apart, step after step, to the slop the projection leaves. Overlaps measured over
  // the pairs the grid finds: mean and deepest, in units of the radius.
  const auto overlaps = [](const ParticleView& v) {
    detail::ParticleCollider pc;
    for (std::size_t i = 0; i < v.count; ++i) {
      pc.x.push_back(position_of(v, i));
      pc.v.push_back(Vec3::Zero());
      pc.inv_mass.push_back(1.0);
      pc.radius.push_back(v.radius[i]);
      pc.restitution.push_back(0.5);
      pc.friction.push_back(0.1);
    }
    pc.find_contacts(0.05);
    double sum = 0.0, deepest = 0.0;
    for (const auto& c : pc.contacts) {
      sum += c.depth;
      deepest = std::max(deepest, c.depth);
    }
    return std::pair(sum / 0.01 / double(std::max<std::size_t>(1, pc.contacts.size())), deepest / 0.01);
  };
  for (const int n : {2000, 20000}) {
    World world(WorldDef{1.0 / 240, 3, 0.05, 2});
    ParticleSystemDef def = test::spawn_only_system();
    def.gravity = Vec3::Zero();
    def.collide_particles = true;
    def.emitter.max_particles = std::size_t(n);
    const auto ps = world.add_particle_system(def);
    // 1 cm beads at ~35 % volume fraction placed at random: most overlap a neighbour.
    const double side = std::cbrt(double(n) * 4.19e-6 / 0.35);
    Rng rng(11, 0);
    for (int i = 0; i < n; ++i)
      world.spawn_particle(ps, Vec3(rng.uniform(0, side), rng.uniform(0, side), rng.uniform(0, side)),
                           Vec3::Zero(), 1e-3, 0.01, 100);
    const auto [mean0, deep0] = overlaps(world.particles(ps));
    for (int s = 0; s < 12; ++s) world.advance(1.0 / 240);
    const auto [mean1, deep1] = overlaps(world.particles(ps));
    SCOPED_TRACE(testing::Message() << n << " beads: mean overlap " << mean0 << " -> " << mean1
                                    << " r, deepest " << deep0 << " -> " << deep1 << " r");
    EXPECT_GT(mean0, 0.3);
    EXPECT_LT(mean1, 0.05 * mean0);
    EXPECT_LT(deep1, 0.1);
  }
}

TEST(SimParticleCollision, ProjectionLetsASpeculativeContactCloseItsGapButNotOverlap) {
  // A bead 0.02 r above one that cannot move (a sleeper: inverse mass 0), both at rest: within
  // the pair margin, a speculative contact (target -gap / h: it may close the gap this step).
  // Whatever the step did, the projection must leave the bead alone where it closed the gap and
  // bring it back only from an overlap, to touching: pushing it back to the gap it was found with
  // undid gravity's work every step, and a settled pile's beads read a velocity without moving
  // (BeadsHeldStillInALargePileSleepEvenWithAVelocity).
  const double r = 0.01, h = 1.0 / 240, gap = 0.02 * r;
  for (const double end_gap : {gap, 0.5 * gap, 0.0, -0.005 * r, -0.03 * r}) {
    detail::ParticleCollider pc;
    pc.x = {Vec3::Zero(), Vec3(0, 0, 2 * r + gap)};
    pc.v = {Vec3::Zero(), Vec3::Zero()};
    pc.inv_mass = {0.0, 1000.0};
    pc.radius = {r, r};
    pc.restitution = {0.2, 0.2};
    pc.friction = {0.3, 0.3};
    pc.find_contacts(0.05, h);
    ASSERT_EQ(pc.contacts.size(), 1u);
    EXPECT_NEAR(pc.contacts[0].depth, -gap, 1e-15);
    EXPECT_NEAR(pc.contacts[0].target, -gap / h, 1e-12);
    pc.x[1] = Vec3(0, 0, 2 * r + end_gap);  // where the step left it
    pc.project_positions();
    EXPECT_EQ(pc.x[0], Vec3::Zero());
    // Apart or touching: untouched (to the bit); overlapping: back to touching, not beyond.
    if (end_gap >= 0.0)
      EXPECT_EQ(pc.x[1].z(), 2 * r + end_gap) << "end gap " << end_gap;
    else
      EXPECT_NEAR(pc.x[1].z(), 2 * r, 1e-15) << "end gap " << end_gap;
  }
}

/// Colliders for the wavefront tests: the ground plane and a box moving into the heap (its
/// contacts carry a surface velocity).
std::vector<detail::Collider> ground_and_moving_box() {
  std::vector<detail::Collider> cols;
  cols.push_back(detail::make_collider(ShapeDef::plane(), "ground"));
  cols.back().follow(Transform{}, Vec3::Zero(), Vec3::Zero());
  cols.push_back(detail::make_collider(ShapeDef::box(Vec3(0.05, 0.2, 0.05)), "box"));
  cols.back().follow(Transform{Vec3(0.1, 0.0, 0.04), Quat::Identity()}, Vec3(-0.5, 0.1, 0.0),
                     Vec3(0.0, 0.0, 2.0));
  return cols;
}

TEST(SimParticleCollision, BeadsWokenInALargeSleepingLayerRestOnTheirNeighbours) {
  // 20,000 sleeping beads in two touching layers on the ground (a large system: solved in bands
  // over the threads) and 50 awake beads coming down at 1 m/s onto the top layer. The beads they
  // hit wake, and their pairs with the sleepers under them join the contacts before the solve:
  // the banded sweeps must solve those pairs too (a woken bead must not go on into the sleeper
  // under it), the same at one and two threads.
  const double r = 0.01, h = 1.0 / 240;
  const int side = 100, hits = 50;
  std::vector<detail::Collider> ground;
  ground.push_back(detail::make_collider(ShapeDef::plane(), "ground"));
  ground.back().follow(Transform{}, Vec3::Zero(), Vec3::Zero());
  const auto run = [&](int threads) {
    detail::ParticleStore s;
    s.track_rest = true;
    const std::size_t n = std::size_t(2 * side * side + hits);
    s.append(n);
    for (std::size_t k = 0; k < n; ++k) {
      Vec3 x, v = Vec3::Zero();
      if (k < std::size_t(2 * side * side)) {
        const std::size_t layer = k / std::size_t(side * side), q = k % std::size_t(side * side);
        x = Vec3(2 * r * double(q % std::size_t(side)), 2 * r * double(q / std::size_t(side)),
                 r + 2 * r * double(layer));
        for (int a = 0; a < 3; ++a) s.rest[4 * k + std::size_t(a)] = float(x[a]);
        s.rest[4 * k + 3] = detail::kSleepTime;
      } else {  // above every 7th bead of the top layer's middle rows, 2 mm into it
        const std::size_t q = (k - std::size_t(2 * side * side)) * 7 + std::size_t(side * side / 2);
        x = Vec3(2 * r * double(q % std::size_t(side)), 2 * r * double(q / std::size_t(side)), 5 * r - 0.002);
        v = Vec3(0, 0, -1.0);
      }
      for (int a = 0; a < 3; ++a) {
        s.position[3 * k + std::size_t(a)] = float(x[a]);
        s.velocity[3 * k + std::size_t(a)] = float(v[a]);
      }
      s.radius[k] = float(r);
      s.mass[k] = 4.19e-3f;
      s.age[k] = 1.0f;
      s.id[k] = k;
    }
    detail::ParticleCollider pc;
    pc.threads = threads;
    const std::vector<detail::ParticleGroupMember> members{{&s, 0.2, 0.3, true, 0, true, 9.81}};
    pc.run(members, 0.05, h, &ground);
    return std::vector<float>(s.velocity.data(), s.velocity.data() + 3 * n);
  };
  const std::vector<float> one = run(1);
  EXPECT_EQ(one, run(2));
  for (int k = 0; k < hits; ++k) {
    // The bead hit (held by the sleeper under it, it may fall asleep again at once) and the one
    // that hit it (bounced off): neither goes on down.
    const std::size_t q = std::size_t(k) * 7 + std::size_t(side * side / 2) + std::size_t(side * side);
    const std::size_t p = std::size_t(2 * side * side + k);
    EXPECT_GE(one[3 * q + 2], -1e-3f) << "woken bead " << q << " goes on into the sleeper under it";
    EXPECT_GE(one[3 * p + 2], -1e-3f) << "bead " << p << " goes on through the one it hit";
  }
}

/// Appends n particles to pc's working arrays: positions uniform in [-w, w]² x [z0, z1] (m,
/// box = {w, z0, z1}), velocities in [-u, u]² x [vz0, vz1] (m/s, vel = {u, vz0, vz1}), mass 1-3 g,
/// radius 6-11 mm, restitution e, friction 0 for every k-th particle and 0.4 for the others.
void add_random_particles(detail::ParticleCollider& pc, Rng& rng, int n, const std::array<double, 3>& box,
                          const std::array<double, 3>& vel, double e, int k) {
  for (int i = 0; i < n; ++i) {
    pc.x.emplace_back(rng.uniform(-box[0], box[0]), rng.uniform(-box[0], box[0]), rng.uniform(box[1], box[2]));
    pc.v.emplace_back(rng.uniform(-vel[0], vel[0]), rng.uniform(-vel[0], vel[0]), rng.uniform(vel[1], vel[2]));
    pc.inv_mass.push_back(1.0 / rng.uniform(1e-3, 3e-3));
    pc.radius.push_back(rng.uniform(0.006, 0.011));
    pc.restitution.push_back(e);
    pc.friction.push_back(i % k == 0 ? 0.0 : 0.4);
  }
}

TEST(SimParticleCollision, WavefrontSweepsGiveTheBitsOfTheContactOrder) {
  // The solve sweeps the contacts in waves that share no particle (schedule()), so that the
  // processor overlaps neighbouring updates. Each update touches only its two particles, so any
  // order that keeps each particle's contacts in order is the same Gauss-Seidel sweep: the
  // velocities and impulses must be those of the plain sweep in contact order, to the bit.
  // A heap on the ground against a moving box: pairs and collider contacts, resting, sliding
  // (friction 0.4 and 0), speculative gaps, warm-started impulses.
  const double h = 1.0 / 240;
  const std::vector<detail::Collider> cols = ground_and_moving_box();
  detail::ParticleCollider a;
  Rng rng(17, 0);
  add_random_particles(a, rng, 4000, {0.15, 0.004, 0.12}, {0.3, -0.5, 0.1}, 0.3, 5);
  a.find_contacts(0.05, h);
  const std::size_t pairs = a.contacts.size();
  a.find_collider_contacts(cols, h, 0.05);
  ASSERT_GT(pairs, 5000u);
  ASSERT_GT(a.contacts.size() - pairs, 300u);
  for (auto& c : a.contacts) {  // a warm start, as the previous step would leave it
    c.pn = rng.uniform(0.0, 1e-4);
    c.pt = Vec3(rng.uniform(-1e-5, 1e-5), rng.uniform(-1e-5, 1e-5), rng.uniform(-1e-5, 1e-5));
  }
  detail::ParticleCollider b = a;
  b.wavefront = false;
  // The wavefront sweep with eight contacts at once (two interleaved groups of four AVX2 lanes,
  // the default), four, two (where AVX2 is missing) and one.
  ASSERT_EQ(a.max_lanes, 8);
  // Eight and four also with AVX2's 16 registers where the CPU has AVX-512VL's 32.
  std::vector<detail::ParticleCollider> lanes(6, a);
  lanes[1].max_lanes = 4;
  lanes[2].max_lanes = 2;
  lanes[3].max_lanes = 1;
  lanes[4].avx512_registers = false;
  lanes[5].max_lanes = 4;
  lanes[5].avx512_registers = false;
  const std::vector<Vec3> v0 = a.v;
  b.solve();
  for (auto& l : lanes) l.solve();
  int changed = 0;
  for (std::size_t p = 0; p < a.v.size(); ++p) {
    for (const auto& l : lanes) ASSERT_EQ(l.v[p], b.v[p]) << "particle " << p << ", lanes " << l.max_lanes;
    changed += lanes[0].v[p] != v0[p];
  }
  EXPECT_GT(changed, 3000);
  int sliding = 0;
  for (std::size_t q = 0; q < a.contacts.size(); ++q) {
    for (const auto& l : lanes) {
      ASSERT_EQ(l.contacts[q].pn, b.contacts[q].pn) << "contact " << q << ", lanes " << l.max_lanes;
      ASSERT_EQ(l.contacts[q].pt, b.contacts[q].pt) << "contact " << q << ", lanes " << l.max_lanes;
    }
    const auto& c = b.contacts[q];
    sliding += c.mu > 0.0 && c.pn > 0.0 && c.pt.norm() >= c.mu * c.pn * (1 - 1e-12);
  }
  EXPECT_GT(sliding, 100) << "the case must have contacts at the friction bound";
  // The overlap projection in the sweeps' work order (what run() does) against contact order:
  // the same bits, each wavefront's order and width alike.
  const std::vector<Vec3> x0 = b.x;
  b.project_positions();
  for (auto& l : lanes) l.project_positions(true);
  int moved = 0;
  for (std::size_t p = 0; p < a.x.size(); ++p) {
    for (const auto& l : lanes) ASSERT_EQ(l.x[p], b.x[p]) << "particle " << p << ", lanes " << l.max_lanes;
    moved += b.x[p] != x0[p];
  }
  EXPECT_GT(moved, 1000) << "the case must have overlaps to project";
}

TEST(SimParticleCollision, PairSearchWidthsFindTheSamePairs) {
  // The pair search tests a cell's candidates eight (AVX-512VL) or four (AVX2) at a time where
  // the CPU has them, compressing the kept ones to the front; each lane performs the scalar
  // test's operations, so the contacts (which pairs, in which order, with which depth, normal
  // and target) must be those of the one-at-a-time search, to the bit. A dense random heap of
  // radii 6-11 mm (one uniform grid), speculative gaps included.
  const double h = 1.0 / 240;
  detail::ParticleCollider a;
  Rng rng(23, 0);
  add_random_particles(a, rng, 6000, {0.12, 0.0, 0.1}, {0.5, -0.5, 0.5}, 0.3, 4);
  std::vector<detail::ParticleCollider> width(3, a);
  width[1].pair_search_lanes = 4;
  width[2].pair_search_lanes = 1;
  for (auto& w : width) w.find_contacts(0.05, h);
  ASSERT_EQ(width[0].levels, 1);
  const auto& ref = width[2].contacts;
  ASSERT_GT(ref.size(), 10000u);
  int gaps = 0;
  for (const auto& c : ref) gaps += c.depth < 0.0;
  EXPECT_GT(gaps, 100) << "the case must have speculative contacts";
  for (int k = 0; k < 2; ++k) {
    const auto& got = width[std::size_t(k)].contacts;
    ASSERT_EQ(got.size(), ref.size()) << "lanes " << width[std::size_t(k)].pair_search_lanes;
    for (std::size_t q = 0; q < ref.size(); ++q) {
      ASSERT_EQ(got[q].i, ref[q].i) << "contact " << q;
      ASSERT_EQ(got[q].j, ref[q].j) << "contact " << q;
      ASSERT_EQ(got[q].depth, ref[q].depth) << "contact " << q;
      ASSERT_EQ(got[q].n, ref[q].n) << "contact " << q;
      ASSERT_EQ(got[q].target, ref[q].target) << "contact " << q;
    }
  }
}

TEST(SimParticleCollision, AwakeSearchGivesTheFullSearchsContactsToTheBit) {
  // With most particles asleep the pair search starts from the awake ones alone, over the 27
  // cells around each (awake_search_share), instead of every particle's half stencil. A dense
  // random heap of 20,000 beads (radii 6-11 mm; a large system, whose full search splits over
  // the threads), one in ten awake and coming down at up to 1 m/s (impacts that wake sleepers,
  // whose pairs with other sleepers then join): the contacts (which pairs, in which order, with
  // which depth, normal, target and impulse) and the run's results must be those of the full
  // search, to the bit, at one and two threads.
  const double h = 1.0 / 240;
  std::vector<detail::Collider> ground;
  ground.push_back(detail::make_collider(ShapeDef::plane(), "ground"));
  ground.back().follow(Transform{}, Vec3::Zero(), Vec3::Zero());
  struct Result {
    std::vector<detail::ParticleCollider::Contact> contacts;
    std::vector<float> x, v;
    std::size_t awake_pairs = 0, mixed_pairs = 0;
  };
  const auto run = [&](int share, int threads) {
    detail::ParticleStore s;
    s.track_rest = true;
    const std::size_t n = 20000;
    s.append(n);
    Rng rng(29, 0);
    for (std::size_t k = 0; k < n; ++k) {
      const bool awake = k % 10 == 3;
      const Vec3 x(rng.uniform(-0.27, 0.27), rng.uniform(-0.27, 0.27), rng.uniform(0.011, 0.4));
      const Vec3 v = awake ? Vec3(rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(-1.0, 0.0))
                           : Vec3::Zero();
      for (int a = 0; a < 3; ++a) {
        s.position[3 * k + std::size_t(a)] = float(x[a]);
        s.velocity[3 * k + std::size_t(a)] = float(v[a]);
        s.rest[4 * k + std::size_t(a)] = float(x[a]);
      }
      s.rest[4 * k + 3] = awake ? 0.0f : detail::kSleepTime;
      s.radius[k] = float(rng.uniform(0.006, 0.011));
      s.mass[k] = float(rng.uniform(1e-3, 3e-3));
      s.age[k] = 1.0f;
      s.id[k] = k;
    }
    detail::ParticleCollider pc;
    pc.threads = threads;
    pc.awake_search_share = share;
    const std::vector<detail::ParticleGroupMember> members{{&s, 0.3, 0.4, true, 0, true, 9.81}};
    pc.run(members, 0.05, h, &ground);
    Result r{pc.contacts, std::vector<float>(s.position.data(), s.position.data() + 3 * n),
             std::vector<float>(s.velocity.data(), s.velocity.data() + 3 * n)};
    for (const auto& c : pc.contacts) {
      if (c.i == detail::ParticleCollider::kCollider) continue;
      ++(pc.inv_mass[c.i] != 0.0 && pc.inv_mass[c.j] != 0.0 ? r.awake_pairs : r.mixed_pairs);
    }
    return r;
  };
  const Result full = run(0, 1);
  EXPECT_GT(full.awake_pairs, 2000u) << "the case must have pairs of two awake beads";
  EXPECT_GT(full.mixed_pairs, 2000u) << "the case must have pairs of an awake bead and a sleeper";
  for (const auto& [share, threads] : {std::pair{1, 1}, std::pair{4, 1}, std::pair{1, 2}}) {
    const Result got = run(share, threads);
    ASSERT_EQ(got.contacts.size(), full.contacts.size()) << "share " << share << ", threads " << threads;
    for (std::size_t q = 0; q < full.contacts.size(); ++q) {
      const auto &a = got.contacts[q], &b = full.contacts[q];
      ASSERT_EQ(a.i, b.i) << "contact " << q;
      ASSERT_EQ(a.j, b.j) << "contact " << q;
      ASSERT_EQ(a.depth, b.depth) << "contact " << q;
      ASSERT_EQ(a.n, b.n) << "contact " << q;
      ASSERT_EQ(a.target, b.target) << "contact " << q;
      ASSERT_EQ(a.pn, b.pn) << "contact " << q;
    }
    EXPECT_EQ(got.x, full.x);
    EXPECT_EQ(got.v, full.v);
  }
}

TEST(SimParticleCollision, LoneContactsAreSolvedByTheFirstSweep) {
  // A contact that shares neither particle with another is solved by one update: its normal
  // impulse reaches its restitution target, its friction impulse cancels the sliding or stops at
  // the Coulomb bound, and later sweeps find nothing left to change. So the solve leaves lone
  // contacts out of every sweep after the first (lone_contacts). Against the solve that sweeps
  // them all: the coupled contacts' particles take the same bits (nothing they touch differs),
  // the lone ones agree to rounding, and each lone contact satisfies its conditions.
  const double h = 1.0 / 240;
  const std::vector<detail::Collider> cols = ground_and_moving_box();
  detail::ParticleCollider a;
  Rng rng(41, 0);
  // A spray over the ground: sparse enough that many contacts are lone, dense enough for
  // clusters. Restitution 0.5 (impacts) and friction 0.4 and 0.
  add_random_particles(a, rng, 4000, {0.4, 0.006, 0.2}, {0.5, -0.8, 0.2}, 0.5, 4);
  a.find_contacts(0.05, h);
  a.find_collider_contacts(cols, h, 0.05);
  for (auto& c : a.contacts) {  // a warm start as load_warm_start() leaves it: pt in the tangent plane
    if (rng.uniform(0.0, 1.0) < 0.5) continue;
    c.pn = rng.uniform(0.0, 1e-4);
    const Vec3 t(rng.uniform(-1e-5, 1e-5), rng.uniform(-1e-5, 1e-5), rng.uniform(-1e-5, 1e-5));
    c.pt = t - t.dot(c.n) * c.n;
  }
  std::vector<int> degree(a.x.size(), 0);
  for (const auto& c : a.contacts) {
    ++degree[c.j];
    if (c.i != detail::ParticleCollider::kCollider) ++degree[c.i];
  }
  const auto lone = [&](const detail::ParticleCollider::Contact& c) {
    return degree[c.j] == 1 && (c.i == detail::ParticleCollider::kCollider || degree[c.i] == 1);
  };
  detail::ParticleCollider all = a;
  all.lone_contacts = false;
  ASSERT_TRUE(a.lone_contacts);  // the default
  a.solve();
  all.solve();
  int lone_pairs = 0, lone_walls = 0, coupled = 0, sliding = 0;
  for (std::size_t q = 0; q < a.contacts.size(); ++q) {
    const auto& c = a.contacts[q];
    const auto& r = all.contacts[q];
    const bool wall = c.i == detail::ParticleCollider::kCollider;
    if (!lone(c)) {
      ++coupled;
      ASSERT_EQ(c.pn, r.pn) << "coupled contact " << q;
      ASSERT_EQ(c.pt, r.pt) << "coupled contact " << q;
      ASSERT_EQ(a.v[c.j], all.v[c.j]) << "coupled contact " << q;
      if (!wall) {
        ASSERT_EQ(a.v[c.i], all.v[c.i]) << "coupled contact " << q;
      }
      continue;
    }
    (wall ? lone_walls : lone_pairs) += 1;
    const double scale = c.m_eff * 1e-12 + 1e-18;
    ASSERT_NEAR(c.pn, r.pn, scale * 10) << "lone contact " << q;
    ASSERT_NEAR((c.pt - r.pt).norm(), 0.0, scale * 10) << "lone contact " << q;
    // Its conditions: the relative normal velocity at the target while it pushes (no faster
    // apart otherwise), no sliding inside the friction cone, the impulse on the cone when sliding.
    const Vec3 vi = wall ? a.wall_vc[q - (a.contacts.size() - a.wall_vc.size())] : a.v[c.i];
    const Vec3 dv = a.v[c.j] - vi;
    const double vn = dv.dot(c.n);
    if (c.pn > 0.0) {
      ASSERT_NEAR(vn, c.target, 1e-9) << "lone contact " << q;
    } else {
      ASSERT_GE(vn, c.target - 1e-9) << "lone contact " << q;
    }
    const Vec3 vt = dv - vn * c.n;
    if (c.pt.norm() < c.mu * c.pn * (1 - 1e-9)) {
      ASSERT_LT(vt.norm(), 1e-9) << "lone contact " << q << " slides inside the friction cone";
    } else if (c.pn > 0.0 && c.mu > 0.0) {
      ++sliding;
      ASSERT_NEAR(c.pt.norm(), c.mu * c.pn, 1e-9 * c.mu * c.pn) << "lone contact " << q;
    }
  }
  EXPECT_GT(lone_pairs, 300);  // 461, 126, 983 and 261 when written
  EXPECT_GT(lone_walls, 80);
  EXPECT_GT(coupled, 600);
  EXPECT_GT(sliding, 100) << "the case must have lone contacts at the friction bound";
}

TEST(SimParticleCollision, LoneContactsOfABandedStepNeedOnlyTheFirstSweep) {
  // The same through run() for a system large enough to be swept in bands (each band's lone
  // pairs and lone collider contacts after its coupled ones), at one and two threads: particles
  // of coupled contacts to the bit, those of lone contacts to rounding.
  const double h = 1.0 / 240;
  const std::vector<detail::Collider> cols = ground_and_moving_box();
  const std::size_t n = 20000;
  Rng rng(29, 0);
  detail::ParticleStore start;
  start.append(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double x[3] = {rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6), rng.uniform(0.004, 0.15)};
    const double v[3] = {rng.uniform(-0.4, 0.4), rng.uniform(-0.4, 0.4), rng.uniform(-0.6, 0.1)};
    for (int k = 0; k < 3; ++k) {
      start.position[3 * i + std::size_t(k)] = float(x[k]);
      start.velocity[3 * i + std::size_t(k)] = float(v[k]);
    }
    start.radius[i] = float(rng.uniform(0.004, 0.006));
    start.mass[i] = 1e-3f;
    start.age[i] = 1.0f;
    start.id[i] = i;
  }
  const auto step = [&](bool lone, int threads) {
    auto pc = std::make_unique<detail::ParticleCollider>();
    detail::ParticleStore s = start;
    pc->lone_contacts = lone;
    pc->threads = threads;
    pc->run({{&s, 0.5, 0.4, true, 0}}, 0.05, h, &cols);
    return std::pair(std::move(pc), s);
  };
  const auto [all, s_all] = step(false, 1);
  const std::vector<detail::ParticleCollider::Contact>& contacts = all->contacts;
  std::vector<int> degree(n, 0);
  for (const auto& c : contacts) {
    ++degree[c.j];
    if (c.i != detail::ParticleCollider::kCollider) ++degree[c.i];
  }
  std::vector<char> in_lone(n, 0);  // working index: touched by a lone contact
  int lone = 0;
  for (const auto& c : contacts) {
    const bool wall = c.i == detail::ParticleCollider::kCollider;
    if (degree[c.j] != 1 || (!wall && degree[c.i] != 1)) continue;
    ++lone;
    in_lone[c.j] = 1;
    if (!wall) in_lone[c.i] = 1;
  }
  ASSERT_GT(lone, 1000);
  ASSERT_GT(contacts.size() - std::size_t(lone), 2000u);
  for (int threads : {1, 2}) {
    const auto [a, s_a] = step(true, threads);
    ASSERT_EQ(a->contacts.size(), contacts.size());
    int differ = 0;
    for (std::uint32_t q = 0; q < n; ++q) {
      const std::size_t p = a->flat_index(q);
      for (int k = 0; k < 3; ++k) {
        const float va = s_a.velocity[3 * p + std::size_t(k)], vb = s_all.velocity[3 * p + std::size_t(k)];
        const float xa = s_a.position[3 * p + std::size_t(k)], xb = s_all.position[3 * p + std::size_t(k)];
        if (in_lone[q] == 0) {
          ASSERT_EQ(va, vb) << "particle " << p << " of coupled contacts, threads " << threads;
          ASSERT_EQ(xa, xb) << "particle " << p << " of coupled contacts, threads " << threads;
        } else {
          ASSERT_NEAR(va, vb, 1e-6f * (1.0f + std::abs(vb))) << "particle " << p << ", threads " << threads;
          ASSERT_NEAR(xa, xb, 1e-6f * (1.0f + std::abs(xb))) << "particle " << p << ", threads " << threads;
        }
      }
      if (in_lone[q] != 0) differ += a->v[q] != all->v[q];
    }
    // The later sweeps were left out for them: the rounding of their working (double)
    // velocities shows it (1,535 of the 2,585 lone contacts' particles when written).
    EXPECT_GT(differ, 100) << "threads " << threads;
  }
}

TEST(SimParticleCollision, WavefrontSweepsOfBandsGiveTheBitsOfTheContactOrder) {
  // The same for a step of run() large enough to be solved in bands (even bands, odd bands,
  // then the collider contacts), at 1 to 4 threads: positions and velocities to the bit.
  const double h = 1.0 / 240;
  const std::vector<detail::Collider> cols = ground_and_moving_box();
  detail::ParticleStore start;
  const std::size_t n = 20000;
  start.append(n);
  Rng rng(23, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const float x[3] = {float(rng.uniform(-0.3, 0.3)), float(rng.uniform(-0.3, 0.3)),
                        float(rng.uniform(0.004, 0.1))};
    const float v[3] = {float(rng.uniform(-0.3, 0.3)), float(rng.uniform(-0.3, 0.3)),
                        float(rng.uniform(-0.5, 0.1))};
    for (int k = 0; k < 3; ++k) {
      start.position[3 * i + std::size_t(k)] = x[k];
      start.velocity[3 * i + std::size_t(k)] = v[k];
    }
    start.radius[i] = float(rng.uniform(0.004, 0.006));
    start.mass[i] = 1e-3f;
    start.age[i] = 1.0f;
    start.id[i] = i;
  }
  auto step = [&](bool wavefront, int threads) {
    detail::ParticleStore s;
    s.append(n);
    std::copy_n(start.position.data(), 3 * n, s.position.data());
    std::copy_n(start.velocity.data(), 3 * n, s.velocity.data());
    std::copy_n(start.radius.data(), n, s.radius.data());
    std::copy_n(start.mass.data(), n, s.mass.data());
    std::copy_n(start.age.data(), n, s.age.data());
    std::copy_n(start.id.data(), n, s.id.data());
    detail::ParticleCollider pc;
    pc.wavefront = wavefront;
    pc.threads = threads;
    const std::vector<detail::ParticleGroupMember> members{{&s, 0.3, 0.4, true, 0}};
    for (int k = 0; k < 3; ++k) pc.run(members, 0.05, h, &cols);  // warm-started after the first
    std::vector<float> out(s.position.data(), s.position.data() + 3 * n);
    out.insert(out.end(), s.velocity.data(), s.velocity.data() + 3 * n);
    return std::pair(out, pc.contacts.size());
  };
  const auto [plain, contacts] = step(false, 1);
  ASSERT_GT(contacts, 20000u);
  EXPECT_EQ(step(true, 1).first, plain);
  EXPECT_EQ(step(true, 2).first, plain);
  // Three threads: a middle thread's bands take impulses from the band before them and give to
  // the band after (the warm start's first application, the sweeps' split by contact count).
  EXPECT_EQ(step(true, 3).first, plain);
  // Four threads on this machine's cores: the threads' shares of the pair search and the sweeps
  // (run_claims.hpp) then depend on how the system schedules them, and the bits must not.
  EXPECT_EQ(step(true, 4).first, plain);
  int changed = 0;
  for (std::size_t k = 0; k < 3 * n; ++k) changed += plain[3 * n + k] != start.velocity[k];
  EXPECT_GT(changed, 3 * 10000);
}

TEST(SimParticleCollision, StackOfTenOnAPlaneStaysStackedWithoutDrift) {
  // Resting contact (§3.6.3): ten particles in a column on the ground. The ground contact is in
  // the same solve as the pair contacts and the resting impulses are warm started, so the
  // column holds with its weight carried down to the ground, neither sinking nor creeping.
  const double r = 0.01;
  World world;
  PlaneDef ground;
  ground.material = Material(0.5, 0.5);
  world.add_plane(ground);
  ParticleSystemDef def = test::spawn_only_system();
  def.collide_particles = true;
  def.particle_restitution = 0.5;
  def.particle_friction = 0.5;
  const auto ps = world.add_particle_system(def);
  std::vector<Vec3> start;
  for (int k = 0; k < 10; ++k) {
    start.emplace_back(0, 0, r + 2 * r * k);
    world.spawn_particle(ps, start.back(), Vec3::Zero(), 0.01, r, 100);
  }
  double drift = 0, speed = 0;
  for (int frame = 0; frame < 5 * 24; ++frame) {
    world.advance(1.0 / 24);
    const ParticleView v = world.particles(ps);
    ASSERT_EQ(v.count, 10u);
    for (std::size_t i = 0; i < v.count; ++i) {
      drift = std::max(drift, (position_of(v, i) - start[i]).norm());
      speed = std::max(speed, velocity_of(v, i).norm());
      EXPECT_GE(v.position[3 * i + 2], r - 1e-6) << i;
    }
  }
  EXPECT_LT(drift, 1e-3);
  EXPECT_LT(speed, 1e-2);
  // The column is still a column: the top particle sits (almost) where it started.
  EXPECT_NEAR(world.particles(ps).position[3 * 9 + 2], 19 * r, 1e-3);
}

TEST(SimParticleCollision, SystemsCollideAcrossAGroupOnlyWhenTheyOptIn) {
  for (bool grouped : {false, true}) {
    World world;
    ParticleSystemDef a = colliding(1.0, 0.0), b = colliding(1.0, 0.0);
    a.collide_particles = b.collide_particles = false;
    if (grouped) a.collision_group = b.collision_group = "balls";
    const auto sa = world.add_particle_system(a);
    const auto sb = world.add_particle_system(b);
    world.spawn_particle(sa, Vec3(-0.2, 0, 0), Vec3(1, 0, 0), 1, 0.05, 100);
    world.spawn_particle(sb, Vec3(0.2, 0, 0), Vec3(-1, 0, 0), 1, 0.05, 100);
    world.advance(0.5);
    EXPECT_NEAR(world.particles(sa).velocity[0], grouped ? -1.0 : 1.0, 1e-5);
    EXPECT_NEAR(world.particles(sb).velocity[0], grouped ? 1.0 : -1.0, 1e-5);
  }
}

TEST(SimParticleCollision, SameSeedGivesBitIdenticalState) {
  auto run = [](std::uint64_t seed) {
    World world(WorldDef{1.0 / 240, seed, 0.05});
    PlaneDef ground;
    ground.material = Material(0.3, 0.4);
    ground.material.on_hit = HitAction::split;
    ground.material.split.min_radius = 0.009;
    world.add_plane(ground);
    ParticleSystemDef def;
    def.collide_particles = true;
    def.emitter.rate = 300;
    def.emitter.spread_deg = {20, 10, 0, 60};
    def.emitter.start_speed = {2, 0.5, 0};
    def.emitter.transform.translation = Vec3(0, 0, 0.3);
    const auto ps = world.add_particle_system(def);
    world.advance(1.0);
    const ParticleView v = world.particles(ps);
    return std::vector<float>(v.position, v.position + 3 * v.count);
  };
  const auto a = run(5), b = run(5), c = run(6);
  ASSERT_GT(a.size(), 300u);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}


TEST(SimParticleCollision, RunWritesEachWorkingEntryBackToItsOwnParticle) {
  // run() reads every working entry straight from its member's particle in cell order and writes
  // it back there: with two members of a group (flat order: the first's particles, then the
  // second's), each entry must come back to its own particle, once, and the pair impulses
  // (equal and opposite, §3.6.1) keep the group's momentum across the two stores.
  Rng rng(31);
  const double r = 0.01, h = 1.0 / 240;
  const std::size_t sizes[2] = {700, 1300};
  detail::ParticleStore stores[2];
  Vec3 p0 = Vec3::Zero();
  for (int mi = 0; mi < 2; ++mi) {
    detail::ParticleStore& s = stores[mi];
    s.append(sizes[mi]);
    for (std::size_t i = 0; i < sizes[mi]; ++i) {
      for (int a = 0; a < 3; ++a) {  // a dense cube 0.2 m wide, 5 cm above the ground
        s.position[3 * i + std::size_t(a)] = float(rng.uniform(0.0, 0.2) + (a == 2 ? 0.05 : 0.0));
        s.velocity[3 * i + std::size_t(a)] = float(rng.uniform(-0.5, 0.5));
      }
      s.radius[i] = float(r);
      s.mass[i] = mi == 0 ? 4e-3f : 1e-3f;
      s.age[i] = 1.0f;
      s.id[i] = std::uint32_t(i);
      for (int a = 0; a < 3; ++a) p0[a] += double(s.mass[i]) * double(s.velocity[3 * i + std::size_t(a)]);
    }
  }
  const std::vector<detail::ParticleGroupMember> members{{&stores[0], 0.4, 0.3, true, 0},
                                                         {&stores[1], 0.2, 0.3, true, 1}};
  detail::ParticleCollider pc;
  pc.run(members, 0.05, h, nullptr);
  ASSERT_GT(pc.contacts.size(), 1000u);
  Vec3 p1 = Vec3::Zero();
  for (int mi = 0; mi < 2; ++mi)
    for (std::size_t i = 0; i < sizes[mi]; ++i)
      for (int a = 0; a < 3; ++a)
        p1[a] += double(stores[mi].mass[i]) * double(stores[mi].velocity[3 * i + std::size_t(a)]);
  // Each velocity stored as a float moves it by up to 6e-8 of itself: under 2e-10 kg m/s a
  // particle, 4e-7 for all; a particle written with another's velocity moves it by ~1e-3.
  EXPECT_LT((p1 - p0).norm(), 4e-7) << "momentum before " << p0.transpose() << " after " << p1.transpose();
  std::vector<int> seen(sizes[0] + sizes[1], 0);
  for (std::uint32_t q = 0; q < pc.x.size(); ++q) {
    const auto [mi, i] = pc.member_particle(q);
    ASSERT_LT(mi, 2u);
    ASSERT_LT(i, sizes[mi]);
    EXPECT_EQ(pc.flat_index(q), (mi == 0 ? 0 : sizes[0]) + i);
    ++seen[pc.flat_index(q)];
    const detail::ParticleStore& s = stores[mi];
    for (int a = 0; a < 3; ++a) {
      ASSERT_EQ(s.position[3 * i + std::size_t(a)], float(pc.x[q][a])) << "entry " << q;
      ASSERT_EQ(s.velocity[3 * i + std::size_t(a)], float(pc.v[q][a])) << "entry " << q;
    }
    EXPECT_EQ(pc.radius[q], double(s.radius[i]));
    EXPECT_EQ(pc.restitution[q], members[mi].restitution);
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), std::ptrdiff_t(seen.size()));
}

TEST(SimParticleCollision, AlikeMembersGiveTheBitsOfThePerParticleSurfaceArrays) {
  // With members alike in restitution, friction and colliding, run() takes those values from the
  // members and does not fill the per-particle arrays: the steps of a heap of two such members
  // on the ground against a moving box (impacts, resting and sliding contacts, colliders, warm
  // starts over several steps) must be those of the arrays, to the bit.
  const double h = 1.0 / 240;
  const std::vector<detail::Collider> cols = ground_and_moving_box();
  Rng rng(23);
  const std::size_t sizes[2] = {900, 1600};
  detail::ParticleStore stores[2][2];  // [path][member]
  for (int mi = 0; mi < 2; ++mi) {
    detail::ParticleStore& s = stores[0][mi];
    s.append(sizes[mi]);
    for (std::size_t i = 0; i < sizes[mi]; ++i) {
      for (int a = 0; a < 3; ++a) {
        s.position[3 * i + std::size_t(a)] = float(a == 2 ? rng.uniform(0.004, 0.12) : rng.uniform(-0.15, 0.15));
        s.velocity[3 * i + std::size_t(a)] = float(rng.uniform(-0.4, 0.4));
      }
      s.radius[i] = float(rng.uniform(0.006, 0.011));
      s.mass[i] = float(rng.uniform(1e-3, 3e-3));
      s.age[i] = float(i % 7 == 0 ? 0.5 * h : 1.0);
      s.id[i] = std::uint32_t(i);
    }
    stores[1][mi] = s;
  }
  detail::ParticleCollider pc[2];
  pc[1].uniform_surface = false;
  for (int path = 0; path < 2; ++path) {
    const std::vector<detail::ParticleGroupMember> members{{&stores[path][0], 0.3, 0.4, true, 0, false, 9.81},
                                                           {&stores[path][1], 0.3, 0.4, true, 1, false, 9.81}};
    for (int step = 0; step < 4; ++step) pc[path].run(members, 0.05, h, &cols);
  }
  ASSERT_GT(pc[0].contacts.size(), 3000u);
  ASSERT_EQ(pc[0].restitution.size(), 0u) << "the alike members' run filled the arrays";
  ASSERT_EQ(pc[1].restitution.size(), sizes[0] + sizes[1]);
  for (int mi = 0; mi < 2; ++mi)
    for (std::size_t k = 0; k < 3 * sizes[mi]; ++k) {
      ASSERT_EQ(stores[0][mi].position[k], stores[1][mi].position[k]) << "member " << mi << " entry " << k;
      ASSERT_EQ(stores[0][mi].velocity[k], stores[1][mi].velocity[k]) << "member " << mi << " entry " << k;
    }
}

TEST(SimParticleCollision, PairOfTwoSystemsTakesTheirMeanRestitution) {
  // Two particles of systems with restitution 0.9 and 0.1 meet head on: the pair's coefficient
  // is the mean, 0.5, so equal masses closing at 2 m/s part at 1 m/s (§3.6.1, v_n' = -e v_n).
  const double r = 0.01, h = 1.0 / 240;
  detail::ParticleStore stores[2];
  for (int mi = 0; mi < 2; ++mi) {
    detail::ParticleStore& s = stores[mi];
    s.append(1);
    s.position[0] = float(mi == 0 ? -0.009 : 0.009);  // overlapping by 2 mm at the end of the step
    s.position[1] = s.position[2] = 0.0f;
    s.velocity[0] = float(mi == 0 ? 1.0 : -1.0);
    s.velocity[1] = s.velocity[2] = 0.0f;
    s.radius[0] = float(r);
    s.mass[0] = 1e-3f;
    s.age[0] = 1.0f;
    s.id[0] = 0;
  }
  const std::vector<detail::ParticleGroupMember> members{{&stores[0], 0.9, 0.2, true, 0},
                                                         {&stores[1], 0.1, 0.2, true, 1}};
  detail::ParticleCollider pc;
  pc.run(members, 0.05, h, nullptr);
  ASSERT_EQ(pc.contacts.size(), 1u);
  EXPECT_NEAR(stores[1].velocity[0] - stores[0].velocity[0], 1.0, 1e-6);
  EXPECT_NEAR(stores[0].velocity[0] + stores[1].velocity[0], 0.0, 1e-6);  // momentum
}

// A step finds each contact's warm start (the previous step's impulses) through the working index
// its particle had then while the stores hold the same particles in the same places (births
// after them allowed), and by key otherwise (after a restore, or once particles died or a birth
// moved others). The two lookups must give the same impulses: a heap of two systems in one group
// settling on a plane (resting pairs within and across the systems, resting collider contacts,
// friction), with beads born now and then into the second system (after every particle: by
// place) and the first (moving the second's: by key), stepped on, against the same heap saved
// and restored into a fresh world before every step (its caches come back in key order), bit for
// bit; likewise a system large enough for the threads' split, on one thread and on two.
TEST(SimParticleCollision, WarmStartByPlaceGivesTheImpulsesOfTheLookupByKey) {
  struct Heap {
    World world;
    ParticleSystemHandle a, b;
    /// Every 10th step three beads are born over the heap into the second system, every 25th
    /// into the first.
    void births(int step) {
      if (step % 10 != 9 && step % 25 != 24) return;
      for (int k = 0; k < 3; ++k)
        world.spawn_particle(step % 25 == 24 ? a : b, Vec3(0.1 + 0.03 * k, 0.1, 0.09), Vec3(0.0, 0.0, -0.5), 1e-3,
                             0.01, 100.0);
    }
    explicit Heap(int per_side, int layers, int threads) : world(WorldDef{1.0 / 240, 3, 0.05, threads}) {
      PlaneDef ground;
      ground.material = Material(0.2, 0.6);
      world.add_plane(ground);
      ParticleSystemDef def = test::spawn_only_system();
      def.emitter.max_particles = std::size_t(per_side * per_side * layers);
      def.collide_particles = false;
      def.collision_group = "heap";
      def.particle_restitution = 0.1;
      def.particle_friction = 0.5;
      a = world.add_particle_system(def);
      b = world.add_particle_system(def);
      Rng rng(11);
      for (int k = 0; k < layers; ++k)
        for (int i = 0; i < per_side; ++i)
          for (int j = 0; j < per_side; ++j) {
            const Vec3 at(0.0205 * i + rng.uniform(-0.002, 0.002), 0.0205 * j + rng.uniform(-0.002, 0.002),
                          0.0105 + 0.0205 * k);
            // The systems' particles alternate along x, so the heap's pairs cross them.
            world.spawn_particle(i % 2 == 0 ? a : b, at, Vec3(0.0, 0.0, -0.2), 1e-3, 0.01, 100.0);
          }
    }
  };
  const auto compare = [](int per_side, int layers, int steps, int threads_a, int threads_b) {
    Heap a(per_side, layers, threads_a);
    std::string state;
    a.world.save_state(state);
    for (int s = 0; s < steps; ++s) {
      a.births(s);
      a.world.advance(1.0 / 240);
      Heap fresh(per_side, layers, threads_b);
      fresh.world.load_state(state);
      fresh.births(s);
      fresh.world.advance(1.0 / 240);
      state.clear();
      fresh.world.save_state(state);
      ASSERT_EQ(a.world.state_hash(), fresh.world.state_hash())
          << "step " << s + 1 << ", " << per_side << " x " << per_side << " x " << layers;
    }
  };
  compare(20, 3, 90, 1, 1);    // 1,200 particles, 3/8 s: settled onto the plane and each other
  compare(60, 5, 6, 1, 2);     // 18,000: over kParallelMin, bands and the threads' split
}

}  // namespace
}  // namespace simreel::sim
