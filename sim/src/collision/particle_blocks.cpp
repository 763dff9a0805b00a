// The particle collision pass's block kernels: see particle_blocks.hpp.
#include "collision/particle_blocks.hpp"

#include <algorithm>
#include <cmath>

#include "core/vector_clones.hpp"

namespace simreel::sim::detail {

/// near[k] = 1 when particle k (x: n x 3 floats, r: n) ends the step closer than its radius to
/// one of the planes: collide()'s rejection test, the same double arithmetic, in a loop the
/// compiler vectorises.
SIMREEL_VECTOR_CLONES
void near_planes(const float* __restrict x, const float* __restrict r, std::size_t n,
                 const Collider* planes, std::size_t count, std::uint8_t* __restrict near) {
  for (std::size_t k = 0; k < n; ++k) near[k] = 0;
  for (std::size_t c = 0; c < count; ++c) {
    const double n0 = planes[c].normal[0], n1 = planes[c].normal[1], n2 = planes[c].normal[2];
    const double q0 = planes[c].point[0], q1 = planes[c].point[1], q2 = planes[c].point[2];
    for (std::size_t k = 0; k < n; ++k) {
      const double e0 = double(x[3 * k]) - q0, e1 = double(x[3 * k + 1]) - q1,
                   e2 = double(x[3 * k + 2]) - q2;
      near[k] |= std::uint8_t(n0 * e0 + n1 * e1 + n2 * e2 - double(r[k]) < 0.0);
    }
  }
}

/// b = the swept bounds of particles [0, n): see particle_blocks.hpp.
SIMREEL_VECTOR_CLONES
void swept_bounds_plain(const float* __restrict x, const float* __restrict v,
                        const float* __restrict age, const float* __restrict r, std::size_t n,
                        double h, const double* __restrict g, SweptBounds& b) {
  for (std::size_t k = 0; k < n; ++k) {
    const double a = double(age[k]);
    const double dt = h < a ? h : a;  // std::min(age, h)
    const double c = 0.5 * dt * dt;
    const double p0 = double(x[3 * k]), p1 = double(x[3 * k + 1]), p2 = double(x[3 * k + 2]);
    const double s0 = p0 - dt * double(v[3 * k]) + c * g[0];
    const double s1 = p1 - dt * double(v[3 * k + 1]) + c * g[1];
    const double s2 = p2 - dt * double(v[3 * k + 2]) + c * g[2];
    // surface_tol(p1): 1e-7 + 5e-7 max |p1_i| (the largest of three is exact in any order).
    const double m01 = std::abs(p0) < std::abs(p1) ? std::abs(p1) : std::abs(p0);
    const double m = m01 < std::abs(p2) ? std::abs(p2) : m01;
    b.grow[k] = double(r[k]) + (1e-7 + 5e-7 * m);
    // Eigen's cwiseMin / cwiseMax of start s and end p: (p < s) ? p : s and (s < p) ? p : s.
    b.lo[0][k] = p0 < s0 ? p0 : s0;
    b.hi[0][k] = s0 < p0 ? p0 : s0;
    b.lo[1][k] = p1 < s1 ? p1 : s1;
    b.hi[1][k] = s1 < p1 ? p1 : s1;
    b.lo[2][k] = p2 < s2 ? p2 : s2;
    b.hi[2][k] = s2 < p2 ? p2 : s2;
  }
}

namespace {
/// Bounds k of b, grown by b.grow[k], overlap the AABB (center, half): near_aabb's arithmetic.
inline bool overlaps(const SweptBounds& b, std::size_t k, const double* center, const double* half) {
  const double grow = b.grow[k];
  const double e0 = half[0] + grow, e1 = half[1] + grow, e2 = half[2] + grow;
  return (b.lo[0][k] - center[0] <= e0) & (b.lo[1][k] - center[1] <= e1) &
         (b.lo[2][k] - center[2] <= e2) & (b.hi[0][k] - center[0] >= -e0) &
         (b.hi[1][k] - center[1] >= -e1) & (b.hi[2][k] - center[2] >= -e2);
}
}  // namespace

/// near[k] |= 1 when bounds k overlap the solid's AABB: see particle_blocks.hpp.
SIMREEL_VECTOR_CLONES
void near_solid(const SweptBounds& b, std::size_t n, const double* __restrict center,
                const double* __restrict half, std::uint8_t* __restrict near) {
  for (std::size_t k = 0; k < n; ++k) near[k] |= std::uint8_t(overlaps(b, k, center, half));
}

void near_block_plain(const float* __restrict x, const float* __restrict v,
                      const float* __restrict age, const float* __restrict r, std::size_t n,
                      double h, const double* g, const std::vector<Collider>& colliders,
                      SweptBounds& b, std::uint8_t* __restrict near, std::uint8_t* __restrict pend) {
  std::fill(near, near + n, std::uint8_t{0});
  std::fill(pend, pend + n, std::uint8_t{0});
  swept_bounds_plain(x, v, age, r, n, h, g, b);
  std::uint8_t near_c[SweptBounds::kBlock];
  for (const Collider& c : colliders) {
    if (c.shape == Collider::Shape::plane) {
      near_planes(x, r, n, &c, 1, near_c);
      for (std::size_t k = 0; k < n; ++k) near[k] |= near_c[k];
    } else {
      near_solid(b, n, c.aabb_center.data(), c.aabb_half.data(), column_tested(c) ? pend : near);
    }
  }
}

void columns_clear_block(const SweptBounds& b, std::size_t n, const Collider& c,
                         const std::uint8_t* __restrict pend, std::uint8_t* __restrict clear) {
  const MeshGrid& grid = c.mesh->grid;
  for (std::size_t k = 0; k < n; ++k) {
    if (pend[k] == 0) continue;
    // This mesh's AABB test (near_solid()'s) for the particles asked only: pend may come from
    // another column-tested mesh.
    if (!overlaps(b, k, c.aabb_center.data(), c.aabb_half.data())) continue;
    const double grow = b.grow[k];
    const Vec3 lo(b.lo[0][k] - grow, b.lo[1][k] - grow, b.lo[2][k] - grow);
    const Vec3 hi(b.hi[0][k] + grow, b.hi[1][k] + grow, b.hi[2][k] + grow);
    if (!grid.clear_of(lo, hi)) clear[k] = 0;
  }
}

/// Lanes [0, len) of `l` from a block of particles (x, v: len x 3; prev: the start-of-step
/// positions or null; mass, radius, age: len), each lane's step min(age, h).
SIMREEL_VECTOR_CLONES
void gather_block(const float* __restrict x, const float* __restrict v,
                  const float* __restrict prev, const float* __restrict mass,
                  const float* __restrict radius, const float* __restrict age, double h,
                  std::size_t len, PlaneRestLanes& l) {
  for (std::size_t k = 0; k < len; ++k) {
    l.bx[k] = x[3 * k];
    l.by[k] = x[3 * k + 1];
    l.bz[k] = x[3 * k + 2];
    l.vx[k] = v[3 * k];
    l.vy[k] = v[3 * k + 1];
    l.vz[k] = v[3 * k + 2];
    l.m[k] = mass[k];
    l.r[k] = radius[k];
    const double a = age[k];
    l.dt[k] = h < a ? h : a;  // std::min(a, h)
  }
  if (prev != nullptr)
    for (std::size_t k = 0; k < len; ++k) {
      l.ax[k] = prev[3 * k];
      l.ay[k] = prev[3 * k + 1];
      l.az[k] = prev[3 * k + 2];
    }
}

/// The lanes' outputs back into the block (x, v: len x 3): the results of the lanes that
/// plane_rest() resolved, the others' values as they were.
SIMREEL_VECTOR_CLONES
void scatter_block(const PlaneRestLanes& l, std::size_t len, float* __restrict x,
                   float* __restrict v) {
  for (std::size_t k = 0; k < len; ++k) {
    x[3 * k] = l.ox[k];
    x[3 * k + 1] = l.oy[k];
    x[3 * k + 2] = l.oz[k];
    v[3 * k] = l.ovx[k];
    v[3 * k + 1] = l.ovy[k];
    v[3 * k + 2] = l.ovz[k];
  }
}

/// near[k] = 1 when lane k of `l` ends the step closer than its radius to the plane (the test of
/// near_planes(), on the same values).
SIMREEL_VECTOR_CLONES
void near_lanes(const PlaneRestLanes& l, std::size_t len, const PlaneRestParams& p,
                std::uint8_t* __restrict near) {
  const double n0 = p.n[0], n1 = p.n[1], n2 = p.n[2], q0 = p.q[0], q1 = p.q[1], q2 = p.q[2];
  for (std::size_t k = 0; k < len; ++k)
    near[k] = std::uint8_t(n0 * (l.bx[k] - q0) + n1 * (l.by[k] - q1) + n2 * (l.bz[k] - q2) -
                               l.r[k] < 0.0);
}

}  // namespace simreel::sim::detail
