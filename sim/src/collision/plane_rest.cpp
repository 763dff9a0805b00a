// The resting-on-a-plane fast path (plane_rest.hpp): resolve() of particle_response.cpp for the
// one case that dominates a settled scene, a particle lying on the ground plane, written as
// straight-line arithmetic over lanes. The expressions are resolve()'s, in its order, but in
// float (all but the sweep's two distances and its time of impact, which stay in double), in
// coordinates relative to the plane's point (taken in double): a float lane holds twice the
// particles of a double one and takes the same time per operation, and the loop is bound by the
// number of its operations (docs/benchmarks.md, issue 19 at stop 89). The state is stored as
// floats, so the result differs from the double path by a few roundings of a float
// (tests/sim/test_plane_rest.cpp bounds the difference). Selects replace resolve()'s branches.
// Built with -fno-trapping-math -fno-math-errno (sim/CMakeLists.txt) so both sides of a select
// may be evaluated and the square roots vectorise.
#include "collision/plane_rest.hpp"

#include "collision/narrow_phase.hpp"  // np::kSkin
#include "core/same_bits.hpp"
#include "core/vector_clones.hpp"

namespace simreel::sim::detail {

namespace {

inline float dot3(float x0, float x1, float x2, float y0, float y1, float y2) {
  return (x0 * y0 + x1 * y1) + x2 * y2;
}

/// The lanes for one combination of the system-wide choices (template arguments, so that the
/// loop holds only per-lane selects, which vectorise): the start of the step stored, quadratic
/// drag, a static coefficient different from the dynamic one, and (kUp) a normal of exactly +z
/// (the ground of every scene that does not tilt it), where n · x is z itself and the products
/// drop out of the longest chain of dependent operations in the loop.
/// Positions are taken relative to the plane's point q in double and then rounded to float, so
/// that the distances to the plane keep a float's relative precision however far q is from the
/// origin; the result is put back (q + the relative position) in double before its rounding to
/// the stored float. A lane whose outputs are not all finite (an overflow of the float
/// arithmetic, or a non-finite input) goes to the general path, which works in double.
/// kOrigin (with kUp only): the plane passes through z = +0 (q = 0 along the normal: every
/// ground left where a scene puts it), so z relative to the plane is the stored float itself
/// and the double round trips around q drop out: x - (+0) is x exactly (-0 included), and
/// float(double(e) + 0) is e + 0 in float (-0 becomes +0 both ways); the same bits.
/// kUniform: every lane has lane 0's mass, radius and step (the usual case: an emitter's
/// particles share them and are older than a step), so the loop reads them as scalars and the
/// compiler takes what depends on them alone (the drag over the mass, the start-of-step factors:
/// two divisions a lane) out of the loop; the same operations on the same values, so the same
/// bits.
template <bool kStored, bool kQuadratic, bool kTwoMu, bool kUp, bool kUniform, bool kOrigin>
SIMREEL_VECTOR_CLONES void lanes(PlaneRestLanes& l, std::size_t count, const PlaneRestParams& p) {
  using F = float;
  const F n0 = kUp ? 0.0f : F(p.n[0]), n1 = kUp ? 0.0f : F(p.n[1]), n2 = kUp ? 1.0f : F(p.n[2]);
  // kUp: x and y never enter a distance to the plane, so they stay in world coordinates (the
  // stored floats, exactly) and only z is taken relative to the plane.
  const double q0 = kUp ? 0.0 : p.q[0], q1 = kUp ? 0.0 : p.q[1], q2 = p.q[2];
  const double dn0 = p.n[0], dn1 = p.n[1], dn2 = p.n[2];
  const F g0 = F(p.g[0]), g1 = F(p.g[1]), g2 = F(p.g[2]);
  const F drag = F(p.drag), c2 = F(p.drag_quadratic), cs = F(p.contact_speed);
  const F mu_d = F(p.mu), mu_s = F(p.mu_static);
  constexpr F kSkin = F(np::kSkin);
  const auto along = [&](F x, F y, F z) {
    if constexpr (kUp) {
      return z;
    } else {
      return dot3(n0, n1, n2, x, y, z);
    }
  };
  for (std::size_t k = 0; k < count; ++k) {
    // b, a: end and start of the step relative to q (kUp: z only), in double until the sweep's
    // fraction (below), then in float
    const double bzd = kOrigin ? double(l.bz[k]) : double(l.bz[k]) - q2;
    double bxd, byd;
    F bx, by;
    if constexpr (kUp) {
      bx = l.bx[k];
      by = l.by[k];
      bxd = byd = 0.0;
    } else {
      bxd = double(l.bx[k]) - q0;
      byd = double(l.by[k]) - q1;
      bx = F(bxd);
      by = F(byd);
    }
    const F bz = kOrigin ? l.bz[k] : F(bzd);
    const F vx = l.vx[k], vy = l.vy[k], vz = l.vz[k];
    const std::size_t u = kUniform ? 0 : k;  // the lane of the mass, radius and step
    const F m = F(l.m[u]), r = F(l.r[u]), dt = F(l.dt[u]);
    // step_acceleration(): A = g - (k / m) v with k = drag_at(v)
    const F speed = __builtin_sqrtf(dot3(vx, vy, vz, vx, vy, vz));
    const F kd = kQuadratic ? drag + c2 * speed : drag;
    const F km = kd / m;
    const F Ax = g0 - km * vx, Ay = g1 - km * vy, Az = g2 - km * vz;
    // start_of_step(): x0 = x1 - dt v1 + (dt² d² / 2) A, d = m / (m + dt k), unless stored
    // (kUp: only the normal component, z, needs double; x and y only carry the sliding along.)
    double axd, ayd, azd;
    F ax, ay, az;
    if constexpr (kStored) {
      axd = l.ax[k] - q0;
      ayd = l.ay[k] - q1;
      azd = kOrigin ? double(l.az[k]) : l.az[k] - q2;
      ax = F(axd);
      ay = F(ayd);
    } else {
      const F d = m / (m + dt * kd);
      const F coef = 0.5f * dt * dt * d * d;
      const double dtd = l.dt[u];
      if constexpr (kUp) {
        ax = (bx - dt * vx) + coef * Ax;
        ay = (by - dt * vy) + coef * Ay;
        axd = ayd = 0.0;
      } else {
        axd = (bxd - dtd * l.vx[k]) + double(coef * Ax);
        ayd = (byd - dtd * l.vy[k]) + double(coef * Ay);
        ax = F(axd);
        ay = F(ayd);
      }
      azd = (bzd - dtd * l.vz[k]) + double(coef * Az);
    }
    az = F(azd);
    const F kx = Ax * dt, ky = Ay * dt, kz = Az * dt;  // the kick
    // sweep_plane(), in double: the two distances are small differences of the positions, and
    // the fraction of the step at the contact is their ratio, which float would leave wrong by
    // a float's epsilon times |x - q| / (d0 - d1) (a time of impact off by a part in a thousand
    // for a slow approach across a plane tilted under particles metres from its point).
    const double rd = l.r[u];
    const double d0 = (kUp ? azd : (dn0 * axd + dn1 * ayd) + dn2 * azd) - rd;
    const double d1 = (kUp ? bzd : (dn0 * bxd + dn1 * byd) + dn2 * bzd) - rd;
    const double frac = d0 / (d0 - d1);
    const F s = F(d0 > 0.0 ? frac : 0.0);
    // A contact: d1 < -kSkin, d1 < d0 and s < inf (s >= 0 or NaN here, so: s is finite). The
    // lane's verdict is kept as a float (1 or 0) so that every select is on 32-bit lanes.
    F ok = d1 < -np::kSkin ? 1.0f : 0.0f;
    ok = d1 < d0 ? ok : 0.0f;
    ok = s - s == 0.0f ? ok : 0.0f;
    F px = ax + s * (bx - ax), py = ay + s * (by - ay), pz = az + s * (bz - az);
    const F pd = along(px, py, pz) - r;
    px = px - pd * n0;
    py = py - pd * n1;
    pz = pz - pd * n2;
    // resolve(): the velocity at the time of impact and the resting test (vc = 0 on a plane)
    const F rest = (1.0f - s) * dt;
    const F hx = vx - rest * Ax, hy = vy - rest * Ay, hz = vz - rest * Az;
    const F vn_hit = along(hx, hy, hz);
    const F kn = along(kx, ky, kz);
    const F push = 0.0f < -kn ? -kn : 0.0f;
    ok = -vn_hit < cs + push ? ok : 0.0f;  // resting
    // respond(v_hit + rest A, force_resting): e = 0
    const F wx = hx + rest * Ax, wy = hy + rest * Ay, wz = hz + rest * Az;
    const F vn = along(wx, wy, wz);
    const F tx = wx - vn * n0, ty = wy - vn * n1, tz = wz - vn * n2;
    const F tl = __builtin_sqrtf(dot3(tx, ty, tz, tx, ty, tz));
    // respond()'s static coefficient while not sliding (only when it differs)
    F mu = mu_d;
    if constexpr (kTwoMu) {
      const F jx = kx - kn * n0, jy = ky - kn * n1, jz = kz - kn * n2;
      const F kick_t = __builtin_sqrtf(dot3(jx, jy, jz, jx, jy, jz));
      mu = tl <= kick_t * (1.0f + 1e-6f) + 1e-12f ? mu_s : mu_d;
    }
    const F lim = mu * (-vn);
    const F dvt = lim < tl ? lim : tl;
    const F f = 1.0f - dvt / tl;
    const F ux = tl > 0.0f ? tx * f : tx, uy = tl > 0.0f ? ty * f : ty,
            uz = tl > 0.0f ? tz * f : tz;
    // vc + (-e vn) n + u with vc = 0 and e = 0 (vn < 0 here): u, a -0 component made +0.
    F v1x = vn >= 0.0f ? wx : ux + 0.0f;
    F v1y = vn >= 0.0f ? wy : uy + 0.0f;
    F v1z = vn >= 0.0f ? wz : uz + 0.0f;
    // v0: just after the impact, its normal part removed
    const F v0x = vn_hit < 0.0f ? hx - vn_hit * n0 : hx,
            v0y = vn_hit < 0.0f ? hy - vn_hit * n1 : hy,
            v0z = vn_hit < 0.0f ? hz - vn_hit * n2 : hz;
    // the rest of the step along the surface, never back into it
    const F half = 0.5f * rest;
    F sx = half * (v0x + v1x), sy = half * (v0y + v1y), sz = half * (v0z + v1z);
    const F dn = along(sx, sy, sz);
    sx = dn < 0.0f ? sx - dn * n0 : sx;
    sy = dn < 0.0f ? sy - dn * n1 : sy;
    sz = dn < 0.0f ? sz - dn * n2 : sz;
    F ex = px + sx, ey = py + sy, ez = pz + sz;
    // The second sweep of the step (p -> e) must find nothing, else the general path.
    const F e0 = along(px, py, pz) - r;
    const F e1 = along(ex, ey, ez) - r;
    ok = e1 < -kSkin && e1 < e0 ? 0.0f : ok;
    // resolve()'s closing projection onto the plane
    ex = e1 < 0.0f ? ex - e1 * n0 : ex;
    ey = e1 < 0.0f ? ey - e1 * n1 : ey;
    ez = e1 < 0.0f ? ez - e1 * n2 : ez;
    const F vn1 = along(v1x, v1y, v1z);
    v1x = e1 < 0.0f && vn1 < 0.0f ? v1x - vn1 * n0 : v1x;
    v1y = e1 < 0.0f && vn1 < 0.0f ? v1y - vn1 * n1 : v1y;
    v1z = e1 < 0.0f && vn1 < 0.0f ? v1z - vn1 * n2 : v1z;
    // Every output finite, else the general path (an overflow in float, a non-finite input).
    const F all = ((ex + ey) + (ez + v1x)) + ((v1y + v1z) + (bx + by));
    ok = all - all == 0.0f ? ok : 0.0f;
    // Back to world coordinates, rounded to the stored floats.
    float fx, fy;
    if constexpr (kUp) {
      fx = ex;
      fy = ey;
    } else {
      fx = float(double(ex) + q0);
      fy = float(double(ey) + q1);
    }
    const float fz = kOrigin ? ez + 0.0f : float(double(ez) + q2);
    // The stored floats must be outside the plane too (resolve()'s last step), in double.
    const double gap =
        kOrigin ? double(fz) - rd
        : kUp   ? (double(fz) - q2) - rd
            : ((dn0 * (double(fx) - q0) + dn1 * (double(fy) - q1)) + dn2 * (double(fz) - q2)) -
                  rd;
    // Lanes not resolved here give back their input (exactly: the inputs are floats).
    const bool yes = ok != 0.0f;
    l.ox[k] = yes ? fx : l.bx[k];
    l.oy[k] = yes ? fy : l.by[k];
    l.oz[k] = yes ? fz : l.bz[k];
    l.ovx[k] = yes ? v1x : vx;
    l.ovy[k] = yes ? v1y : vy;
    l.ovz[k] = yes ? v1z : vz;
    l.ok[k] = gap >= 0.0 ? ok : 2.0f * ok;
  }
}

/// Lanes [0, count) all have lane 0's mass, radius and step, bit for bit (a clone of its own so
/// that the scans run in the widest vectors).
SIMREEL_VECTOR_CLONES bool uniform_scalars(const PlaneRestLanes& l, std::size_t count) {
  return same_bits(l.m, count) && same_bits(l.r, count) && same_bits(l.dt, count);
}

template <bool kStored, bool kQuadratic, bool kTwoMu, bool kUp, bool kOrigin>
void pick_uniform(PlaneRestLanes& l, std::size_t count, const PlaneRestParams& p) {
  if (l.shared || uniform_scalars(l, count))
    lanes<kStored, kQuadratic, kTwoMu, kUp, true, kOrigin>(l, count, p);
  else
    lanes<kStored, kQuadratic, kTwoMu, kUp, false, kOrigin>(l, count, p);
}

template <bool kStored, bool kQuadratic, bool kTwoMu>
void pick_up(PlaneRestLanes& l, std::size_t count, const PlaneRestParams& p, bool origin_form) {
  if (p.n[0] == 0.0 && p.n[1] == 0.0 && p.n[2] == 1.0) {
    if (origin_form && __builtin_bit_cast(std::uint64_t, p.q[2]) == 0)  // +0 exactly
      pick_uniform<kStored, kQuadratic, kTwoMu, true, true>(l, count, p);
    else
      pick_uniform<kStored, kQuadratic, kTwoMu, true, false>(l, count, p);
  } else {
    pick_uniform<kStored, kQuadratic, kTwoMu, false, false>(l, count, p);
  }
}

template <bool kStored, bool kQuadratic>
void pick_mu(PlaneRestLanes& l, std::size_t count, const PlaneRestParams& p, bool origin_form) {
  if (p.mu_static != p.mu)
    pick_up<kStored, kQuadratic, true>(l, count, p, origin_form);
  else
    pick_up<kStored, kQuadratic, false>(l, count, p, origin_form);
}

template <bool kStored>
void pick_drag(PlaneRestLanes& l, std::size_t count, const PlaneRestParams& p, bool origin_form) {
  if (p.drag_quadratic != 0.0)
    pick_mu<kStored, true>(l, count, p, origin_form);
  else
    pick_mu<kStored, false>(l, count, p, origin_form);
}

}  // namespace

void plane_rest(PlaneRestLanes& l, std::size_t count, const PlaneRestParams& p, bool origin_form) {
  if (p.start_stored)
    pick_drag<true>(l, count, p, origin_form);
  else
    pick_drag<false>(l, count, p, origin_form);
}

}  // namespace simreel::sim::detail
