// The particle collision pass against colliders: Coutinho §3.4 (swept spheres against a
// collider fixed at its end-of-step pose), §3.4.2 (particles found inside a body are removed),
// §3.6.1 (impulse with restitution and Coulomb friction, critical friction), §3.6.3 (resting
// contact under a normal-speed threshold, static friction).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <utility>

#include "collision/body_impulses.hpp"
#include "collision/collide_memo.hpp"
#include "collision/mesh_prefetch.hpp"
#include "collision/particle_blocks.hpp"
#include "collision/plane_rest.hpp"
#include "collision/sweep.hpp"
#include "core/vector_clones.hpp"
#include "particles/forces.hpp"  // kParallelMin

#include <omp.h>

namespace simreel::sim::detail {

/// Impulse response of a particle against an immovable collider (Coutinho §3.6.1 with the
/// collider's mass taken as infinite): relative normal velocity v_n' = -e v_n, tangential
/// velocity reduced by the Coulomb impulse mu (1 + e) |v_n| but never reversed — when
/// mu >= |v_t| / ((1 + e) |v_n|), the critical coefficient of eqs. 3.56–3.57, sliding stops
/// exactly. The tangent axes are taken along and across the relative sliding velocity, where
/// the book's directional model (eqs. 3.37–3.40) with one coefficient for both axes reduces to
/// this. Under the contact threshold (§3.6.3) the contact is resting: e = 0, so the normal
/// velocity is cancelled and friction removes mu |v_n| — the contact friction force mu |N|
/// times the step. A resting contact whose tangential speed is no more than this step's
/// tangential push (it was not sliding) uses the static coefficient: it holds on an incline of
/// angle theta when mu_s >= tan theta, and otherwise slides with a = g (sin theta - mu_d cos theta).
/// `kick` is the velocity one step of acceleration adds (g h for a particle lying on the floor):
/// its normal part is not counted as impact speed, so resting is recognised at any step size.
bool is_resting(double vn, double kick_n, double contact_speed) {
  return -vn < contact_speed + std::max(0.0, -kick_n);
}

Vec3 respond(const Vec3& v, const Vec3& vc, const Vec3& n, const Material& m, double contact_speed,
             const Vec3& kick, bool force_resting) {
  const Vec3 vr = v - vc;
  const double vn = vr.dot(n);
  if (vn >= 0.0) return v;  // already separating
  const bool resting = force_resting || is_resting(vn, kick.dot(n), contact_speed);
  double e = resting ? 0.0 : m.restitution;
  const Vec3 vt = vr - vn * n;
  const double vt_len = vt.norm();
  // The static coefficient only matters when it differs from the dynamic one (the tangential
  // push of the step is then needed to tell holding from sliding).
  double mu = m.friction;
  if (resting && m.static_mu() != m.friction) {
    const double kick_t = (kick - kick.dot(n) * n).norm();
    if (vt_len <= kick_t * (1.0 + 1e-6) + 1e-12) mu = m.static_mu();
  }
  if (m.on_hit == HitAction::stick) {
    e = 0.0;
    mu = std::numeric_limits<double>::infinity();
  }
  const double dvt = std::min(vt_len, mu * (1.0 + e) * (-vn));
  const Vec3 vt_new = vt_len > 0.0 ? Vec3(vt * (1.0 - dvt / vt_len)) : vt;
  return vc + (-e * vn) * n + vt_new;
}
namespace {

constexpr int kMaxContacts = 4;  // contacts resolved per particle per step (corners, wedges)
/// Passes over at least this many particles against a mesh visit them in spatial order.
constexpr std::size_t kSpatialOrderMin = 4096;


/// A particle found inside a box (the box may have moved onto it) leaves through the face it is
/// least deep behind and takes the box's velocity along that face's normal if it was moving in.
/// (Coutinho §3.4.2 removes such particles; simreel keeps them for boxes, which suits pushing
/// boxes; the other solids remove them.)
void push_out(const Collider& c, Vec3& p, Vec3& v, double r) {
  Vec3 l = c.R.transpose() * (p - c.center);
  const Vec3 E = c.half_extents + Vec3::Constant(r);
  const Vec3 depth = E - l.cwiseAbs();
  int k = 0;
  if (!(depth.minCoeff(&k) > surface_tol(p))) return;
  const double sign = l[k] >= 0.0 ? 1.0 : -1.0;
  l[k] = sign * E[k];
  p = c.center + c.R * l;
  const Vec3 n = sign * c.R.col(k);
  const double vn = (v - c.point_velocity(p)).dot(n);
  if (vn < 0.0) v -= vn * n;
}

/// Reads back a stored float position. The volatile read is deliberate: GCC 12 -O3 forwards the
/// unrounded doubles to a reload after a vectorised float store (it folds the round trip
/// cvtps2pd(cvtpd2ps(x)) into x), which made the check below pass on values never stored.
Vec3 load_stored(const float* pf) {
  const volatile float* v = pf;
  return Vec3(v[0], v[1], v[2]);
}

/// The guarantee holds for the stored floats: rounding a position to float may put the centre
/// (pf, 3 floats) a hair inside the plane c; step it out by growing amounts until it is not.
void keep_stored_out(const Collider& c, float* pf, double r) {
  for (int attempt = 0; attempt < 8; ++attempt) {
    const Vec3 p = load_stored(pf);
    const double d = c.normal.dot(p - c.point) - r;
    if (d >= 0.0) break;
    const double extra = attempt == 0 ? 0.0 : std::ldexp(1.2e-7, attempt) * (1.0 + p.cwiseAbs().maxCoeff());
    const Vec3 q = p + (extra - d) * c.normal;
    for (int k = 0; k < 3; ++k) pf[k] = float(q[k]);
  }
}

/// (kg/s) The drag coefficient at speed |v1|: k_d + c_2 |v1| (the square root only when c_2 is
/// set, which keeps the linear-drag contact path as cheap as before quadratic drag existed).
double drag_at(const ForceParams& f, const Vec3& v1) {
  return f.drag_quadratic != 0.0f ? double(f.drag) + double(f.drag_quadratic) * v1.norm()
                                  : double(f.drag);
}

/// (m/s²) The acceleration taken as constant over a particle's step, evaluated at its end
/// velocity v1: gravity and the drag -k v1 / m (the forces semi-implicit Euler integrates).
Vec3 step_acceleration(const ForceParams& f, double mass, const Vec3& v1) {
  if (f.drag == 0.0f && f.drag_quadratic == 0.0f)  // g - (0 / m) v1 is g exactly
    return Vec3(f.gravity[0], f.gravity[1], f.gravity[2]);
  return Vec3(f.gravity[0], f.gravity[1], f.gravity[2]) - (drag_at(f, v1) / mass) * v1;
}

/// Where particle i was at the start of its step: stored (the other integrators) or, for
/// semi-implicit Euler, recovered from its position update x1 = x0 + dt v1 - dt²/2 a(v1) d²,
/// d = 1 / (1 + dt k / m) (within float rounding of x1, which surface_tol absorbs).
/// `accel`: step_acceleration(f, m, v1) when the caller has it already (the same value).
Vec3 start_of_step(const ParticleStore& s, std::size_t i, const Vec3& p1, const Vec3& v1,
                   double dt, const ForceParams& f, const Vec3* accel = nullptr) {
  if (s.track_prev) {
    const float* q = &s.prev_position[3 * i];
    return Vec3(q[0], q[1], q[2]);
  }
  const Vec3 g(f.gravity[0], f.gravity[1], f.gravity[2]);
  // No drag: d = 1 and a = g exactly (what the general expression gives), without its divisions.
  if (f.drag == 0.0f && f.drag_quadratic == 0.0f)
    return p1 - dt * v1 + (0.5 * dt * dt) * (accel != nullptr ? *accel : g);
  const double m = s.mass[i], k = drag_at(f, v1), d = m / (m + dt * k);
  const Vec3 a = accel != nullptr ? *accel : Vec3(g - (k / m) * v1);
  return p1 - dt * v1 + (0.5 * dt * dt * d * d) * a;
}

/// Droplets of a split hit (HitAction::split): see SplitOnHit.
void splash(const Material& m, const Vec3& contact, const Vec3& n, const Vec3& v_rel,
            const Vec3& vc, double r, double mass, CollisionContext& ctx) {
  const SplitOnHit& sp = m.split;
  if (r < sp.min_radius || ctx.spawns == nullptr || ctx.rng == nullptr) return;
  const double rd = r * sp.size_fraction;
  const double speed = sp.speed_fraction * v_rel.norm();
  const Vec3 t = n.unitOrthogonal();
  const Vec3 k = n.cross(t);
  const double cos_max = std::cos(sp.spread_deg * 3.14159265358979323846 / 180.0);
  const Vec3 surface = contact - r * n;
  for (int j = 0; j < sp.count; ++j) {
    const double cz = 1.0 - ctx.rng->uniform() * (1.0 - cos_max);  // uniform over the cap
    const double phi = 2.0 * 3.14159265358979323846 * ctx.rng->uniform();
    const double sz = std::sqrt(std::max(0.0, 1.0 - cz * cz));
    const Vec3 dir = cz * n + sz * (std::cos(phi) * t + std::sin(phi) * k);
    ctx.spawns->push_back(SpawnRequest{Vec3(surface + 1.01 * rd * n), Vec3(vc + speed * dir), rd,
                                       mass * sp.size_fraction * sp.size_fraction *
                                           sp.size_fraction,
                                       sp.lifetime});
  }
}

/// The slow path for one particle that may touch something this step. The step is taken as
/// one of constant acceleration A = g - k_d v1 / m (step_acceleration): a contact at fraction s
/// of the swept segment happens at time s dt with the velocity v(s) = v1 - (1 - s) dt A, which
/// the response reflects (§3.6.1); the remainder r = (1 - s) dt is then integrated with the
/// forces, v = v' + r A and x = x_c + r (v' + v) / 2 (exact for a constant acceleration), so the
/// energy of a bounce does not depend on where in the step it falls. A resting contact (§3.6.3)
/// holds over the whole remainder: its normal velocity and acceleration are cancelled and the
/// friction acts on the normal impulse of both (the response of the velocity at the end of the
/// remainder), and the particle moves along the surface by the mean of its velocities. Returns
/// true when the particle was removed (its age set to its lifetime).
bool resolve(ParticleStore& s, std::size_t i, double dt, const std::vector<Collider>& colliders,
             CollisionContext& ctx, const ForceParams& f) {
  float* pf = &s.position[3 * i];
  float* vf = &s.velocity[3 * i];
  Vec3 b(pf[0], pf[1], pf[2]);
  Vec3 v(vf[0], vf[1], vf[2]);
  const Vec3 A = step_acceleration(f, s.mass[i], v);
  Vec3 a = start_of_step(s, i, b, v, dt, f, &A);
  const double r = s.radius[i];
  const Vec3 kick = A * dt;  // the velocity one whole step of the forces adds
  bool dead = false;

  for (int contact = 0;; ++contact) {
    Hit hit;
    for (const Collider& c : colliders) sweep(c, a, b, r, contact == 0, hit);
    if (hit.collider == nullptr) {
      // Nothing hit and nothing below to push it out of or test it inside: b and v are the
      // stored values (the writes back would store the same floats).
      if (contact == 0 && ctx.bare_misses) return false;
      break;
    }
    Material mat = hit.collider->material;
    if (ctx.on_hit != nullptr) {
      mat.on_hit = *ctx.on_hit;
      mat.split = *ctx.on_hit_split;
    }
    const Vec3 vc = hit.collider->point_velocity(hit.point);
    const double rest = (1.0 - hit.s) * dt;
    const Vec3 v_hit = v - rest * A;  // the velocity at the time of impact
    if (mat.on_hit == HitAction::kill || mat.on_hit == HitAction::split) {
      const std::size_t spawned = ctx.spawns != nullptr ? ctx.spawns->size() : 0;
      if (mat.on_hit == HitAction::split)
        splash(mat, hit.point, hit.normal, v_hit - vc, vc, r, s.mass[i], ctx);
      if (ctx.impulses != nullptr) {  // §3.7: the body takes what the droplets do not carry off
        Vec3 J = double(s.mass[i]) * v_hit;
        for (std::size_t q = spawned; ctx.spawns != nullptr && q < ctx.spawns->size(); ++q)
          J -= (*ctx.spawns)[q].mass * (*ctx.spawns)[q].velocity;
        ctx.impulses->add(*hit.collider, J, hit.point - r * hit.normal);
      }
      dead = true;
      b = hit.point;
      break;
    }
    const Vec3& n = hit.normal;
    const double vn_hit = (v_hit - vc).dot(n);
    const bool resting = is_resting(vn_hit, kick.dot(n), ctx.contact_speed) ||
                         mat.on_hit == HitAction::stick;
    Vec3 v0, v1;  // just after the impact, and at the end of the remainder
    if (resting) {
      // The contact holds for the remainder: one response to everything pressing in over it.
      v1 = respond(v_hit + rest * A, vc, n, mat, ctx.contact_speed, kick, true);
      const double vn0 = (v_hit - vc).dot(n);
      v0 = vn0 < 0.0 ? Vec3(v_hit - vn0 * n) : v_hit;
    } else {
      v0 = respond(v_hit, vc, n, mat, ctx.contact_speed, kick, false);
      // An impact on a dynamic body is a collision of two free bodies: the change of the
      // relative velocity is shared in proportion to the inverse masses, 1/m_p against the
      // body's 1/M + (r × n)·I⁻¹(r × n) at the contact (Coutinho §3.6.1 with both sides free;
      // the body takes the rest through the logged impulse, §3.7). Held fixed, a particle as
      // heavy as the body would bounce off it as off a wall and throw it at many times its speed.
      // The body's point then recedes along -n by `recede` (m/s): the particle is separating
      // from it at -e vn even when it keeps going the same way.
      double recede = 0.0;
      if (ctx.impulses != nullptr) {
        const double wb = ctx.impulses->inverse_mass_at(*hit.collider, hit.point - r * n, n);
        if (wb > 0.0) {
          const double wp = 1.0 / double(s.mass[i]);
          v0 = v_hit + (wp / (wp + wb)) * (v0 - v_hit);
          recede = wb * double(s.mass[i]) * (v0 - v_hit).dot(n);
        }
      }
      v1 = v0 + rest * A;
      // Gravity turning a weak bounce back within the remainder: it lies on the surface.
      const double vn1 = (v1 - vc).dot(n) + recede;
      if (vn1 < 0.0) v1 -= vn1 * n;
    }
    // §3.7: the body takes the momentum the contact removed, m (v without it - v with it).
    if (ctx.impulses != nullptr)
      ctx.impulses->add(*hit.collider, double(s.mass[i]) * (v - v1), hit.point - r * n);
    v = v1;
    // The rest of the step against the collider held at its end pose (§3.4), never back into
    // the surface just left. (Not relative to a moving collider: a particle at rest on a box
    // sliding under it must stay where it is, not slide backwards.)
    Vec3 disp = (0.5 * rest) * (v0 + v1);
    const double dn = disp.dot(n);
    if (dn < 0.0) disp -= dn * n;
    a = hit.point;
    dt = rest;
    if (contact + 1 == kMaxContacts) {
      b = a;  // out of contacts: stay at the last one, which is outside everything hit so far
      break;
    }
    b = a + disp;
  }

  if (!dead) {
    for (const Collider& c : colliders) {
      if (c.shape != Collider::Shape::box) continue;
      const Vec3 v_in = v;
      push_out(c, b, v, r);
      if (ctx.impulses != nullptr && v != v_in)
        ctx.impulses->add(c, double(s.mass[i]) * (v_in - v), b);
    }
    for (const Collider& c : colliders) {
      if (c.shape != Collider::Shape::plane) continue;
      const double d = c.normal.dot(b - c.point) - r;
      if (d < 0.0) {
        b -= d * c.normal;
        const double vn = v.dot(c.normal);
        if (vn < 0.0) v -= vn * c.normal;
      }
    }
    for (const Collider& c : colliders) {
      if (c.shape == Collider::Shape::plane || c.shape == Collider::Shape::box) continue;
      if (c.shape == Collider::Shape::mesh && !c.mesh->closed) continue;  // an open mesh has no inside
      if (((b - c.aabb_center).cwiseAbs().array() > c.aabb_half.array()).any()) continue;
      if (inside_solid(c, b)) {
        dead = true;  // §3.4.2
        ++ctx.removed_inside;
        break;
      }
    }
  }
  if (dead) s.age[i] = s.lifetime[i];

  for (int k = 0; k < 3; ++k) {
    pf[k] = float(b[k]);
    vf[k] = float(v[k]);
  }
  for (const Collider& c : colliders)
    if (c.shape == Collider::Shape::plane) keep_stored_out(c, pf, r);
  return dead;
}

/// Particles [i0, i0 + len) of s against the one plane colliders[0]: the fast path for those
/// resting on it, resolve() for the others near it. Most of a block on the plane: every lane goes
/// through in place; a few: a compacted list of them. `dense`: the previous block's case, a guess
/// that saves the rejection test's separate pass, and for a settled block the rejection test
/// itself (updated; the results do not depend on it).
void plane_block(ParticleStore& s, std::size_t i0, std::size_t len, double h,
                 const PlaneRestParams& pp, const std::vector<Collider>& colliders,
                 CollisionContext& ctx, const ForceParams& f, bool& dense) {
  thread_local std::unique_ptr<PlaneRestLanes> lanes;
  if (!lanes) lanes = std::make_unique<PlaneRestLanes>();  // zeroed: unused lanes stay defined
  PlaneRestLanes& l = *lanes;
  const Collider& c0 = colliders.front();
  const float* x = s.position.data();
  const float* vel = s.velocity.data();
  const float* prev = s.track_prev ? s.prev_position.data() : nullptr;
  const auto gather = [&] {
    gather_block(x + 3 * i0, vel + 3 * i0, prev != nullptr ? prev + 3 * i0 : nullptr,
                 s.mass.data() + i0, s.radius.data() + i0, s.age.data() + i0, h, len, l);
  };
  std::uint8_t near[kPlaneRestLanes];
  const bool gathered = dense;
  if (gathered) {
    // Guessed on the plane: the lanes first. A lane plane_rest() resolves is near the plane
    // (its d1 < -skin is the rejection test's value), and its other lanes give back their
    // inputs, so a settled block (every lane resolved and stored outside the plane: one
    // branch-free pass says so) needs neither the rejection test nor the loop below; it stays
    // dense. Otherwise the rejection test, and the lanes' results are used in place whether or
    // not the block turns out dense (each lane's result depends on that lane alone).
    gather();
    plane_rest(l, len, pp);
    if (all_resolved_outside(l, len)) {
      scatter_block(l, len, s.position.data() + 3 * i0, s.velocity.data() + 3 * i0);
      return;
    }
    near_lanes(l, len, pp, near);
  } else {
    near_planes(x + 3 * i0, s.radius.data() + i0, len, colliders.data(), 1, near);
  }
  std::size_t m = 0;
  for (std::size_t k = 0; k < len; ++k) m += near[k];
  dense = 3 * m >= 2 * len;
  if (m == 0) return;  // (no lane resolved, so the block's values are as they were)
  if (dense || gathered) {
    if (!gathered) {
      gather();
      plane_rest(l, len, pp);
    }
    scatter_block(l, len, s.position.data() + 3 * i0, s.velocity.data() + 3 * i0);
    for (std::size_t k = 0; k < len; ++k) {
      const std::size_t u = l.shared ? 0 : k;  // the lane of the step and radius
      if (l.ok[k] == 0.0f) {
        if (near[k]) resolve(s, i0 + k, l.dt[u], colliders, ctx, f);
      } else if (l.ok[k] != 1.0f) {
        keep_stored_out(c0, &s.position[3 * (i0 + k)], l.r[u]);
      }
    }
    return;
  }
  std::uint32_t idx[kPlaneRestLanes];
  l.shared = false;  // every lane's own m, r and dt below
  m = 0;
  for (std::size_t k = 0; k < len; ++k) {
    if (!near[k]) continue;
    const std::size_t i = i0 + k;
    idx[m] = std::uint32_t(i);
    l.bx[m] = x[3 * i];
    l.by[m] = x[3 * i + 1];
    l.bz[m] = x[3 * i + 2];
    l.vx[m] = vel[3 * i];
    l.vy[m] = vel[3 * i + 1];
    l.vz[m] = vel[3 * i + 2];
    if (prev != nullptr) {
      l.ax[m] = prev[3 * i];
      l.ay[m] = prev[3 * i + 1];
      l.az[m] = prev[3 * i + 2];
    }
    l.m[m] = s.mass[i];
    l.r[m] = s.radius[i];
    l.dt[m] = std::min(double(s.age[i]), h);
    ++m;
  }
  plane_rest(l, m, pp);
  for (std::size_t k = 0; k < m; ++k) {
    const std::size_t i = idx[k];
    if (l.ok[k] == 0.0f) {
      resolve(s, i, l.dt[k], colliders, ctx, f);
      continue;
    }
    float* pf = &s.position[3 * i];
    float* vf = &s.velocity[3 * i];
    pf[0] = l.ox[k];
    pf[1] = l.oy[k];
    pf[2] = l.oz[k];
    vf[0] = l.ovx[k];
    vf[1] = l.ovy[k];
    vf[2] = l.ovz[k];
    if (l.ok[k] != 1.0f) keep_stored_out(c0, pf, l.r[k]);
  }
}

}  // namespace

void collide(ParticleStore& s, std::size_t begin, std::size_t end, double h,
             const std::vector<Collider>& colliders, CollisionContext& ctx, const ForceParams& f) {
  if (colliders.empty()) return;
  const float* x = s.position.data();
  const float* vel = s.velocity.data();
  bool planes_only = true;
  for (const Collider& c : colliders) planes_only = planes_only && c.shape == Collider::Shape::plane;
  if (planes_only) {
    // Only planes (a ground): the rejection test below for a block of particles at a time, then
    // the slow path for the few near a plane. resolve() changes only its own particle, so
    // testing the block first changes nothing.
    constexpr std::size_t kBlock = kPlaneRestLanes;
    // One plane that only bounces (the ground): the particles near it go through the vectorised
    // resting fast path first (plane_rest.hpp, float lanes: resolve()'s results to a few roundings
    // of a float); resolve() takes the rest.
    // Then nothing is shared between particles (no splash, no body impulse, no removal), so
    // large systems split their blocks statically over ctx.threads: the same results.
    const Collider& c0 = colliders.front();
    const HitAction act = ctx.on_hit != nullptr ? *ctx.on_hit : c0.material.on_hit;
    const bool fast = colliders.size() == 1 && act == HitAction::bounce &&
                      (ctx.impulses == nullptr || !ctx.impulses->logs(c0));
    PlaneRestParams pp{};
    if (fast) {
      for (int a = 0; a < 3; ++a) {
        pp.n[a] = c0.normal[a];
        pp.q[a] = c0.point[a];
        pp.g[a] = f.gravity[a];
      }
      pp.drag = f.drag;
      pp.drag_quadratic = f.drag_quadratic;
      pp.mu = c0.material.friction;
      pp.mu_static = c0.material.static_mu();
      pp.contact_speed = ctx.contact_speed;
      pp.start_stored = s.track_prev;
    }
    const std::ptrdiff_t blocks = std::ptrdiff_t((end - begin + kBlock - 1) / kBlock);
    const bool par = fast && ctx.threads > 1 && end - begin >= kParallelMin;
#pragma omp parallel for schedule(static) num_threads(ctx.threads) if (par)
    for (std::ptrdiff_t b = 0; b < blocks; ++b) {
      const std::size_t i0 = begin + std::size_t(b) * kBlock;
      const std::size_t len = std::min(kBlock, end - i0);
      if (fast) {
        // Whether the last block of this thread lay on the plane: a guess of how to read this
        // one (the results do not depend on it).
        thread_local bool dense = false;
        plane_block(s, i0, len, h, pp, colliders, ctx, f, dense);
        continue;
      }
      std::uint8_t near[kBlock];
      near_planes(x + 3 * i0, s.radius.data() + i0, len, colliders.data(), colliders.size(), near);
      for (std::size_t k = 0; k < len; ++k)
        if (near[k]) resolve(s, i0 + k, std::min(double(s.age[i0 + k]), h), colliders, ctx, f);
    }
    return;
  }
  // Particles share nothing here unless a hit splits them (droplets appended in particle order,
  // splash draws from one generator) or a dynamic body logs their impulses (summed in particle
  // order): otherwise each resolve() changes its own particle alone, and large systems split
  // statically over ctx.threads with the same results; the removal count is an integer sum.
  bool shared = false;
  ctx.bare_misses = std::all_of(colliders.begin(), colliders.end(), [](const Collider& c) {
    return c.shape == Collider::Shape::mesh && !c.mesh->closed;
  });
  for (const Collider& c : colliders) {
    const HitAction act = ctx.on_hit != nullptr ? *ctx.on_hit : c.material.on_hit;
    shared = shared || act == HitAction::split || (ctx.impulses != nullptr && ctx.impulses->logs(c));
  }
  const bool par = !shared && ctx.threads > 1 && end - begin >= kParallelMin;
  // The memo of responses (collide_memo.hpp): where particles share nothing, and each response
  // is a function of the particle's stored end state alone (not of a stored start of step).
  CollideMemo* memo = ctx.memo != nullptr && !shared && !s.track_prev ? ctx.memo : nullptr;
  const std::uint32_t epoch =
      memo != nullptr ? memo->begin_pass(s, colliders, f, h, ctx.contact_speed, ctx.on_hit,
                                         ctx.on_hit_split)
                      : 0;
  // The output resolve() gave last time for the same input in the same environment, written
  // back (true), or nothing (false). Only whole steps (dt = h) are kept: a newborn's dt is its
  // age, which is not in the key.
  const auto reuse = [&](std::size_t i, std::size_t& reused) __attribute__((always_inline)) {
    if (memo == nullptr || !(double(s.age[i]) >= h) || s.memo_epoch[i] != epoch) return false;
    float* pf = &s.position[3 * i];
    float* vf = &s.velocity[3 * i];
    const float key[CollideMemo::kKey] = {pf[0], pf[1], pf[2], vf[0], vf[1], vf[2], s.radius[i], s.mass[i]};
    const float* e = &s.memo[CollideMemo::kStride * i];
    if (std::memcmp(key, e, sizeof key) != 0) return false;
    std::memcpy(pf, e + CollideMemo::kKey, 3 * sizeof(float));
    std::memcpy(vf, e + CollideMemo::kKey + 3, 3 * sizeof(float));
    ++reused;
    return true;
  };
  // resolve(), its input and output kept for reuse when the output is at rest (velocity zero):
  // only a particle that the step leaves where it was can meet the same input next step, and
  // one that moves cannot be where it was (writing every response's entry cost the first second
  // of the rain benchmark ~9 %, three more cache lines a drop). A response that removed the
  // particle is not kept (it is not a function of the particle alone: the pass counts it).
  const auto resolve_kept = [&](std::size_t i, CollisionContext& c) __attribute__((always_inline)) {
    const double dt = std::min(double(s.age[i]), h);
    if (memo == nullptr || dt != h) {
      resolve(s, i, dt, colliders, c, f);
      return;
    }
    float* pf = &s.position[3 * i];
    float* vf = &s.velocity[3 * i];
    const float key[CollideMemo::kKey] = {pf[0], pf[1], pf[2], vf[0], vf[1], vf[2], s.radius[i], s.mass[i]};
    if (resolve(s, i, dt, colliders, c, f) || vf[0] != 0.0f || vf[1] != 0.0f || vf[2] != 0.0f) return;
    float* e = &s.memo[CollideMemo::kStride * i];
    std::memcpy(e, key, sizeof key);
    std::memcpy(e + CollideMemo::kKey, pf, 3 * sizeof(float));
    std::memcpy(e + CollideMemo::kKey + 3, vf, 3 * sizeof(float));
    s.memo_epoch[i] = epoch;
  };
  // Particle i's swept bounds from p0 to p1, grown by its radius and surface_tol(p1), against
  // solid c's AABB.
  const auto near_aabb = [&](const Collider& c, const Vec3& p0, const Vec3& p1, double grow) {
    const Vec3 lo = p0.cwiseMin(p1) - c.aabb_center;
    const Vec3 hi = p0.cwiseMax(p1) - c.aabb_center;
    const Vec3 ext = c.aabb_half + Vec3::Constant(grow);
    return (lo.array() <= ext.array()).all() && (hi.array() >= -ext.array()).all();
  };
  // True when every column-tested mesh whose AABB particle i's swept bounds overlap shows by its
  // columns that they clear its triangles.
  const auto columns_clear = [&](std::size_t i) {
    const Vec3 p1(x[3 * i], x[3 * i + 1], x[3 * i + 2]);
    const Vec3 v1(vel[3 * i], vel[3 * i + 1], vel[3 * i + 2]);
    const Vec3 p0 = start_of_step(s, i, p1, v1, std::min(double(s.age[i]), h), f);
    const double grow = s.radius[i] + surface_tol(p1);
    for (const Collider& c : colliders)
      if (column_tested(c) && near_aabb(c, p0, p1, grow) &&
          !c.mesh->grid.clear_of(p0.cwiseMin(p1) - Vec3::Constant(grow),
                                 p0.cwiseMax(p1) + Vec3::Constant(grow)))
        return false;
    return true;
  };
  // Fast rejection: end point clear of every plane, swept bounds clear of every solid; a
  // sleeping particle is put back where it sleeps by the caller. 0: not near; 1: near; 2: near
  // only the AABBs of column-tested meshes, left to columns_clear() (with `defer`; without, it
  // is asked here and 2 is not returned). The Z-order pass defers: a particle lying on a
  // terrain is answered by the memo, in index order, before the columns are read in no order.
  const float* rest = ctx.sleep && s.track_rest ? s.rest.data() : nullptr;
  const auto is_near = [&](std::size_t i, bool defer) __attribute__((always_inline)) {
    if (rest != nullptr && rest[4 * i + 3] >= kSleepTime) return 0;
    const Vec3 p1(x[3 * i], x[3 * i + 1], x[3 * i + 2]);
    const double r = s.radius[i];
    int pending = 0;
    for (const Collider& c : colliders) {
      if (c.shape == Collider::Shape::plane) {
        if (c.normal.dot(p1 - c.point) - r < 0.0) return 1;
        continue;
      }
      if (pending != 0 && column_tested(c)) continue;
      const double dt = std::min(double(s.age[i]), h);
      const Vec3 v1(vel[3 * i], vel[3 * i + 1], vel[3 * i + 2]);
      const Vec3 p0 = start_of_step(s, i, p1, v1, dt, f);
      if (!near_aabb(c, p0, p1, r + surface_tol(p1))) continue;
      if (!column_tested(c)) return 1;
      pending = 2;
    }
    if (pending != 0 && !defer) return columns_clear(i) ? 0 : 1;
    return pending;
  };
  const bool ordered = !shared && end - begin >= kSpatialOrderMin &&
                       std::any_of(colliders.begin(), colliders.end(), [](const Collider& c) {
                         return c.shape == Collider::Shape::mesh;
                       });
  std::uint64_t removed = 0;
  std::size_t reused = 0;
  if (shared && ctx.threads > 1 && end - begin >= kParallelMin) {
    // The responses share state, so they run in index order on one thread, but the rejection
    // test before them reads only its own particle, which no earlier response writes: a large
    // system (the rain demo's splashing drops) tests on every thread first. The same results.
    // (No memo here: it is kept only where particles share nothing.)
    thread_local std::vector<std::uint8_t> near_flags;
    near_flags.resize(end - begin);
    std::uint8_t* flags = near_flags.data();  // this thread's vector, not each worker's own
    const std::ptrdiff_t m = std::ptrdiff_t(end - begin);
#pragma omp parallel for schedule(static) num_threads(ctx.threads)
    for (std::ptrdiff_t k = 0; k < m; ++k) flags[k] = is_near(begin + std::size_t(k), false) != 0 ? 1 : 0;
    CollisionContext local = ctx;
    local.removed_inside = 0;
    for (std::size_t i = begin; i < end; ++i)
      if (near_flags[i - begin] != 0) resolve_kept(i, local);
    ctx.removed_inside += local.removed_inside;
    return;
  }
  const ZOrder zorder = ordered ? ZOrder(colliders) : ZOrder();
#pragma omp parallel num_threads(ctx.threads) if (par) reduction(+ : removed, reused)
  {
    CollisionContext local = ctx;
    local.removed_inside = 0;
    if (ordered) {
      // Each thread's share of the particles (contiguous, so no two threads write to one cache
      // line), those near something visited in Z-order of where they are: neighbours in the
      // list read the same cells and triangles of a mesh, from cache instead of memory. Each
      // resolve() changes its own particle alone, so the order changes no result.
      const std::size_t n = end - begin, t = std::size_t(omp_get_thread_num()),
                        nt = std::size_t(omp_get_num_threads());
      const std::size_t b = begin + n * t / nt, e = begin + n * (t + 1) / nt;
      thread_local std::vector<std::uint64_t> keys, tmp;
      keys.clear();
      // The rejection test a chunk at a time, vectorised in start_of_step()'s plain case.
      constexpr std::size_t kChunk = 256;
      static_assert(kChunk == SweptBounds::kBlock);
      std::uint8_t near[kChunk], pend[kChunk], clear[kChunk];
      thread_local SweptBounds bounds;
      const bool plain = !s.track_prev && f.drag == 0.0f && f.drag_quadratic == 0.0f;
      const Collider* memo_mesh = nullptr;
      std::uint64_t* slots = plain ? column_memo_slots(colliders, e, memo_mesh) : nullptr;
      const double g[3] = {f.gravity[0], f.gravity[1], f.gravity[2]};
      for (std::size_t i0 = b; i0 < e; i0 += kChunk) {
        const std::size_t len = std::min(kChunk, e - i0);
        if (plain) {
          near_block_plain(x + 3 * i0, vel + 3 * i0, s.age.data() + i0, s.radius.data() + i0, len,
                           h, g, colliders, bounds, near, pend);
        } else {
          for (std::size_t k = 0; k < len; ++k) {
            const int v = is_near(i0 + k, true);
            near[k] = v == 1 ? 1 : 0;
            pend[k] = v == 2 ? 1 : 0;
          }
        }
        // A reused response is written here, in index order (its particle's arrays read in
        // sequence, not scattered as in Z-order), and leaves the sort; it changes no other. A
        // particle near only column-tested meshes' AABBs is asked of the memo first (one lying
        // on a terrain is answered there), then of the columns: in the plain case for the
        // block at once (its bounds computed once), else one at a time.
        for (std::size_t k = 0; k < len; ++k) {
          const std::size_t i = i0 + k;
          const bool ask = (near[k] | pend[k]) != 0 &&
                           !(rest != nullptr && rest[4 * i + 3] >= kSleepTime) && !reuse(i, reused);
          pend[k] = ask && near[k] == 0 ? 1 : 0;
          near[k] = ask && near[k] != 0 ? 1 : 0;
        }
        std::fill(clear, clear + len, std::uint8_t{1});
        if (plain)
          for (const Collider& c : colliders)
            if (column_tested(c))
              columns_clear_block(bounds, len, c, pend, clear, 8,
                                  &c == memo_mesh ? slots + i0 : nullptr);
        for (std::size_t k = 0; k < len; ++k) {
          const std::size_t i = i0 + k;
          if (near[k] != 0 || (pend[k] != 0 && !(plain ? clear[k] != 0 : columns_clear(i))))
            keys.push_back(zorder.code(x + 3 * i) << 32 | std::uint64_t(i));
        }
      }
      zorder.sort(keys, tmp);
      // Z-order scatters the particles' own arrays (they stay in index order): their lines are
      // asked for a few particles ahead, so that the loads overlap instead of each missing in
      // turn (a hint only: no result depends on it).
      constexpr std::size_t kAhead = 8;
      const std::size_t nk = keys.size();
      // The mesh grids' cells, blocks and triangles they will read are asked for further ahead.
      MeshPrefetch mesh_ahead(colliders, x, keys);
      for (std::size_t q = 0; q < nk; ++q) {
        mesh_ahead.before(q);
        if (q + kAhead < nk) {
          const std::size_t j = std::size_t(keys[q + kAhead] & 0xffffffffu);
          __builtin_prefetch(x + 3 * j, 1);
          __builtin_prefetch(vel + 3 * j, 1);
          __builtin_prefetch(s.radius.data() + j);
          __builtin_prefetch(s.mass.data() + j);
          __builtin_prefetch(s.age.data() + j);
          if (memo != nullptr) __builtin_prefetch(s.memo.data() + CollideMemo::kStride * j, 1);
        }
        resolve_kept(std::size_t(keys[q] & 0xffffffffu), local);
      }
    } else {
#pragma omp for schedule(static)
      for (std::size_t i = begin; i < end; ++i)
        if (is_near(i, false) != 0 && !reuse(i, reused)) resolve_kept(i, local);
    }
    removed += local.removed_inside;
  }
  ctx.removed_inside += removed;
  if (memo != nullptr) memo->reused = reused;
}

}  // namespace simreel::sim::detail
