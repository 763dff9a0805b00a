// The resting-on-a-plane fast path (plane_rest.hpp): resolve() of particle_response.cpp for the
// one case that dominates a settled scene, a particle lying on the ground plane, written as
// straight-line arithmetic over lanes. Each expression is the one resolve() evaluates, in the
// same order (Eigen's dot is (x0 y0 + x1 y1) + x2 y2, its norm the square root of that for x = y;
// -ffp-contract=off), and selects replace its branches, so a lane's result is the slow path's
// bit for bit; tests/sim/test_plane_rest.cpp compares the two. Built with -fno-trapping-math
// -fno-math-errno (sim/CMakeLists.txt) so both sides of a select may be evaluated and the square
// roots vectorise; neither changes a value.
#include "collision/plane_rest.hpp"

#include "collision/narrow_phase.hpp"  // np::kSkin
#include "core/vector_clones.hpp"

namespace simreel::sim::detail {

namespace {

inline double dot3(double x0, double x1, double x2, double y0, double y1, double y2) {
  return (x0 * y0 + x1 * y1) + x2 * y2;
}

/// The lanes for one combination of the system-wide choices (template arguments, so that the
/// loop holds only per-lane selects, which vectorise): the start of the step stored, quadratic
/// drag, a static coefficient different from the dynamic one.
/// kUp: the plane's normal is +z exactly (the ground of every scene that does not tilt it). Each
/// n · (x, y, z) of the general form, (0 x + 0 y) + 1 z, is then z itself, bit for bit, whenever
/// x and y are finite, except that a z of ±0 may give a zero of the other sign; every place below
/// that reads such a product either subtracts the radius from it (r > 0: -r either way), compares
/// it with zero, or uses it only in a square or on a branch a zero does not take, so the lane's
/// results are the general form's. The x and y terms are summed per lane instead, and a lane
/// whose sum is not finite (a term that was not, or an overflow) or whose radius is not positive
/// goes to the general path. The products drop out of the longest chain of dependent operations
/// in the loop, which sets its speed.
template <bool kStored, bool kQuadratic, bool kTwoMu, bool kUp>
SIMREEL_VECTOR_CLONES void lanes(PlaneRestLanes& l, std::size_t count, const PlaneRestParams& p) {
  const double n0 = kUp ? 0.0 : p.n[0], n1 = kUp ? 0.0 : p.n[1], n2 = kUp ? 1.0 : p.n[2];
  const double q0 = p.q[0], q1 = p.q[1], q2 = p.q[2];
  const double g0 = p.g[0], g1 = p.g[1], g2 = p.g[2];
  const double drag = p.drag, c2 = p.drag_quadratic, cs = p.contact_speed;
  const double mu_d = p.mu, mu_s = p.mu_static;
  constexpr double kSkin = np::kSkin;
  for (std::size_t k = 0; k < count; ++k) {
    const double bx = l.bx[k], by = l.by[k], bz = l.bz[k];
    const double vx = l.vx[k], vy = l.vy[k], vz = l.vz[k];
    const double m = l.m[k], r = l.r[k], dt = l.dt[k];
    double fin = 0.0;  // kUp: the sum of the terms the general form multiplies by 0
    const auto along = [&](double x, double y, double z) {
      if constexpr (kUp) {
        fin += x + y;
        return z;
      } else {
        return dot3(n0, n1, n2, x, y, z);
      }
    };
    // step_acceleration(): A = g - (k / m) v with k = drag_at(v)
    const double speed = __builtin_sqrt(dot3(vx, vy, vz, vx, vy, vz));
    const double kd = kQuadratic ? drag + c2 * speed : drag;
    const double km = kd / m;
    const double Ax = g0 - km * vx, Ay = g1 - km * vy, Az = g2 - km * vz;
    // start_of_step(): x0 = x1 - dt v1 + (dt² d² / 2) A, d = m / (m + dt k), unless stored
    const double d = m / (m + dt * kd);
    const double coef = 0.5 * dt * dt * d * d;
    double ax, ay, az;
    if constexpr (kStored) {
      ax = l.ax[k];
      ay = l.ay[k];
      az = l.az[k];
    } else {
      ax = (bx - dt * vx) + coef * Ax;
      ay = (by - dt * vy) + coef * Ay;
      az = (bz - dt * vz) + coef * Az;
    }
    const double kx = Ax * dt, ky = Ay * dt, kz = Az * dt;  // the kick
    // sweep_plane()
    const double d0 = along(ax - q0, ay - q1, az - q2) - r;
    const double d1 = along(bx - q0, by - q1, bz - q2) - r;
    const double frac = d0 / (d0 - d1);
    const double s = d0 > 0.0 ? frac : 0.0;
    // A contact: d1 < -kSkin, d1 < d0 and s < inf (s >= 0 or NaN here, so: s is finite). The
    // lane's verdict is kept as a double (1 or 0) so that every select is on 64-bit lanes.
    double ok = d1 < -kSkin ? 1.0 : 0.0;
    ok = d1 < d0 ? ok : 0.0;
    ok = s - s == 0.0 ? ok : 0.0;
    double px = ax + s * (bx - ax), py = ay + s * (by - ay), pz = az + s * (bz - az);
    const double pd = along(px - q0, py - q1, pz - q2) - r;
    px = px - pd * n0;
    py = py - pd * n1;
    pz = pz - pd * n2;
    // resolve(): the velocity at the time of impact and the resting test (vc = 0 on a plane)
    const double rest = (1.0 - s) * dt;
    const double hx = vx - rest * Ax, hy = vy - rest * Ay, hz = vz - rest * Az;
    const double vn_hit = along(hx - 0.0, hy - 0.0, hz - 0.0);
    const double kn = along(kx, ky, kz);
    const double push = 0.0 < -kn ? -kn : 0.0;
    ok = -vn_hit < cs + push ? ok : 0.0;  // resting
    // respond(v_hit + rest A, force_resting): e = 0
    const double wx = hx + rest * Ax, wy = hy + rest * Ay, wz = hz + rest * Az;
    const double vn = along(wx - 0.0, wy - 0.0, wz - 0.0);
    const double tx = (wx - 0.0) - vn * n0, ty = (wy - 0.0) - vn * n1, tz = (wz - 0.0) - vn * n2;
    const double tl = __builtin_sqrt(dot3(tx, ty, tz, tx, ty, tz));
    // respond()'s static coefficient while not sliding (only when it differs)
    double mu = mu_d;
    if constexpr (kTwoMu) {
      const double jx = kx - kn * n0, jy = ky - kn * n1, jz = kz - kn * n2;
      const double kick_t = __builtin_sqrt(dot3(jx, jy, jz, jx, jy, jz));
      mu = tl <= kick_t * (1.0 + 1e-6) + 1e-12 ? mu_s : mu_d;
    }
    const double lim = mu * (1.0 + 0.0) * (-vn);
    const double dvt = lim < tl ? lim : tl;
    const double f = 1.0 - dvt / tl;
    const double ux = tl > 0.0 ? tx * f : tx, uy = tl > 0.0 ? ty * f : ty,
                 uz = tl > 0.0 ? tz * f : tz;
    // vc + (-e vn) n + u with vc = 0 and e = 0: (0 + (+0) n) + u = +0 + u (vn < 0 here; a NaN
    // vn gives NaN either way), which is u + 0.0 (a -0 component becomes +0).
    double v1x = vn >= 0.0 ? wx : ux + 0.0;
    double v1y = vn >= 0.0 ? wy : uy + 0.0;
    double v1z = vn >= 0.0 ? wz : uz + 0.0;
    // v0: just after the impact, its normal part removed
    const double v0x = vn_hit < 0.0 ? hx - vn_hit * n0 : hx,
                 v0y = vn_hit < 0.0 ? hy - vn_hit * n1 : hy,
                 v0z = vn_hit < 0.0 ? hz - vn_hit * n2 : hz;
    // the rest of the step along the surface, never back into it
    const double half = 0.5 * rest;
    double sx = half * (v0x + v1x), sy = half * (v0y + v1y), sz = half * (v0z + v1z);
    const double dn = along(sx, sy, sz);
    sx = dn < 0.0 ? sx - dn * n0 : sx;
    sy = dn < 0.0 ? sy - dn * n1 : sy;
    sz = dn < 0.0 ? sz - dn * n2 : sz;
    double ex = px + sx, ey = py + sy, ez = pz + sz;
    // The second sweep of the step (p -> e) must find nothing, else the general path.
    const double e0 = along(px - q0, py - q1, pz - q2) - r;
    const double e1 = along(ex - q0, ey - q1, ez - q2) - r;
    ok = e1 < -kSkin && e1 < e0 ? 0.0 : ok;
    // resolve()'s closing projection onto the plane
    ex = e1 < 0.0 ? ex - e1 * n0 : ex;
    ey = e1 < 0.0 ? ey - e1 * n1 : ey;
    ez = e1 < 0.0 ? ez - e1 * n2 : ez;
    const double vn1 = along(v1x, v1y, v1z);
    v1x = e1 < 0.0 && vn1 < 0.0 ? v1x - vn1 * n0 : v1x;
    v1y = e1 < 0.0 && vn1 < 0.0 ? v1y - vn1 * n1 : v1y;
    v1z = e1 < 0.0 && vn1 < 0.0 ? v1z - vn1 * n2 : v1z;
    const float fx = float(ex), fy = float(ey), fz = float(ez);
    // The stored floats must be outside the plane too (resolve()'s last step)
    const double gap = along(double(fx) - q0, double(fy) - q1, double(fz) - q2) - r;
    if constexpr (kUp) ok = fin - fin == 0.0 && r > 0.0 ? ok : 0.0;
    // Lanes not resolved here give back their input (exactly: the inputs are floats).
    l.ox[k] = float(ok != 0.0 ? ex : bx);
    l.oy[k] = float(ok != 0.0 ? ey : by);
    l.oz[k] = float(ok != 0.0 ? ez : bz);
    l.ovx[k] = float(ok != 0.0 ? v1x : vx);
    l.ovy[k] = float(ok != 0.0 ? v1y : vy);
    l.ovz[k] = float(ok != 0.0 ? v1z : vz);
    l.gap[k] = gap;
    l.ok[k] = ok;
  }
}

template <bool kStored, bool kQuadratic, bool kTwoMu>
void pick_up(PlaneRestLanes& l, std::size_t count, const PlaneRestParams& p) {
  if (p.n[0] == 0.0 && p.n[1] == 0.0 && p.n[2] == 1.0)
    lanes<kStored, kQuadratic, kTwoMu, true>(l, count, p);
  else
    lanes<kStored, kQuadratic, kTwoMu, false>(l, count, p);
}

template <bool kStored, bool kQuadratic>
void pick_mu(PlaneRestLanes& l, std::size_t count, const PlaneRestParams& p) {
  if (p.mu_static != p.mu)
    pick_up<kStored, kQuadratic, true>(l, count, p);
  else
    pick_up<kStored, kQuadratic, false>(l, count, p);
}

template <bool kStored>
void pick_drag(PlaneRestLanes& l, std::size_t count, const PlaneRestParams& p) {
  if (p.drag_quadratic != 0.0)
    pick_mu<kStored, true>(l, count, p);
  else
    pick_mu<kStored, false>(l, count, p);
}

}  // namespace

void plane_rest(PlaneRestLanes& l, std::size_t count, const PlaneRestParams& p) {
  if (p.start_stored)
    pick_drag<true>(l, count, p);
  else
    pick_drag<false>(l, count, p);
}

}  // namespace simreel::sim::detail
