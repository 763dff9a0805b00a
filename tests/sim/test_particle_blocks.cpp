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
#include <vector>

#include "collision/collider_impl.hpp"
#include "collision/particle_blocks.hpp"
#include "collision/sweep.hpp"
#include "sim_test_util.hpp"
#include "simreel/sim/body.hpp"
#include "simreel/sim/random.hpp"

namespace simreel::sim {
namespace {

TEST(SimParticleBlocks, ColumnsClearBlockDecidesAsTheParticleTest) {
  // An open height field (a terrain: the columns apply) and a block of particles above,
  // through and below it, beside it, newborns (age < h), fast and slow, and a few on its faces.
  const auto height = [](double x, double y) { return 0.2 * std::sin(2.1 * x) * std::cos(1.4 * y); };
  ShapeDef def;
  def.type = ShapeType::mesh;
  test::fill_height_field(def, 48, 2.0, height);
  detail::Collider c = detail::make_collider(def, "terrain");
  c.set_pose(Transform{});
  c.note_pose();
  ASSERT_TRUE(c.unposed);
  ASSERT_FALSE(c.mesh->closed);
  const double h = 1.0 / 240;
  const double g[3] = {0.3, -0.2, -9.81};
  Rng rng(31, 2);
  constexpr std::size_t kN = detail::SweptBounds::kBlock;
  int cleared = 0, kept = 0, near_aabb_count = 0;
  for (int round = 0; round < 40; ++round) {
    std::vector<float> x(3 * kN), v(3 * kN), age(kN), r(kN);
    std::uint8_t pend[kN], clear[kN], clear4[kN], clear_scalar[kN];
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
      near_aabb_count += in_aabb;
      if (k < len && pend[k] != 0 && in_aabb) (columns ? cleared : kept) += 1;
    }
  }
  // Both answers are given many times, not one of them always.
  EXPECT_GT(cleared, 600);
  EXPECT_GT(kept, 600);
  EXPECT_LT(near_aabb_count, 40 * int(kN) - 500);  // and some particles are beside the AABB
}

}  // namespace
}  // namespace simreel::sim
