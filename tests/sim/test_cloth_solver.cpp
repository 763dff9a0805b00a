// The cloth's implicit solver: the two-level preconditioner's coarse level (cloth/coarse_space)
// checked against the explicit Galerkin product, its aggregates, and what it buys the implicit
// Euler step at the default CG tolerance (issue 16).
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <random>
#include <vector>

#include "cloth/aero.hpp"
#include "cloth/coarse_space.hpp"
#include "cloth/spring_stencil.hpp"
#include "simreel/sim/world.hpp"

namespace {

using namespace simreel::sim;
using detail::CoarseSpace;
using detail::SpringStencil;
using detail::Sym3;

std::vector<std::uint8_t> free_but_two_corners(const ClothTopology& t) {
  std::vector<std::uint8_t> free(t.vertex_count(), 1);
  free[0] = free[t.columns - 1] = 0;
  return free;
}

// Every free vertex is in one aggregate and every aggregate is a connected patch of the stretch
// springs; a 64 x 64 grid gets patches of tens of vertices; a cloth too small gets none.
TEST(ClothCoarseSpace, AggregatesAreConnectedPatchesOfTheFreeVertices) {
  const ClothTopology t(64, 64, 1.0, 1.0);
  const auto free = free_but_two_corners(t);
  CoarseSpace c;
  c.build(t, free);
  ASSERT_FALSE(c.empty());
  const std::size_t m = c.aggregate_count();
  std::vector<std::vector<std::uint32_t>> members(m);
  for (std::size_t i = 0; i < t.vertex_count(); ++i) {
    const std::int32_t a = c.aggregate_of(i);
    if (!free[i]) {
      EXPECT_EQ(a, -1) << "pinned vertex " << i;
      continue;
    }
    ASSERT_GE(a, 0) << "free vertex " << i;
    ASSERT_LT(std::size_t(a), m);
    members[std::size_t(a)].push_back(std::uint32_t(i));
  }
  std::size_t smallest = t.vertex_count(), largest = 0;
  for (std::size_t a = 0; a < m; ++a) {
    ASSERT_FALSE(members[a].empty()) << "aggregate " << a;
    smallest = std::min(smallest, members[a].size());
    largest = std::max(largest, members[a].size());
    // Flood fill over the stretch springs inside the aggregate reaches all its members.
    std::vector<std::uint8_t> seen(t.vertex_count(), 0);
    std::deque<std::uint32_t> todo{members[a][0]};
    seen[members[a][0]] = 1;
    std::size_t reached = 0;
    while (!todo.empty()) {
      const std::uint32_t i = todo.front();
      todo.pop_front();
      ++reached;
      for (std::uint32_t k = t.adj_start[i]; k < t.adj_start[i + 1]; ++k) {
        const std::uint32_t j = t.adj_other[k];
        if (t.kind[t.adj_spring[k]] == SpringKind::stretch && !seen[j] &&
            c.aggregate_of(j) == std::int32_t(a)) {
          seen[j] = 1;
          todo.push_back(j);
        }
      }
    }
    EXPECT_EQ(reached, members[a].size()) << "aggregate " << a << " is not connected";
  }
  const double mean = double(t.vertex_count() - 2) / double(m);
  std::printf("64 x 64: %zu aggregates, %zu..%zu vertices, mean %.1f\n", m, smallest, largest, mean);
  EXPECT_GE(mean, 20.0);
  EXPECT_LE(mean, 100.0);
  EXPECT_GE(smallest, 2u);

  CoarseSpace tiny;
  const ClothTopology small(12, 12, 1.0, 1.0);  // 144 vertices: block Jacobi alone
  tiny.build(small, free_but_two_corners(small));
  EXPECT_TRUE(tiny.empty());
}

// z += P A_c⁻¹ Pᵀ r equals the same product formed densely: A from its blocks, P from the
// aggregates, A_c = Pᵀ A P solved by a dense Cholesky.
TEST(ClothCoarseSpace, CorrectionIsTheDenseGalerkinSolve) {
  const ClothTopology t(20, 20, 1.0, 1.0);
  const std::size_t n = t.vertex_count(), ns = t.spring_count();
  const auto free = free_but_two_corners(t);
  CoarseSpace c;
  c.build(t, free);
  ASSERT_FALSE(c.empty());
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0), pos(0.0, 1.0);
  std::vector<Sym3> S(ns), aero(n);
  std::vector<double> len(ns, 0.02);
  len[5] = 0.0;  // a degenerate spring is left out, as the product leaves it out
  for (std::size_t s = 0; s < ns; ++s) {
    const Vec3 dir = Vec3(u(rng), u(rng), u(rng)).normalized();
    S[s] = Sym3::outer(dir, 10.0 * pos(rng));
    S[s].add_diagonal(pos(rng));
  }
  for (std::size_t i = 0; i < n; ++i) aero[i] = Sym3::outer(Vec3(u(rng), u(rng), u(rng)), 0.5);
  const double diag_m = 0.3, h = 0.01;
  ASSERT_TRUE(c.factorize(diag_m, aero.data(), h, S.data(), len.data()));

  const auto N = Eigen::Index(3 * n), M = Eigen::Index(3 * c.aggregate_count());
  const auto dense = [](const Sym3& b) {
    Eigen::Matrix3d d;
    d << b.xx, b.xy, b.xz, b.xy, b.yy, b.yz, b.xz, b.yz, b.zz;
    return d;
  };
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(N, N), P = Eigen::MatrixXd::Zero(N, M);
  for (std::size_t i = 0; i < n; ++i) {
    if (!free[i]) continue;
    A.block<3, 3>(3 * i, 3 * i) += diag_m * Eigen::Matrix3d::Identity() + h * dense(aero[i]);
    P.block<3, 3>(3 * i, 3 * c.aggregate_of(i)) = Eigen::Matrix3d::Identity();
  }
  for (std::size_t s = 0; s < ns; ++s) {
    if (!(len[s] > 0.0)) continue;
    const std::uint32_t a = t.spring_a[s], b = t.spring_b[s];
    const Eigen::Matrix3d B = dense(S[s]);
    if (free[a]) A.block<3, 3>(3 * a, 3 * a) += B;
    if (free[b]) A.block<3, 3>(3 * b, 3 * b) += B;
    if (free[a] && free[b]) {
      A.block<3, 3>(3 * a, 3 * b) -= B;
      A.block<3, 3>(3 * b, 3 * a) -= B;
    }
  }
  std::vector<Vec3> r(n), z(n, Vec3::Zero());
  Eigen::VectorXd rv = Eigen::VectorXd::Zero(N);
  for (std::size_t i = 0; i < n; ++i) {
    r[i] = free[i] ? Vec3(u(rng), u(rng), u(rng)) : Vec3::Zero();
    rv.segment<3>(3 * Eigen::Index(i)) = r[i];
  }
  const Eigen::MatrixXd Ac = P.transpose() * A * P;
  const Eigen::VectorXd expected = P * Ac.llt().solve(P.transpose() * rv);
  // Structure of arrays, as the solver holds its vectors: x, y, z components n apart.
  std::vector<double> rs(3 * n), zs(3 * n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t k = 0; k < 3; ++k) rs[k * n + i] = r[i][Eigen::Index(k)];
  c.apply_add(rs.data(), zs.data(), n);
  for (std::size_t i = 0; i < n; ++i) z[i] = Vec3(zs[i], zs[n + i], zs[2 * n + i]);
  double err = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    err = std::max(err, (z[i] - Vec3(expected.segment<3>(3 * Eigen::Index(i)))).cwiseAbs().maxCoeff());
  EXPECT_LT(err, 1e-9 * expected.cwiseAbs().maxCoeff()) << "largest difference " << err;
}

// The stencil product (cloth/spring_stencil) against the spring-by-spring sum it replaces:
// random blocks, a random diagonal, some pinned rows, on grids whose classes and padding differ
// (rectangular; one row; one column; 3 x 3, where the shear offset columns - 1 = 2 is the bend
// offset), at 1 and 2 threads (the same bits).
TEST(ClothStencil, GridProductIsTheSpringBySpringProduct) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto random_sym = [&] {
    const Vec3 d = Vec3(u(rng), u(rng), u(rng));
    Sym3 m = Sym3::outer(d, 2.0);
    m.add_diagonal(0.5 + 0.5 * u(rng));
    return m;
  };
  struct Size {
    std::size_t rows, columns, classes;
  };
  for (const Size sz : {Size{17, 23, 6}, Size{1, 40, 2}, Size{40, 1, 2}, Size{3, 3, 5}}) {
    const ClothTopology t(sz.rows, sz.columns, 1.0, 1.0);
    SpringStencil st;
    st.build(t, {}, {});
    ASSERT_EQ(st.class_count(), sz.classes) << sz.rows << " x " << sz.columns;
    const std::size_t n = t.vertex_count(), ns = t.spring_count(), S = st.stride(), P = st.pad();
    ASSERT_GE(S, n + 2 * P);
    // Blocks q qᵀ + β I, some springs left out (zero blocks).
    std::vector<Sym3> blocks(ns), diag(n);
    for (std::size_t s = 0; s < ns; ++s) {
      const bool out = s % 7 == 3;
      const Vec3 q = out ? Vec3::Zero() : Vec3(u(rng), u(rng), u(rng));
      const double beta = out ? 0.0 : 0.5 + 0.5 * u(rng);
      blocks[s] = Sym3::outer(q, 1.0);
      blocks[s].add_diagonal(beta);
      st.set(s, q, beta);
    }
    std::vector<double> y(3 * S, 0.0), dg(6 * S, 0.0), out(3 * S, 0.0), mask(n), yAy(n);
    std::vector<Vec3> yv(n);
    for (std::size_t i = 0; i < n; ++i) {
      diag[i] = random_sym();
      const double d[6] = {diag[i].xx, diag[i].xy, diag[i].xz, diag[i].yy, diag[i].yz, diag[i].zz};
      for (std::size_t k = 0; k < 6; ++k) dg[k * S + P + i] = d[k];
      mask[i] = i % 5 == 0 ? 0.0 : 1.0;
      yv[i] = Vec3(u(rng), u(rng), u(rng));
      for (std::size_t k = 0; k < 3; ++k) y[k * S + P + i] = yv[i][Eigen::Index(k)];
    }
    // Reference: each spring's S (y_a - y_b) added at a and subtracted at b.
    std::vector<Vec3> ref(n);
    for (std::size_t i = 0; i < n; ++i) ref[i] = diag[i] * yv[i];
    for (std::size_t s = 0; s < ns; ++s) {
      const Vec3 w = blocks[s] * Vec3(yv[t.spring_a[s]] - yv[t.spring_b[s]]);
      ref[t.spring_a[s]] += w;
      ref[t.spring_b[s]] -= w;
    }
    std::vector<double> first;
    for (const int threads : {1, 2}) {
      st.apply(y.data() + P, dg.data() + P, mask.data(), out.data() + P, yAy.data(), threads);
      double err = 0.0, scale = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        const Vec3 o(out[P + i], out[S + P + i], out[2 * S + P + i]);
        const Vec3 expect = mask[i] * ref[i];
        err = std::max(err, (o - expect).cwiseAbs().maxCoeff());
        scale = std::max(scale, ref[i].cwiseAbs().maxCoeff());
        EXPECT_NEAR(yAy[i], yv[i].dot(expect), 1e-12 * (1.0 + std::abs(yv[i].dot(expect))));
      }
      EXPECT_LT(err, 1e-13 * scale) << sz.rows << " x " << sz.columns << ", " << threads
                                    << " threads: largest difference " << err;
      if (threads == 1) first = out;
      else EXPECT_TRUE(first == out) << "2 threads changed the bits";
    }
    // assemble(): each vertex's inverse diagonal block D_i + Σ S_s and its right-hand side
    // h f_i + Σ ±w_s, zero at pinned vertices.
    std::vector<Vec3> w(ns), f(n), bref(n);
    std::vector<double> fs(3 * S, 0.0);
    std::vector<Sym3> Pref(diag);
    const double h = 0.02;
    for (std::size_t i = 0; i < n; ++i) {
      f[i] = Vec3(u(rng), u(rng), u(rng));
      for (std::size_t k = 0; k < 3; ++k) fs[k * S + P + i] = f[i][Eigen::Index(k)];
      bref[i] = h * f[i];
    }
    for (std::size_t s = 0; s < ns; ++s) {
      w[s] = Vec3(u(rng), u(rng), u(rng));
      st.set_rhs(s, w[s]);
      for (const std::uint32_t e : {t.spring_a[s], t.spring_b[s]}) Pref[e] += blocks[s];
      bref[t.spring_a[s]] += w[s];
      bref[t.spring_b[s]] -= w[s];
    }
    std::vector<double> pc(6 * S, 0.0), b(3 * S, 0.0);
    st.assemble(dg.data() + P, mask.data(), h, fs.data() + P, pc.data() + P, b.data() + P, 1);
    for (std::size_t i = 0; i < n; ++i) {
      const Sym3 inv = Pref[i].inverse();
      const double e[6] = {inv.xx, inv.xy, inv.xz, inv.yy, inv.yz, inv.zz};
      for (std::size_t k = 0; k < 6; ++k)
        EXPECT_NEAR(pc[k * S + P + i], mask[i] * e[k], 1e-12 * (1.0 + std::abs(e[k])))
            << "vertex " << i << " entry " << k;
      for (std::size_t k = 0; k < 3; ++k)
        EXPECT_NEAR(b[k * S + P + i], mask[i] * bref[i][Eigen::Index(k)], 1e-13)
            << "vertex " << i << " component " << k;
    }
  }
}

// The stencil's spring forces, blocks and right-hand side against the plain per-spring formulas
// (Coutinho §3.9.2; Baraff & Witkin 1998, eq. 6): a perturbed 13 x 9 grid with springs
// stretched and compressed (the transverse term only when stretched), a few springs stored
// high index first and one of length 0 (no force, no block), at 1 and 2 threads.
TEST(ClothStencil, ForcesAndBlocksAreTheSpringBySpringOnes) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ClothTopology t(13, 9, 1.2, 0.8);
  const std::size_t n = t.vertex_count(), ns = t.spring_count();
  for (std::size_t s = 0; s < ns; s += 5) std::swap(t.spring_a[s], t.spring_b[s]);
  std::vector<double> ks(ns), kds(ns);
  for (std::size_t s = 0; s < ns; ++s) {
    ks[s] = 500.0 * (1.5 + u(rng));
    kds[s] = 0.2 * (1.0 + u(rng));
  }
  std::vector<Vec3> x(n), v(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = Vec3(t.local_rest[i].x(), t.local_rest[i].y(), 0.0) * 1.05 +
           0.02 * Vec3(u(rng), u(rng), u(rng));
    v[i] = Vec3(u(rng), u(rng), u(rng));
  }
  const std::uint32_t z0 = t.spring_a[3], z1 = t.spring_b[3];
  x[z1] = x[z0];  // spring 3 has length 0
  SpringStencil st;
  st.build(t, ks, kds);
  ASSERT_FALSE(st.empty());
  const std::size_t S = st.stride(), P = st.pad();
  auto soa = [&](const std::vector<Vec3>& a) {
    std::vector<double> o(3 * S, 0.0);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t k = 0; k < 3; ++k) o[k * S + P + i] = a[i][Eigen::Index(k)];
    return o;
  };
  const std::vector<double> xs = soa(x), vs = soa(v);
  const double m = 0.01, c = 0.3, h = 1.0 / 60;
  const Vec3 g(0.1, -0.2, -9.81);
  // Reference, spring by spring.
  std::vector<Vec3> fref(n), bref(n, Vec3::Zero());
  std::vector<Sym3> Sref(ns), Dref(n);
  for (std::size_t i = 0; i < n; ++i) fref[i] = m * (g - c * v[i]);
  std::size_t stretched = 0, compressed = 0;
  for (std::size_t s = 0; s < ns; ++s) {
    const std::uint32_t a = t.spring_a[s], b = t.spring_b[s];
    const Vec3 d = x[b] - x[a];
    const double l = d.norm();
    if (!(l > 0.0)) continue;
    const Vec3 uu = d / l;
    const Vec3 F = (ks[s] * (l - t.rest_length[s]) + kds[s] * (v[b] - v[a]).dot(uu)) * uu;
    fref[a] += F;
    fref[b] -= F;
    const double tau = ks[s] * std::max(0.0, 1.0 - t.rest_length[s] / l);
    (tau > 0.0 ? stretched : compressed) += 1;
    Sref[s] = Sym3::outer(uu, h * h * (ks[s] - tau) + h * kds[s]);
    Sref[s].add_diagonal(h * h * tau);
    const Vec3 w = h * h * ((ks[s] - tau) * uu.dot(v[b] - v[a]) * uu + tau * (v[b] - v[a]));
    bref[a] += w;
    bref[b] -= w;
    Dref[a] += Sref[s];
    Dref[b] += Sref[s];
  }
  ASSERT_GT(stretched, 20u);
  ASSERT_GT(compressed, 20u);
  for (std::size_t i = 0; i < n; ++i) {
    bref[i] += h * fref[i];
    Dref[i].add_diagonal(m);
  }
  std::vector<double> first;
  for (const int threads : {1, 2}) {
    std::vector<double> fs(3 * S, 0.0);
    st.forces(xs.data() + P, vs.data() + P, m, g, c, fs.data() + P, threads);
    st.blocks(h, vs.data() + P, threads);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t k = 0; k < 3; ++k)
        ASSERT_NEAR(fs[k * S + P + i], fref[i][Eigen::Index(k)], 1e-11 * (1.0 + fref[i].norm()))
            << "force at vertex " << i << ", " << threads << " threads";
    for (std::size_t s = 0; s < ns; ++s) {
      const Sym3 b = st.block(s), r = Sref[s];
      const double e[6] = {b.xx - r.xx, b.xy - r.xy, b.xz - r.xz, b.yy - r.yy, b.yz - r.yz,
                           b.zz - r.zz};
      for (const double d : e) ASSERT_NEAR(d, 0.0, 1e-12) << "block of spring " << s;
    }
    EXPECT_EQ(st.length(3), 0.0);
    EXPECT_NEAR(st.length(0), (x[t.spring_b[0]] - x[t.spring_a[0]]).norm(), 1e-15);
    // The right-hand side and inverse diagonal blocks assembled from these (no pinned vertex).
    std::vector<double> dg(6 * S, 0.0), mask(n, 1.0), pc(6 * S, 0.0), bb(3 * S, 0.0);
    for (std::size_t i = 0; i < n; ++i)
      for (const std::size_t k : {0u, 3u, 5u}) dg[k * S + P + i] = m;
    st.assemble(dg.data() + P, mask.data(), h, fs.data() + P, pc.data() + P, bb.data() + P,
                threads);
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t k = 0; k < 3; ++k)
        ASSERT_NEAR(bb[k * S + P + i], bref[i][Eigen::Index(k)], 1e-12)
            << "right-hand side at vertex " << i << ", " << threads << " threads";
      const Sym3 inv = Dref[i].inverse();
      ASSERT_NEAR(pc[P + i], inv.xx, 1e-9 * std::abs(inv.xx)) << "vertex " << i;
      ASSERT_NEAR(pc[4 * S + P + i], inv.yz, 1e-9 * (std::abs(inv.xx) + std::abs(inv.yz)));
    }
    if (threads == 1) first = fs;
    else EXPECT_TRUE(first == fs) << "2 threads changed the forces' bits";
  }
}

// A grid has six spring offsets; springs of scattered offsets (a fan of triangles around a
// centre vertex) or two springs joining the same vertices leave the stencil empty.
TEST(ClothStencil, OnlyFewOffsetClassesTakeTheStencil) {
  ClothMesh fan;
  fan.vertices.push_back(Vec3::Zero());
  constexpr int kRim = 16;
  for (int k = 0; k < kRim; ++k) {
    const double a = 2.0 * 3.141592653589793 * k / kRim;
    fan.vertices.push_back(Vec3(std::cos(a), std::sin(a), 0.0));
  }
  for (std::uint32_t k = 0; k < kRim; ++k)
    fan.triangles.insert(fan.triangles.end(), {0, 1 + k, 1 + (k + 1) % kRim});
  SpringStencil st;
  st.build(ClothTopology(fan), {}, {});
  EXPECT_TRUE(st.empty());
  EXPECT_EQ(st.pad(), 0u);
  ClothTopology twice(8, 8, 1.0, 1.0);
  twice.spring_a.push_back(twice.spring_a[0]);
  twice.spring_b.push_back(twice.spring_b[0]);
  twice.rest_length.push_back(twice.rest_length[0]);
  twice.kind.push_back(twice.kind[0]);
  st.build(twice, {}, {});
  EXPECT_TRUE(st.empty());
}

// The aerodynamic force and damping block of each triangle (Coutinho §3.9.2's wind force with
// lift; aero.hpp) against the per-triangle formula written with Eigen, summed per vertex: the
// general loop over a triangle list and the grid loop by cell, at 1 and 2 threads. A 7 x 5 grid
// with a crumpled sheet (normals both ways to the wind), one triangle of zero area and one
// moving with the wind (still air): those two add nothing.
TEST(ClothAero, GridAndTriangleLoopsAreThePerTriangleFormula) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const ClothTopology t(7, 5, 1.0, 0.8);
  const std::size_t n = t.vertex_count(), C = t.columns, nt = t.triangles.size() / 3;
  const detail::AeroCoefficients k{1.225, 1.1, 0.6};
  const Vec3 wind(6.0, -2.0, 1.0);
  std::vector<Vec3> x(n), v(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = t.local_rest[i] + 0.08 * Vec3(u(rng), u(rng), u(rng));
    v[i] = 2.0 * Vec3(u(rng), u(rng), u(rng));
  }
  x[1] = x[0];  // triangle (0, 6, 1) of cell 0 has zero area
  v[C + 3] = v[2 * C + 4] = v[C + 4] = wind;  // cell (1, 3)'s first triangle: still air
  std::vector<Vec3> fref(n, Vec3::Zero());
  std::vector<Sym3> Dref(n);
  std::size_t live = 0, turned = 0;
  for (std::size_t k3 = 0; k3 < t.triangles.size(); k3 += 3) {
    const std::uint32_t i0 = t.triangles[k3], i1 = t.triangles[k3 + 1], i2 = t.triangles[k3 + 2];
    const Vec3 uu = wind - (v[i0] + v[i1] + v[i2]) / 3.0;
    Vec3 nrm = (x[i1] - x[i0]).cross(x[i2] - x[i0]);
    const double area2 = nrm.norm();
    if (!(uu.squaredNorm() > 0.0) || !(area2 > 0.0)) continue;
    ++live;
    nrm /= area2;
    const Vec3 uh = uu.normalized();
    double c = nrm.dot(uh);
    if (c < 0.0) {
      nrm = -nrm;
      c = -c;
      ++turned;
    }
    const double q = 0.5 * k.rho * uu.squaredNorm() * 0.5 * area2;
    Vec3 F = q * k.cd * c * nrm;
    const Vec3 l = nrm - c * uh;
    if (l.squaredNorm() > 1e-24) F += q * k.cl * c * l;
    const Sym3 D = Sym3::outer(nrm, q * k.cd / uu.norm() * (1.0 + c) / 3.0);
    for (const std::uint32_t i : {i0, i1, i2}) {
      fref[i] += F / 3.0;
      Dref[i] += D;
    }
  }
  ASSERT_EQ(live, nt - 2);
  ASSERT_GT(turned, 3u);
  ASSERT_LT(turned, live - 3);
  // The layout the grid loop needs: columns + 1 of padding on both sides.
  const std::size_t P = C + 1, S = n + 2 * P;
  std::vector<double> xs(3 * S, 0.0), vs(3 * S, 0.0), winds(6 * S, 0.0), cells(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t e = 0; e < 3; ++e) {
      xs[e * S + P + i] = x[i][Eigen::Index(e)];
      vs[e * S + P + i] = v[i][Eigen::Index(e)];
      winds[e * S + P + i] = winds[(3 + e) * S + P + i] = wind[Eigen::Index(e)];
    }
  for (std::size_t r = 0; r + 1 < t.rows; ++r)
    for (std::size_t c = 0; c + 1 < C; ++c) cells[r * C + c] = 1.0;
  auto check = [&](const double* f, std::size_t fs, const double* D, std::size_t ds,
                   const char* what) {
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t e = 0; e < 3; ++e)
        ASSERT_NEAR(f[e * fs + i], fref[i][Eigen::Index(e)], 1e-13) << what << ", vertex " << i;
      const double d[6] = {Dref[i].xx, Dref[i].xy, Dref[i].xz, Dref[i].yy, Dref[i].yz, Dref[i].zz};
      for (std::size_t e = 0; e < 6; ++e)
        ASSERT_NEAR(D[e * ds + i], d[e], 1e-13) << what << ", block entry " << e << " at " << i;
    }
  };
  std::vector<double> first;
  for (const int threads : {1, 2}) {
    std::vector<double> work(18 * S, 0.0), f(3 * S, 0.0), D(6 * S, 0.0);
    detail::aero_grid(t.rows, C, xs.data() + P, vs.data() + P, std::ptrdiff_t(S),
                      winds.data() + P, cells.data(), k, work.data() + P, f.data() + P,
                      D.data() + P, threads);
    check(f.data() + P, S, D.data() + P, S, threads == 1 ? "grid, 1 thread" : "grid, 2 threads");
    if (threads == 1) first = f;
    else EXPECT_TRUE(first == f) << "2 threads changed the bits";
  }
  // The general loop over the triangle list, its terms added in triangle order.
  std::vector<double> tw(3 * nt), out(9 * nt), f(3 * n, 0.0), D(6 * n, 0.0);
  for (std::size_t j = 0; j < nt; ++j)
    for (std::size_t e = 0; e < 3; ++e) tw[e * nt + j] = wind[Eigen::Index(e)];
  detail::aero_triangles(nt, t.triangles.data(), xs.data() + P, vs.data() + P, std::ptrdiff_t(S),
                         tw.data(), k, out.data());
  for (std::size_t j = 0; j < nt; ++j)
    for (std::size_t c = 0; c < 3; ++c) {
      const std::uint32_t i = t.triangles[3 * j + c];
      for (std::size_t e = 0; e < 3; ++e) f[e * n + i] += out[e * nt + j];
      for (std::size_t e = 0; e < 6; ++e) D[e * n + i] += out[(3 + e) * nt + j];
    }
  check(f.data(), n, D.data(), n, "triangle list");
}

struct Hang {
  std::vector<float> x;
  double cg_per_step = 0.0;
};

/// A 32 x 32 sheet of 1 m and 1 kg hanging from two corners (the peer scene of bench_cloth at a
/// quarter of its nodes), one implicit step per frame for 1 s.
Hang hang(double tol, int threads = 1) {
  World w(WorldDef{1.0 / 60, 1, 0.05, threads});
  ClothDef d;
  d.rows = d.columns = 32;
  d.width = d.height = 1.0;
  d.mass = 1.0;
  d.transform.translation = Vec3(0, 0, 2.0);
  d.pins = {{0, 0, {}}, {0, 31, {}}};
  d.cg_tolerance = tol;
  d.cg_max_iterations = 2000;
  const ClothHandle h = w.add_cloth(d);
  Hang out;
  for (int f = 0; f < 60; ++f) {
    w.advance(1.0 / 60);
    out.cg_per_step += double(w.cloth_stats(h).cg_iterations) / 60.0;
  }
  const ClothView v = w.cloth(h);
  out.x.assign(v.positions, v.positions + 3 * v.vertex_count);
  return out;
}

// With block Jacobi alone, CG stopped at |r| <= 1e-2 |b| left the smooth error (the sheet's
// swing) that a small residual hides: 1 s in, the sheet was 20 mm rms from the converged
// solve, in 35 iterations per step. The coarse level solves those modes: 1.9 mm in 15.6.
TEST(ClothSolver, DefaultToleranceFollowsTheConvergedSolveClosely) {
  const Hang ref = hang(1e-7), def = hang(ClothDef{}.cg_tolerance);
  double sum2 = 0.0;
  for (std::size_t i = 0; i < ref.x.size(); i += 3) {
    const Eigen::Vector3d d(def.x[i] - ref.x[i], def.x[i + 1] - ref.x[i + 1], def.x[i + 2] - ref.x[i + 2]);
    sum2 += d.squaredNorm();
  }
  const double rms = std::sqrt(sum2 / double(ref.x.size() / 3));
  std::printf("default tolerance: %.2f mm rms from the converged solve, %.1f CG iterations per "
              "step (converged: %.1f)\n", 1e3 * rms, def.cg_per_step, ref.cg_per_step);
  EXPECT_LT(rms, 0.006);
  EXPECT_LT(def.cg_per_step, 22.0);
}

// The coarse level runs on one thread in vertex order: a sheet large enough for the parallel
// loops (48 x 48 = 2304 vertices) gives the same bits at 1 and 2 threads.
TEST(ClothSolver, SameBitsAtOneAndTwoThreads) {
  const auto run = [](int threads) {
    World w(WorldDef{1.0 / 60, 1, 0.05, threads});
    ClothDef d;
    d.rows = d.columns = 48;
    d.width = d.height = 1.0;
    d.transform.translation = Vec3(0, 0, 2.0);
    d.pins = {{0, 0, {}}, {0, 47, {}}};
    const ClothHandle h = w.add_cloth(d);
    for (int f = 0; f < 20; ++f) w.advance(1.0 / 60);
    const ClothView v = w.cloth(h);
    return std::vector<float>(v.positions, v.positions + 3 * v.vertex_count);
  };
  const auto one = run(1), two = run(2);
  ASSERT_EQ(one.size(), two.size());
  EXPECT_EQ(0, std::memcmp(one.data(), two.data(), one.size() * sizeof(float)));
}

}  // namespace
