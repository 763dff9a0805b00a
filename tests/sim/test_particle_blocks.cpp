// The particle collision pass's block kernels (collision/particle_blocks.hpp) decide which
// particles collide() hands to the sweeps. A block kernel that says "clear" where the particle's
// own test would not loses a collision, so each is checked against that test written out with
// Eigen as collide() writes it (start of step x0 = x1 - dt v1 + dt²/2 g, Coutinho §3.2's
// semi-implicit Euler without drag; swept bounds grown by the radius and surface_tol; the mesh
// AABB; MeshGrid::clear_of), decision for decision.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "collision/collider_impl.hpp"
#include "collision/particle_blocks.hpp"
#include "collision/plane_rest.hpp"
#include "collision/sweep.hpp"
#include "core/vector_clones.hpp"
#include "sim_test_util.hpp"
#include "simreel/sim/body.hpp"
#include "simreel/sim/random.hpp"

namespace simreel::sim {
namespace {

/// An open height field of n x n squares over [-2, 2]² at rest, as a collider: a terrain, which
/// collide() tests by its columns (column_tested()).
template <class Height>
detail::Collider terrain(const Height& height, int n = 48) {
  ShapeDef def;
  def.type = ShapeType::mesh;
  test::fill_height_field(def, n, 2.0, height);
  detail::Collider c = detail::make_collider(def, "terrain");
  c.set_pose(Transform{});
  c.note_pose();
  return c;
}

TEST(SimParticleBlocks, ColumnsClearBlockDecidesAsTheParticleTest) {
  // An open height field (a terrain: the columns apply) and a block of particles above,
  // through and below it, beside it, newborns (age < h), fast and slow, and a few on its faces.
  const auto height = [](double x, double y) { return 0.2 * std::sin(2.1 * x) * std::cos(1.4 * y); };
  const detail::Collider c = terrain(height);
  ASSERT_TRUE(detail::column_tested(c));
  const double h = 1.0 / 240;
  const double g[3] = {0.3, -0.2, -9.81};
  Rng rng(31, 2);
  constexpr std::size_t kN = detail::SweptBounds::kBlock;
  int cleared = 0, kept = 0, near_aabb_count = 0;
  // Column memos (ColumnMemo) kept over the rounds, so a slot meets other particles too; the
  // second call of a round finds every asked particle's own key in its slot.
  detail::ColumnMemo memo8, memo4;
  for (int round = 0; round < 40; ++round) {
    std::vector<float> x(3 * kN), v(3 * kN), age(kN), r(kN);
    std::uint8_t pend[kN], clear[kN], clear4[kN], clear_scalar[kN];
    std::uint8_t memo_clear[4][kN];
    for (auto& m : memo_clear) std::fill(m, m + kN, std::uint8_t{1});
    for (std::size_t k = 0; k < kN; ++k) {
      const double px = rng.uniform(-2.3, 2.3), py = rng.uniform(-2.3, 2.3);
      const double dz = k % 9 == 0 ? 0.0 : rng.uniform(-0.3, 0.6) * (k % 3 == 0 ? 0.1 : 1.0);
      x[3 * k] = float(px);
      x[3 * k + 1] = float(py);
      x[3 * k + 2] = float(height(px, py) + dz);
      const double speed = k % 4 == 0 ? 20.0 : 2.0;
      for (int a = 0; a < 3; ++a) v[3 * k + std::size_t(a)] = float(rng.uniform(-speed, speed));
      age[k] = k % 5 == 0 ? float(rng.uniform(0.0, h)) : 1.0f;
      r[k] = float(rng.uniform(0.002, 0.03));
      // A few not finite (an exploding scene): the block must answer as the particle's test.
      if (k % 61 == 5) x[3 * k + std::size_t(round % 3)] = std::numeric_limits<float>::quiet_NaN();
      if (k % 67 == 6) v[3 * k + std::size_t(round % 3)] = (round % 2 != 0 ? 1.0f : -1.0f) * std::numeric_limits<float>::infinity();
      // Most asked or a few (a block where the memo answered the rest); the others left alone.
      pend[k] = (round % 2 == 0 ? k % 7 != 3 : k % 13 == 2) ? 1 : 0;
      clear[k] = 1;
      clear4[k] = 1;
      clear_scalar[k] = 1;
    }
    detail::SweptBounds b;
    detail::swept_bounds_plain(x.data(), v.data(), age.data(), r.data(), kN, h, g, b);
    std::uint8_t near[kN] = {};
    detail::near_solid(b, kN, c.aabb_center.data(), c.aabb_half.data(), near);
    // The widest form this CPU runs (AVX-512 lanes where it has them), the AVX2 one (where it
    // has AVX2) and the scalar one; a block's length that is not a multiple of the lanes' eight
    // or four in some rounds.
    const std::size_t len = round % 4 == 1 ? kN - 3 : kN;
    detail::columns_clear_block(b, len, c, pend, clear);
    detail::columns_clear_block(b, len, c, pend, clear4, 4);
    detail::columns_clear_block(b, len, c, pend, clear_scalar, 1);
    for (int call = 0; call < 2; ++call) {
      detail::columns_clear_block(b, len, c, pend, memo_clear[call], 8,
                                  memo8.for_grid(c.mesh->grid, kN));
      detail::columns_clear_block(b, len, c, pend, memo_clear[2 + call], 4,
                                  memo4.for_grid(c.mesh->grid, kN));
    }
    for (std::size_t k = 0; k < kN; ++k) {
      // collide()'s own test for particle k, as start_of_step(), near_aabb and columns_clear()
      // compute it.
      const Vec3 p1(x[3 * k], x[3 * k + 1], x[3 * k + 2]);
      const Vec3 v1(v[3 * k], v[3 * k + 1], v[3 * k + 2]);
      const double dt = std::min(double(age[k]), h);
      const Vec3 p0 = p1 - dt * v1 + (0.5 * dt * dt) * Vec3(g[0], g[1], g[2]);
      const double grow = r[k] + detail::surface_tol(p1);
      const Vec3 lo = p0.cwiseMin(p1) - c.aabb_center, hi = p0.cwiseMax(p1) - c.aabb_center;
      const Vec3 ext = c.aabb_half + Vec3::Constant(grow);
      const bool in_aabb = (lo.array() <= ext.array()).all() && (hi.array() >= -ext.array()).all();
      ASSERT_EQ(near[k] != 0, in_aabb) << round << " " << k;
      const bool columns = c.mesh->grid.clear_of(p0.cwiseMin(p1) - Vec3::Constant(grow),
                                                 p0.cwiseMax(p1) + Vec3::Constant(grow));
      const bool expect = k >= len || pend[k] == 0 || !in_aabb || columns;
      ASSERT_EQ(clear[k] != 0, expect) << round << " " << k;
      ASSERT_EQ(clear4[k] != 0, expect) << round << " " << k;
      ASSERT_EQ(clear_scalar[k] != 0, expect) << round << " " << k;
      for (int m = 0; m < 4; ++m) ASSERT_EQ(memo_clear[m][k] != 0, expect) << round << " " << k << " memo " << m;
      near_aabb_count += in_aabb;
      if (k < len && pend[k] != 0 && in_aabb) (columns ? cleared : kept) += 1;
    }
  }
  const std::size_t filled = std::size_t(std::count_if(
      memo8.slot.begin(), memo8.slot.end(), [](std::uint64_t e) { return e != detail::ColumnMemo::kNone; }));
  // Both answers are given many times, not one of them always; the slots were written where a
  // vector form ran (the scalar one, all a build without GCC's targets has, leaves them).
#if SIMREEL_HAS_VECTOR_CLONES
  if (cpu_has_avx2()) {
    EXPECT_GT(filled, kN / 4);
  }
#else
  EXPECT_EQ(filled, 0u);
#endif
  EXPECT_GT(cleared, 600);
  EXPECT_GT(kept, 600);
  EXPECT_LT(near_aabb_count, 40 * int(kN) - 500);  // and some particles are beside the AABB
}


TEST(SimParticleBlocks, ColumnMemoSlotsAnswerAsTheColumnsDo) {
  // ColumnMemo slots filled by one step's boxes, then asked by boxes moved a little (drops
  // drifting across the terrain's columns: the same first column with one column or row more
  // or less, or another first column): every answer as the scalar test's (itself checked
  // against MeshGrid::clear_of() above), in the AVX-512 and AVX2 forms. Then a slot is voided by
  // another grid, and not by the same one.
  const auto height = [](double x, double y) { return 0.3 * std::sin(3.1 * x) * std::cos(2.4 * y); };
  const detail::Collider c = terrain(height);
  ASSERT_TRUE(detail::column_tested(c));
  const double h = 1.0 / 240;
  const double g[3] = {0.0, 0.0, -9.81};
  Rng rng(7, 3);
  constexpr std::size_t kN = detail::SweptBounds::kBlock;
  detail::ColumnMemo memo8, memo4;
  int differ = 0, asked = 0;
  for (int round = 0; round < 60; ++round) {
    std::vector<float> x(3 * kN), v(3 * kN), age(kN, 1.0f), r(kN);
    for (std::size_t k = 0; k < kN; ++k) {
      const double px = rng.uniform(-1.9, 1.9), py = rng.uniform(-1.9, 1.9);
      x[3 * k] = float(px);
      x[3 * k + 1] = float(py);
      x[3 * k + 2] = float(height(px, py) + rng.uniform(-0.02, 0.12));
      v[3 * k + 2] = float(rng.uniform(-3.0, 0.0));
      r[k] = float(rng.uniform(0.003, 0.03));
    }
    std::uint8_t pend[kN];
    std::fill(pend, pend + kN, std::uint8_t{1});
    for (int step = 0; step < 3; ++step) {
      if (step > 0)
        for (std::size_t k = 0; k < kN; ++k)
          for (int a = 0; a < 2; ++a) x[3 * k + std::size_t(a)] += float(rng.uniform(-0.03, 0.03));
      detail::SweptBounds b;
      detail::swept_bounds_plain(x.data(), v.data(), age.data(), r.data(), kN, h, g, b);
      std::uint8_t scalar[kN], m8[kN], m4[kN];
      std::fill(scalar, scalar + kN, std::uint8_t{1});
      std::fill(m8, m8 + kN, std::uint8_t{1});
      std::fill(m4, m4 + kN, std::uint8_t{1});
      detail::columns_clear_block(b, kN, c, pend, scalar, 1);
      detail::columns_clear_block(b, kN, c, pend, m8, 8, memo8.for_grid(c.mesh->grid, kN));
      detail::columns_clear_block(b, kN, c, pend, m4, 4, memo4.for_grid(c.mesh->grid, kN));
      for (std::size_t k = 0; k < kN; ++k) {
        ASSERT_EQ(m8[k], scalar[k]) << round << " " << step << " " << k;
        ASSERT_EQ(m4[k], scalar[k]) << round << " " << step << " " << k;
        differ += scalar[k] == 0;
        ++asked;
      }
    }
  }
  // Both answers, many times each.
  EXPECT_GT(differ, asked / 10);
  EXPECT_LT(differ, asked - asked / 10);
  // Another grid (another terrain) voids every slot; the same grid, or a copy of it, keeps them.
  const std::uint64_t kept = 12345;  // (a slot of any content: the memo does not read them here)
  memo8.for_grid(c.mesh->grid, kN)[0] = kept;
  const detail::MeshGrid copy = c.mesh->grid;
  EXPECT_EQ(memo8.for_grid(copy, kN)[0], kept);
  const detail::Collider c2 = terrain(height, 40);
  ASSERT_NE(c2.mesh->grid.serial(), c.mesh->grid.serial());
  const std::uint64_t* slots = memo8.for_grid(c2.mesh->grid, kN);
  for (std::size_t k = 0; k < kN; ++k) ASSERT_EQ(slots[k], detail::ColumnMemo::kNone) << k;
}

TEST(SimParticleBlocks, NearPlanesDecidesAsTheParticleTest) {
  // near_planes() reads one coordinate for a plane whose normal is ±e_a (a ground, a wall) and
  // all three otherwise; either way it must answer collide()'s own rejection test,
  // n · (p - q) - r < 0 in double with Eigen, particle for particle: blocks around axis-aligned
  // planes of either sign on each axis (one through an offset point), a tilted one, and two
  // planes at once; particles exactly at the radius, at ±0, far away, and in some blocks an
  // infinite or NaN coordinate off the plane's axis (the general sum is then NaN: not near).
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  Rng rng(17, 3);
  const auto plane = [](Vec3 q, Vec3 nrm) {
    detail::Collider c;
    c.shape = detail::Collider::Shape::plane;
    c.point = q;
    c.normal = nrm;
    return c;
  };
  std::vector<detail::Collider> planes;
  for (int a = 0; a < 3; ++a)
    for (double s : {1.0, -1.0}) {
      Vec3 nrm = Vec3::Zero();
      nrm[a] = s;
      planes.push_back(plane(Vec3(0.25, -0.5, 0.125), nrm));
    }
  planes.push_back(plane(Vec3::Zero(), Vec3(-0.0, 0.0, 1.0)));  // a ground with a signed zero
  planes.push_back(plane(Vec3(0.1, 0.2, 0.3), Vec3(0.36, 0.48, 0.8)));  // tilted (unit)
  constexpr std::size_t kN = 300;
  int near_count = 0, total = 0;
  for (int round = 0; round < 48; ++round) {
    const std::size_t first = std::size_t(round) % planes.size();
    const std::size_t count = round % 5 == 4 ? 2 : 1;  // two planes: planes[first], planes[first + 1]
    std::vector<detail::Collider> use(planes.begin() + std::ptrdiff_t(first),
                                      planes.begin() + std::ptrdiff_t(std::min(first + count, planes.size())));
    const bool spoil = round % 3 == 2;  // a block with infinite and NaN coordinates
    std::vector<float> x(3 * kN), r(kN);
    for (std::size_t k = 0; k < kN; ++k) {
      for (int a = 0; a < 3; ++a) x[3 * k + std::size_t(a)] = float(rng.uniform(-0.2, 0.6));
      r[k] = float(rng.uniform(0.0, 0.05));
      if (k % 11 == 0) r[k] = 0.0f;
      const detail::Collider& c = use.front();
      int axis = -1;
      for (int a = 0; a < 3; ++a)
        if (std::abs(c.normal[a]) == 1.0) axis = a;
      if (axis >= 0 && k % 7 == 1) {
        // Exactly at the radius or on the plane (the boundary of "<"), or at ±0 on the axis.
        const float q = float(c.point[axis]);
        x[3 * k + std::size_t(axis)] = k % 3 == 0 ? q + float(c.normal[axis]) * r[k]
                                      : k % 3 == 1 ? q : (k % 2 == 0 ? 0.0f : -0.0f);
      }
      if (spoil && k % 13 == 3) {
        const std::size_t off = (std::size_t(axis >= 0 ? axis : 0) + 1 + k % 2) % 3;
        x[3 * k + off] = k % 4 == 3 ? nan : (k % 2 == 0 ? inf : -inf);
      }
      if (spoil && k % 29 == 5 && axis >= 0) x[3 * k + std::size_t(axis)] = k % 2 == 0 ? -inf : nan;
    }
    const std::size_t len = round % 4 == 1 ? kN - 5 : kN;
    std::vector<std::uint8_t> near(kN, 7);
    detail::near_planes(x.data(), r.data(), len, use.data(), use.size(), near.data());
    for (std::size_t k = 0; k < len; ++k) {
      const Vec3 p1(x[3 * k], x[3 * k + 1], x[3 * k + 2]);
      bool expect = false;
      for (const detail::Collider& c : use) expect = expect || c.normal.dot(p1 - c.point) - double(r[k]) < 0.0;
      ASSERT_EQ(near[k] != 0, expect) << "round " << round << ", particle " << k << " at ("
                                      << x[3 * k] << ", " << x[3 * k + 1] << ", " << x[3 * k + 2]
                                      << "), r " << r[k];
      near_count += expect ? 1 : 0;
      ++total;
    }
  }
  // Both answers are common (the check above is not one-sided).
  EXPECT_GT(near_count, total / 10);
  EXPECT_LT(near_count, total - total / 10);
}

TEST(SimParticleBlocks, GatherBlockSharesTheScalarsOnlyWhereEveryLaneHasLaneZerosBits) {
  // gather_block() fills lane 0 of m, r and dt alone, and says so (l.shared), when it finds from
  // the stored floats that every lane's double would have lane 0's bits: one mass, one radius,
  // and every age at least h (the step min(age, h) is then h). plane_rest() and plane_block()
  // then read lane 0. Checked against the lanes written out as doubles (m, r, min(age, h)):
  // shared only where they all match bit for bit, lane 0 right, every lane right otherwise.
  // Steps where float(h) falls below h and above it, and ages one float either side of h,
  // catch a threshold rounded the wrong way; a mass or radius one ulp off, in the first lane
  // or the last, a wrong "shared".
  const auto bits = [](double d) { return __builtin_bit_cast(std::uint64_t, d); };
  const auto up = [](float a) { return std::nextafter(a, std::numeric_limits<float>::infinity()); };
  const auto down = [](float a) { return std::nextafter(a, -std::numeric_limits<float>::infinity()); };
  bool below = false, above = false;
  int shared_count = 0, cases = 0;
  Rng rng(5, 9);
  auto l = std::make_unique<detail::PlaneRestLanes>();
  for (const double h : {1.0 / 240, 1.0 / 100, 1.0 / 25, 0.1, 1.0 / 60}) {
    below = below || double(float(h)) < h;
    above = above || double(float(h)) > h;
    for (int c = 0; c < 14; ++c) {
      const std::size_t len = c == 13 ? 1 : c % 3 == 2 ? 37 : detail::kPlaneRestLanes;
      std::vector<float> x(3 * len, 0.5f), v(3 * len, -0.25f), mass(len, 2.5e-3f), radius(len, 0.02f),
          age(len);
      for (float& a : age) a = float(rng.uniform(h, 3.0)) + float(h);
      const std::size_t at = c % 2 == 0 ? len - 1 : 0;
      switch (c) {
        case 1: mass[at] = up(mass[at]); break;
        case 2: radius[at] = down(radius[at]); break;
        case 3: age[at] = float(h); break;               // shared where float(h) >= h
        case 4: age[at] = down(float(h)); break;
        case 5: age[at] = up(float(h)); break;
        case 6: age[at] = std::numeric_limits<float>::quiet_NaN(); break;
        case 7: age[at] = 0.0f; break;                   // a newborn
        case 8: mass[at] = down(mass[at]); break;
        case 9: std::fill(age.begin(), age.end(), down(float(h))); break;  // one step, all below h
        case 10: std::fill(age.begin(), age.end(), float(h)); break;
        case 11: radius[at] = up(radius[at]); break;
        case 13: age[0] = float(h); break;
        default: break;
      }
      // Stale values in the lanes from an earlier block must not matter.
      for (std::size_t k = 0; k < detail::kPlaneRestLanes; ++k) l->m[k] = l->r[k] = l->dt[k] = -1.0;
      detail::gather_block(x.data(), v.data(), nullptr, mass.data(), radius.data(), age.data(), h, len, *l);
      bool all_same = true;
      for (std::size_t k = 0; k < len; ++k) {
        const double m = mass[k], r = radius[k], a = age[k], dt = std::min(a, h);
        all_same = all_same && bits(m) == bits(double(mass[0])) && bits(r) == bits(double(radius[0])) &&
                   bits(dt) == bits(std::min(double(age[0]), h));
        if (!l->shared) {
          ASSERT_EQ(bits(l->m[k]), bits(m)) << "h " << h << ", case " << c << ", lane " << k;
          ASSERT_EQ(bits(l->r[k]), bits(r)) << "h " << h << ", case " << c << ", lane " << k;
          ASSERT_EQ(bits(l->dt[k]), bits(dt)) << "h " << h << ", case " << c << ", lane " << k;
        }
      }
      // Every lane's step h: the only shared step the floats can show (a block of equal ages
      // below h may go either way; here it must not be called shared, its step is not h).
      const bool expect = all_same && bits(std::min(double(age[0]), h)) == bits(h);
      ASSERT_EQ(l->shared, expect) << "h " << h << ", case " << c << ", len " << len;
      if (l->shared) {
        EXPECT_EQ(bits(l->m[0]), bits(double(mass[0])));
        EXPECT_EQ(bits(l->r[0]), bits(double(radius[0])));
        EXPECT_EQ(bits(l->dt[0]), bits(h));
        ++shared_count;
      }
      ++cases;
      // The lanes are always read in full where not shared.
      EXPECT_EQ(l->bx[len - 1], 0.5f);
    }
  }
  EXPECT_TRUE(below);  // both roundings of h were tried
  EXPECT_TRUE(above);
  EXPECT_GT(shared_count, cases / 4);  // both answers are common
  EXPECT_LT(shared_count, cases - cases / 4);
}

}  // namespace
}  // namespace simreel::sim
