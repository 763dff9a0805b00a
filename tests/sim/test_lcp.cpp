// Dantzig's LCP algorithm (Baraff 1994; Coutinho App. G.2) on hand-solvable and random
// problems, and the sequential-impulse solver checked against it.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <vector>

#include "rigid/lcp.hpp"
#include "rigid_scene.hpp"

namespace simreel::sim::detail {
namespace {

using test::RigidScene;

void expect_complementary(const MatX& A, const VecX& b, const LcpResult& r, double tol) {
  ASSERT_TRUE(r.solved);
  EXPECT_LE((A * r.f + b - r.a).cwiseAbs().maxCoeff(), tol);
  EXPECT_GE(r.f.minCoeff(), -tol);
  EXPECT_GE(r.a.minCoeff(), -tol);
  EXPECT_LE(r.f.cwiseProduct(r.a).cwiseAbs().maxCoeff(), tol);
}

TEST(Lcp, HandSolvedOneTwoThreeContacts) {
  MatX A1(1, 1);
  A1 << 2.0;
  VecX b1(1);
  b1 << -4.0;
  LcpResult r = solve_lcp_dantzig(A1, b1);
  EXPECT_NEAR(r.f[0], 2.0, 1e-15);
  b1 << 3.0;  // separating: no force
  r = solve_lcp_dantzig(A1, b1);
  EXPECT_EQ(r.f[0], 0.0);
  EXPECT_EQ(r.a[0], 3.0);

  MatX A2(2, 2);
  A2 << 2.0, 1.0, 1.0, 2.0;
  VecX b2(2);
  b2 << -1.0, -1.0;  // both pushing: f = A⁻¹(-b) = (1/3, 1/3)
  r = solve_lcp_dantzig(A2, b2);
  EXPECT_NEAR(r.f[0], 1.0 / 3.0, 1e-15);
  EXPECT_NEAR(r.f[1], 1.0 / 3.0, 1e-15);
  b2 << -1.0, 2.0;  // the second separates: f = (1/2, 0), a = (0, 2.5)
  r = solve_lcp_dantzig(A2, b2);
  EXPECT_NEAR(r.f[0], 0.5, 1e-15);
  EXPECT_EQ(r.f[1], 0.0);
  EXPECT_NEAR(r.a[1], 2.5, 1e-15);
  b2 << 0.5, -2.0;  // the first must let go after the second pushes: f = (0, 1), a = (1.5, 0)
  r = solve_lcp_dantzig(A2, b2);
  EXPECT_EQ(r.f[0], 0.0);
  EXPECT_NEAR(r.f[1], 1.0, 1e-15);
  EXPECT_NEAR(r.a[0], 1.5, 1e-15);

  MatX A3(3, 3);
  A3 << 4.0, 1.0, 0.0, 1.0, 3.0, 1.0, 0.0, 1.0, 2.0;
  VecX b3(3);
  b3 << -2.0, 1.0, -1.0;  // C = {0, 2}: f = (0.5, 0, 0.5), a_1 = 1 + 0.5 + 0.5 = 2
  r = solve_lcp_dantzig(A3, b3);
  EXPECT_NEAR(r.f[0], 0.5, 1e-15);
  EXPECT_EQ(r.f[1], 0.0);
  EXPECT_NEAR(r.f[2], 0.5, 1e-15);
  EXPECT_NEAR(r.a[1], 2.0, 1e-15);
  expect_complementary(A3, b3, r, 1e-14);
}

TEST(Lcp, RandomPositiveDefiniteProblemsAreComplementary) {
  std::mt19937_64 gen(7);
  std::normal_distribution<double> nd;  // test data only; results are checked, not compared
  int pivots = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 1 + trial % 16;
    MatX M(n + 2, n);
    for (int i = 0; i < M.size(); ++i) M.data()[i] = nd(gen);
    const MatX A = M.transpose() * M + 1e-3 * MatX::Identity(n, n);
    VecX b(n);
    for (int i = 0; i < n; ++i) b[i] = nd(gen);
    const LcpResult r = solve_lcp_dantzig(A, b);
    expect_complementary(A, b, r, 1e-10);
    pivots += r.pivots;
  }
  std::printf("[ figures  ] 200 random PD LCPs (n = 1..16): %d pivots in all\n", pivots);
}

TEST(Lcp, SingularPsdProblemWithRedundantContacts) {
  // Rank 2 with 4 unknowns (like 4 coplanar contacts): solvable, any solution complementary.
  MatX J(2, 4);
  J << 1.0, 1.0, 1.0, 1.0, 1.0, -1.0, 1.0, -1.0;
  const MatX A = J.transpose() * J;
  VecX b(4);
  b << -1.0, -1.0, -1.0, -1.0;
  const LcpResult r = solve_lcp_dantzig(A, b);
  expect_complementary(A, b, r, 1e-12);
}

/// The LCP of the scene's current contacts (frictionless rows): A_ij = change of the relative
/// normal velocity at i per unit normal impulse at j, measured by applying impulses to a copy of
/// the bodies (independent of the solver's own code); b = the current relative normal velocities.
void contact_lcp(const RigidBodies& bodies, const std::vector<ContactPoint>& cs, MatX& A, VecX& b) {
  const auto n = static_cast<Eigen::Index>(cs.size());
  auto normal_velocities = [&](const RigidBodies& bs) {
    VecX v(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const ContactPoint& c = cs[std::size_t(i)];
      v[i] = relative_velocity(bs, c.body_a, c.body_b, c.point).dot(c.normal);
    }
    return v;
  };
  b = normal_velocities(bodies);
  A.resize(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    RigidBodies copy = bodies;
    const ContactPoint& c = cs[std::size_t(j)];
    if (c.body_a != kStaticBody) apply_impulse_at(copy, c.body_a, -c.normal, c.point);
    if (c.body_b != kStaticBody) apply_impulse_at(copy, c.body_b, c.normal, c.point);
    A.col(j) = normal_velocities(copy) - b;
  }
}

/// Runs the solver's velocity sweeps on the scene's contacts after the velocity half step until
/// the largest impulse change is below rel_tol × the largest impulse; returns the sweeps used
/// (capped at max_sweeps) and leaves the impulses in `s.contacts`.
int solve_until_converged(RigidScene& s, double h, double rel_tol, int max_sweeps,
                          MatX* A = nullptr, VecX* b = nullptr) {
  s.solver.prepare(s.bodies, s.contacts, h);
  apply_gravity(s.bodies, s.gravity);
  integrate_velocities(s.bodies, h);
  clear_forces(s.bodies);
  if (A != nullptr) contact_lcp(s.bodies, s.contacts, *A, *b);
  s.solver.warm_start(s.bodies, s.contacts);
  for (int sweep = 1; sweep <= max_sweeps; ++sweep) {
    const double change = s.solver.iterate_velocities(s.bodies, s.contacts);
    double largest = 0.0;
    for (const ContactPoint& c : s.contacts) largest = std::max(largest, c.normal_impulse);
    if (change <= rel_tol * largest) return sweep;
  }
  return max_sweeps;
}

TEST(LcpVsSolver, BoxOnGroundNetImpulseMatchesLcp) {
  // 4 coplanar contacts: A has rank 3, so the individual impulses are not unique (any
  // redistribution along the null space of Jᵀ solves the LCP); A f + b (the contact velocities)
  // and the net impulse and moment Jᵀ f are, and those are compared.
  RigidScene s;
  s.friction = 0.0;
  s.add_ground();
  const Vec3 half(0.5, 0.3, 0.2);
  s.add(ConvexShape::box(half), 500.0, Vec3(0.0, 0.0, half.z() - 0.0005),
        Quat(Eigen::AngleAxisd(0.3, Vec3::UnitZ())), Vec3(0.0, 0.0, -0.2));
  s.bodies.angular_velocity[1] = Vec3(0.1, -0.2, 0.0);  // uneven load
  s.bodies.angular_momentum[1] = world_inertia(s.bodies, 1) * s.bodies.angular_velocity[1];
  s.find_contacts();
  ASSERT_EQ(s.contacts.size(), 4u);
  MatX A;
  VecX b;
  const int sweeps = solve_until_converged(s, 1.0 / 240.0, 1e-12, 5000, &A, &b);
  const LcpResult lcp = solve_lcp_dantzig(A, b);
  ASSERT_TRUE(lcp.solved);
  VecX f(4);
  Vec3 P_si = Vec3::Zero(), M_si = Vec3::Zero(), P_lcp = Vec3::Zero(), M_lcp = Vec3::Zero();
  for (int i = 0; i < 4; ++i) {
    const ContactPoint& c = s.contacts[std::size_t(i)];
    f[i] = c.normal_impulse;
    const Vec3 r = c.point - s.bodies.position[1];
    P_si += f[i] * c.normal;
    M_si += r.cross(f[i] * c.normal);
    P_lcp += lcp.f[i] * c.normal;
    M_lcp += r.cross(lcp.f[i] * c.normal);
  }
  std::printf("[ figures  ] box: SI %d sweeps; impulses SI (%.4f %.4f %.4f %.4f), LCP (%.4f %.4f "
              "%.4f %.4f)\n", sweeps, f[0], f[1], f[2], f[3], lcp.f[0], lcp.f[1], lcp.f[2],
              lcp.f[3]);
  EXPECT_LE((P_si - P_lcp).norm(), 1e-6 * P_lcp.norm());
  EXPECT_LE((M_si - M_lcp).norm(), 1e-6 * P_lcp.norm() * half.norm());
  EXPECT_LE((A * f + b - lcp.a).cwiseAbs().maxCoeff(), 1e-6 * b.cwiseAbs().maxCoeff());
}

TEST(LcpVsSolver, ThreeBoxStackImpulsesMatchLcp) {
  // Line contacts (2 points per face, along x) keep A positive definite, so the impulses are
  // unique and compared one by one.
  RigidScene s;
  s.friction = 0.0;
  s.add_ground();
  const Vec3 half(0.4, 0.3, 0.2);
  s.add_box_stack(3, half, 300.0, 200.0);
  s.bodies.linear_velocity[3] = Vec3(0.0, 0.0, -0.1);
  s.bodies.angular_velocity[2] = Vec3(0.0, 0.3, 0.0);
  s.bodies.angular_momentum[2] = world_inertia(s.bodies, 2) * s.bodies.angular_velocity[2];
  for (int k = 0; k < 3; ++k)
    for (const double x : {-half.x(), half.x()}) {
      ContactPoint c;
      c.body_a = k == 0 ? kStaticBody : std::uint32_t(k);
      c.body_b = std::uint32_t(k + 1);
      c.point = Vec3(x, 0.0, 2.0 * half.z() * k);
      s.contacts.push_back(c);
    }
  MatX A;
  VecX b;
  const int sweeps = solve_until_converged(s, 1.0 / 240.0, 1e-13, 20000, &A, &b);
  const LcpResult lcp = solve_lcp_dantzig(A, b);
  ASSERT_TRUE(lcp.solved);
  for (std::size_t i = 0; i < s.contacts.size(); ++i)
    EXPECT_NEAR(s.contacts[i].normal_impulse, lcp.f[Eigen::Index(i)], 1e-6 * lcp.f.maxCoeff())
        << "contact " << i;
  std::printf("[ figures  ] 3-box stack (6 contacts): SI %d sweeps to 1e-13; LCP %d pivots\n",
              sweeps, lcp.pivots);
}

TEST(LcpVsSolver, SoftStepRelaxSweepsMatchLcpOnAThreeBoxStack) {
  // The soft step's relax sweeps (solve_soft without bias, contacts touching) are sequential
  // impulses on the substep's velocities: iterated, they reach the App. G LCP's impulses.
  RigidScene s;
  s.friction = 0.0;
  s.add_ground();
  const Vec3 half(0.4, 0.3, 0.2);
  s.add_box_stack(3, half, 300.0, 200.0);
  s.bodies.linear_velocity[3] = Vec3(0.0, 0.0, -0.1);
  s.bodies.angular_velocity[2] = Vec3(0.0, 0.3, 0.0);
  s.bodies.angular_momentum[2] = world_inertia(s.bodies, 2) * s.bodies.angular_velocity[2];
  for (int k = 0; k < 3; ++k)
    for (const double x : {-half.x(), half.x()}) {
      ContactPoint c;
      c.body_a = k == 0 ? kStaticBody : std::uint32_t(k);
      c.body_b = std::uint32_t(k + 1);
      c.point = Vec3(x, 0.0, 2.0 * half.z() * k);
      s.contacts.push_back(c);
    }
  const double h = 1.0 / 240.0;
  s.solver.prepare_soft(s.bodies, s.contacts, h);
  apply_gravity(s.bodies, s.gravity);
  integrate_velocities(s.bodies, h);
  clear_forces(s.bodies);
  MatX A;
  VecX b;
  contact_lcp(s.bodies, s.contacts, A, b);
  s.solver.warm_start_soft(s.bodies, s.contacts);
  for (int sweep = 0; sweep < 20000; ++sweep) s.solver.solve_soft(s.bodies, s.contacts, false);
  const LcpResult lcp = solve_lcp_dantzig(A, b);
  ASSERT_TRUE(lcp.solved);
  for (std::size_t i = 0; i < s.contacts.size(); ++i)
    EXPECT_NEAR(s.contacts[i].normal_impulse, lcp.f[Eigen::Index(i)], 1e-6 * lcp.f.maxCoeff())
        << "contact " << i;
}

TEST(LcpVsSolver, WarmStartingConvergesInFewerSweeps) {
  // A settled 3-box stack with 4 corner contacts per face: count the sweeps one step needs to
  // converge to 1e-6 with the previous step's impulses as the start, and from zero.
  RigidScene s;
  s.friction = 0.6;
  s.add_ground();
  s.add_box_stack(3, Vec3(0.4, 0.4, 0.2), 400.0);
  for (int i = 0; i < 480; ++i) s.step(1.0 / 240.0);
  s.find_contacts();
  RigidScene cold = s;
  cold.solver.settings().warm_start = false;
  const int warm_sweeps = solve_until_converged(s, 1.0 / 240.0, 1e-6, 1000);
  const int cold_sweeps = solve_until_converged(cold, 1.0 / 240.0, 1e-6, 1000);
  std::printf("[ figures  ] 3-box stack, %zu contacts: sweeps to 1e-6: warm %d, cold %d\n",
              s.contacts.size(), warm_sweeps, cold_sweeps);
  EXPECT_LT(warm_sweeps, cold_sweeps);
  EXPECT_LE(warm_sweeps, 3);
}

}  // namespace
}  // namespace simreel::sim::detail
