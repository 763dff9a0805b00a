// The resting-on-a-plane fast path of the particle collision pass (collision/plane_rest.hpp, float
// arithmetic) gives the general path's results (double) to a few roundings of a float, and never
// leaves a particle inside the plane (Coutinho §3.4 swept sphere against the plane, §3.6.1
// friction, §3.6.3 resting contact). The general path is reached with the same plane plus a
// second, far one that nothing comes near (the fast path takes one plane only; the far plane
// changes no value of the general path: its sweep finds nothing and its projections do nothing).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "collision/collider_impl.hpp"
#include "collision/particle_blocks.hpp"
#include "collision/plane_rest.hpp"
#include "simreel/sim/random.hpp"

namespace simreel::sim {
namespace {

struct Case {
  bool quadratic = false;   // quadratic drag
  bool two_mu = false;      // a static coefficient other than the dynamic one
  bool stored = false;      // the start of the step stored (RK4 systems)
  Vec3 normal = Vec3::UnitZ();
  bool all_resting = false;  // every particle resting on the plane (settled blocks)
  Vec3 point = Vec3(0.3, -0.2, 0.1);
  bool edges = false;  // some particles given edge values (below)
};

/// Edge values on every 7th particle, for the upright plane's form (kUp in plane_rest.cpp), which
/// takes the normal component of each n · x alone and must send every lane it cannot match bit
/// for bit to the general path: signed zeros in the tangential components (with a plane through
/// the origin they reach the products as -0), zero normal velocity, a zero radius, tangential
/// values that are infinite, not a number, or as large as a float holds.
void give_edge_values(detail::ParticleStore& s) {
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float big = std::numeric_limits<float>::max();
  for (std::size_t i = 0; i < s.count; i += 7) {
    float* x = &s.position[3 * i];
    float* v = &s.velocity[3 * i];
    switch ((i / 7) % 8) {
      case 0: x[0] = -0.0f; x[1] = -0.0f; v[0] = -0.0f; v[1] = -0.0f; break;
      case 1: v[0] = -0.0f; v[1] = 0.0f; v[2] = -0.0f; break;
      case 2: s.radius[i] = 0.0f; x[2] = 0.0f; x[0] = -0.0f; break;
      case 3: v[0] = inf; break;
      case 4: v[1] = nan; break;
      case 5: x[0] = big; x[1] = -big; break;
      case 6: v[0] = big; v[1] = big; break;
      default: x[1] = -inf; break;
    }
  }
}

/// A system of n particles around the plane through `q` with normal `nrm`, integrated one step
/// of h by the caller's rule: the first `dense` lie on the plane (blocks resolved in place), the
/// rest alternate between on it and well above it (blocks resolved through a compacted list);
/// velocities cover resting, sliding, slow and fast impacts and separation, and a few newborns.
detail::ParticleStore make_store(std::size_t n, std::size_t dense, const Vec3& q, const Vec3& nrm,
                                 bool stored, double h, bool all_resting = false) {
  detail::ParticleStore s;
  s.track_prev = stored;
  s.reserve(n);
  s.append(n);
  Rng rng(7);
  const Vec3 t1 = nrm.unitOrthogonal(), t2 = nrm.cross(t1);
  for (std::size_t i = 0; i < n; ++i) {
    const double r = rng.uniform(0.005, 0.05);
    const bool on = all_resting || i < dense || i % 2 == 0;
    // Height of the centre above the plane after the step: around r (resting particles have
    // sunk by about g h²), or far above.
    const double z = on ? r + rng.uniform(-4e-4, all_resting ? -1e-6 : 2e-5) : r + rng.uniform(0.5, 2.0);
    const double kind = all_resting ? 0.7 * rng.uniform() : rng.uniform();
    const double vn = kind < 0.7 ? -rng.uniform(0.0, 0.06)   // resting: about g h or less
                      : kind < 0.8 ? -rng.uniform(0.5, 5.0)  // an impact that bounces
                      : kind < 0.9 ? rng.uniform(0.0, 1.0)   // leaving
                                   : 0.0;
    const double slide = kind < 0.35 ? 0.0 : rng.uniform(0.0, 5.0);
    const double phi = rng.uniform(0.0, 6.283185307179586);
    const Vec3 p = q + (rng.uniform(-10, 10)) * t1 + (rng.uniform(-10, 10)) * t2 + z * nrm;
    const Vec3 v = vn * nrm + slide * (std::cos(phi) * t1 + std::sin(phi) * t2);
    for (int a = 0; a < 3; ++a) {
      s.position[3 * i + std::size_t(a)] = float(p[a]);
      s.velocity[3 * i + std::size_t(a)] = float(v[a]);
      if (stored)  // where it was a step before: a little higher and behind
        s.prev_position[3 * i + std::size_t(a)] = float(p[a] - h * v[a] + 1e-4 * nrm[a]);
    }
    s.radius[i] = float(r);
    s.mass[i] = float(rng.uniform(1e-4, 1e-2));
    s.age[i] = float(i % 17 == 0 && !all_resting ? rng.uniform(0.0, h) : 10.0);  // some born this step
    s.lifetime[i] = 100.0f;
  }
  return s;
}

Vec3 stored(const float* p) { return Vec3(p[0], p[1], p[2]); }

void expect_close_to_general_path(const Case& c) {
  const double h = 1.0 / 240;
  const Vec3 q = c.point;
  detail::Collider ground;
  ground.normal = c.normal.normalized();
  ground.point = q;
  ground.material = Material(0.5, 0.3);
  if (c.two_mu) ground.material.static_friction = 0.6;
  detail::Collider far = ground;
  far.point = q - 1e5 * ground.normal;
  detail::ForceParams f{};
  const Vec3 g = -9.81 * Vec3::UnitZ();
  for (int a = 0; a < 3; ++a) f.gravity[a] = float(g[a]);
  f.drag = 2e-4f;
  f.drag_quadratic = c.quadratic ? 3e-5f : 0.0f;
  const std::size_t n = 4000, dense = 2048;
  detail::ParticleStore fast = make_store(n, dense, q, ground.normal, c.stored, h, c.all_resting);
  detail::ParticleStore general = make_store(n, dense, q, ground.normal, c.stored, h, c.all_resting);
  if (c.edges) {
    give_edge_values(fast);
    give_edge_values(general);
  }
  const std::vector<detail::Collider> one{ground}, two{ground, far};
  detail::CollisionContext ctx_fast, ctx_general;
  detail::collide(fast, 0, n, h, one, ctx_fast, f);
  detail::collide(general, 0, n, h, two, ctx_general, f);
  // The same to a few roundings of a float, and the pass did something: most particles near
  // the plane moved. The tolerance is eight float epsilons of the scale the float arithmetic
  // works at: for positions the particle's distance from the plane's point, plus the margin by
  // which keep_stored_out() steps a stored float out of the plane when its first try rounds
  // back in (2^k 1.2e-7 (1 + |x|) on try k: the two paths may need different tries); for
  // velocities its speed before and after the pass (the friction's 1 - dv_t / |v_t| cancels).
  std::size_t differ = 0, moved = 0, inside = 0, exact = 0;
  double worst_x = 0.0, worst_v = 0.0;
  detail::ParticleStore before = make_store(n, dense, q, ground.normal, c.stored, h, c.all_resting);
  if (c.edges) give_edge_values(before);
  constexpr double kEps = std::numeric_limits<float>::epsilon();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 xf = stored(&fast.position[3 * i]);
    const Vec3 xg = stored(&general.position[3 * i]);
    const Vec3 vf = stored(&fast.velocity[3 * i]);
    const Vec3 vg = stored(&general.velocity[3 * i]);
    const Vec3 v0 = stored(&before.velocity[3 * i]);
    const bool finite = xg.allFinite() && vg.allFinite();
    if (!finite) {  // non-finite lanes go to the general path: the same bits
      differ += std::memcmp(&fast.position[3 * i], &general.position[3 * i], 3 * sizeof(float)) != 0 ||
                std::memcmp(&fast.velocity[3 * i], &general.velocity[3 * i], 3 * sizeof(float)) != 0;
      continue;
    }
    const double scale_x = std::max((xg - q).cwiseAbs().maxCoeff(), 1e-3) +
                           0.5 * (1.0 + xg.cwiseAbs().maxCoeff());
    const double scale_v = std::max({vg.norm(), v0.norm(), 1e-3});
    const double ex = (xf - xg).cwiseAbs().maxCoeff() / (kEps * scale_x);
    const double ev = (vf - vg).cwiseAbs().maxCoeff() / (kEps * scale_v);
    worst_x = std::max(worst_x, ex);
    worst_v = std::max(worst_v, ev);
    differ += !(ex <= 8.0 && ev <= 8.0);
    exact += xf == xg && vf == vg;
    inside += ground.normal.dot(xf - q) - double(fast.radius[i]) < 0.0;
    for (int a = 0; a < 3; ++a) moved += fast.velocity[3 * i + std::size_t(a)] != before.velocity[3 * i + std::size_t(a)];
  }
  EXPECT_EQ(differ, 0u) << "worst position error " << worst_x << " eps, velocity " << worst_v << " eps";
  EXPECT_EQ(inside, 0u);
  EXPECT_GT(moved, c.edges ? n / 2 : n);
  // The fast path took part: some results are not the double path's bits (about a tenth here; in
  // the upright plane's form x and y are mostly the same floats).
  EXPECT_LT(exact, n - n / 50);
}

TEST(SimPlaneRest, FastPathMatchesGeneralPath) {
  expect_close_to_general_path({});
}

TEST(SimPlaneRest, FastPathMatchesGeneralPathWithQuadraticDragStaticFrictionAndTilt) {
  expect_close_to_general_path({true, false, false, Vec3::UnitZ()});
  expect_close_to_general_path({false, true, false, Vec3::UnitZ()});
  expect_close_to_general_path({false, false, false, Vec3(0.2, -0.1, 1.0)});
  expect_close_to_general_path({true, true, false, Vec3(-0.3, 0.1, 1.0)});
}

TEST(SimPlaneRest, FastPathMatchesGeneralPathWithTheStartOfStepStored) {
  expect_close_to_general_path({false, false, true, Vec3::UnitZ()});
  expect_close_to_general_path({true, true, true, Vec3(0.1, 0.2, 1.0)});
}

TEST(SimPlaneRest, FastPathMatchesGeneralPathOnSettledBlocks) {
  // Every lane of every block resting: the blocks skip their per-lane follow-up, except where
  // a stored float lies a hair inside the (tilted) plane and must be stepped out.
  expect_close_to_general_path({false, false, false, Vec3(0.2, -0.1, 1.0), true});
  expect_close_to_general_path({false, true, true, Vec3(-0.3, 0.1, 1.0), true});
  expect_close_to_general_path({false, false, false, Vec3::UnitZ(), true});
}

TEST(SimPlaneRest, UprightPlaneFormMatchesGeneralPathOnEdgeValues) {
  for (const Vec3& point : {Vec3(0.3, -0.2, 0.1), Vec3(0.0, 0.0, 0.0)}) {
    for (bool quadratic : {false, true}) {
      Case c;
      c.point = point;
      c.quadratic = quadratic;
      c.two_mu = quadratic;
      c.edges = true;
      expect_close_to_general_path(c);
      c.all_resting = true;
      expect_close_to_general_path(c);
      c.stored = true;
      expect_close_to_general_path(c);
    }
  }
}

/// plane_rest()'s parameters for the plane through q with unit normal nrm: gravity -9.81 m/s² along
/// z, linear drag k_d (kg/s) and, when quadratic, c_2 = 0.15 k_d (kg/m), Coulomb coefficient 0.3
/// (static 0.6 when two_mu), contact speed 0.05 m/s, the start of the step stored or not.
detail::PlaneRestParams plane_params(const Vec3& q, const Vec3& nrm, double drag, bool quadratic,
                                     bool two_mu, bool stored) {
  detail::PlaneRestParams p{};
  for (int a = 0; a < 3; ++a) {
    p.n[a] = nrm[a];
    p.q[a] = q[a];
  }
  p.g[2] = -9.81;
  p.drag = drag;
  p.drag_quadratic = quadratic ? 0.15 * drag : 0.0;
  p.mu = 0.3;
  p.mu_static = two_mu ? 0.6 : 0.3;
  p.contact_speed = 0.05;
  p.start_stored = stored;
  return p;
}

/// plane_rest()'s loop for lanes that share one mass, radius and step (kUniform in
/// plane_rest.cpp, which reads lane 0's) gives each lane the bits of the per-lane loop: the same
/// lanes are run once alone and once beside an extra lane of another mass, which makes the batch
/// non-uniform. Over every form: upright and tilted planes, the start of the step stored or
/// recovered, linear and quadratic drag, one or two friction coefficients.
TEST(SimPlaneRest, SharedMassRadiusAndStepGiveThePerLaneBits) {
  constexpr std::size_t n = 200;
  for (int form = 0; form < 16; ++form) {
    const bool stored = form & 1, quadratic = form & 2, two_mu = form & 4, tilted = form & 8;
    const Vec3 nrm = tilted ? Vec3(0.2, -0.1, 1.0).normalized() : Vec3::UnitZ();
    const Vec3 q(0.3, -0.2, 0.1);
    // (a strong drag, so that the mass counts: k / m = 1 / s)
    const detail::PlaneRestParams p = plane_params(q, nrm, 2e-3, quadratic, two_mu, stored);
    auto alone = std::make_unique<detail::PlaneRestLanes>();
    const double h = 1.0 / 240, r = 0.01, m = 2e-3;
    const Vec3 t1 = nrm.unitOrthogonal(), t2 = nrm.cross(t1);
    Rng rng(11);
    for (std::size_t k = 0; k < n; ++k) {
      // resting (sunk by about g h²), sliding, bouncing and leaving particles
      const double kind = rng.uniform();
      const double z = r + rng.uniform(-4e-4, 2e-5);
      const double vn = kind < 0.7 ? -rng.uniform(0.0, 0.06) : kind < 0.85 ? -rng.uniform(0.5, 5.0) : rng.uniform(0.0, 1.0);
      const double slide = kind < 0.35 ? 0.0 : rng.uniform(0.0, 5.0);
      const Vec3 x = q + rng.uniform(-10, 10) * t1 + rng.uniform(-10, 10) * t2 + z * nrm;
      const Vec3 v = vn * nrm + slide * t1;
      alone->bx[k] = float(x[0]);
      alone->by[k] = float(x[1]);
      alone->bz[k] = float(x[2]);
      alone->vx[k] = float(v[0]);
      alone->vy[k] = float(v[1]);
      alone->vz[k] = float(v[2]);
      alone->ax[k] = float(x[0] - h * v[0] + 1e-4 * nrm[0]);
      alone->ay[k] = float(x[1] - h * v[1] + 1e-4 * nrm[1]);
      alone->az[k] = float(x[2] - h * v[2] + 1e-4 * nrm[2]);
      alone->m[k] = m;
      alone->r[k] = r;
      alone->dt[k] = h;
    }
    auto beside = std::make_unique<detail::PlaneRestLanes>(*alone);
    beside->m[n] = 2.0 * m;  // the extra lane: another mass
    beside->r[n] = r;
    beside->dt[n] = h;
    beside->bz[n] = float(q[2] + r);
    detail::plane_rest(*alone, n, p);
    detail::plane_rest(*beside, n + 1, p);
    std::size_t resolved = 0;
    for (std::size_t k = 0; k < n; ++k) resolved += alone->ok[k] != 0.0;
    EXPECT_GT(resolved, n / 3) << "form " << form;
    const auto same = [&](const auto& a, const auto& b) { return std::memcmp(a, b, n * sizeof(a[0])) == 0; };
    EXPECT_TRUE(same(alone->ox, beside->ox) && same(alone->oy, beside->oy) && same(alone->oz, beside->oz))
        << "form " << form;
    EXPECT_TRUE(same(alone->ovx, beside->ovx) && same(alone->ovy, beside->ovy) && same(alone->ovz, beside->ovz))
        << "form " << form;
    EXPECT_TRUE(same(alone->ok, beside->ok)) << "form " << form;
  }
}

TEST(SimPlaneRest, GroundThroughTheOriginFormGivesTheUprightFormsBits) {
  // An upright plane through z = +0 (every scene's ground left where it is) takes a loop that
  // drops the arithmetic around the plane's point; it must give the general upright loop's bits,
  // lane for lane, in every upright form (the start stored or recovered, linear or quadratic
  // drag, one or two friction coefficients), with per-lane and shared scalars, on edge values
  // (signed zeros, a zero radius at z = 0, infinities, NaNs, the largest floats) as well as
  // resting, sliding, bouncing and leaving particles. Planes at -0, above and below the origin
  // must not take it (they would differ).
  const double h = 1.0 / 240;
  std::size_t resolved = 0, compared = 0;
  for (const double q2 : {0.0, -0.0, 1e-3, -2.5}) {
    for (int form = 0; form < 16; ++form) {
      const bool stored = form & 1, quadratic = form & 2, two_mu = form & 4, shared = form & 8;
      const Vec3 q(0.0, 0.0, q2);
      detail::ParticleStore st = make_store(detail::kPlaneRestLanes, detail::kPlaneRestLanes / 2, q,
                                            Vec3::UnitZ(), stored, h);
      if (shared) {
        for (std::size_t i = 0; i < st.count; ++i) {
          st.mass[i] = 2e-3f;
          st.radius[i] = 0.01f;
          st.age[i] = 10.0f;
        }
      }
      give_edge_values(st);
      for (std::size_t i = 3; i < st.count; i += 29) {  // at z = -0, resting with -0 speeds
        st.position[3 * i + 2] = -0.0f;
        st.velocity[3 * i + 2] = i % 2 == 0 ? -0.0f : -0.02f;
        if (!shared) st.radius[i] = 0.0f;
      }
      if (shared) std::fill(st.radius.begin(), st.radius.end(), 0.01f);  // (edge values set some to 0)
      const detail::PlaneRestParams p = plane_params(q, Vec3::UnitZ(), 2e-4, quadratic, two_mu, stored);
      auto a = std::make_unique<detail::PlaneRestLanes>();
      const std::size_t n = st.count;
      detail::gather_block(st.position.data(), st.velocity.data(), stored ? st.prev_position.data() : nullptr,
                           st.mass.data(), st.radius.data(), st.age.data(), h, n, *a);
      ASSERT_EQ(a->shared, shared);
      auto b = std::make_unique<detail::PlaneRestLanes>(*a);
      detail::plane_rest(*a, n, p);
      detail::plane_rest(*b, n, p, false);
      const auto same = [&](const auto& x, const auto& y) { return std::memcmp(x, y, n * sizeof(x[0])) == 0; };
      EXPECT_TRUE(same(a->ox, b->ox) && same(a->oy, b->oy) && same(a->oz, b->oz)) << "q2 " << q2 << ", form " << form;
      EXPECT_TRUE(same(a->ovx, b->ovx) && same(a->ovy, b->ovy) && same(a->ovz, b->ovz)) << "q2 " << q2 << ", form " << form;
      EXPECT_TRUE(same(a->ok, b->ok)) << "q2 " << q2 << ", form " << form;
      for (std::size_t k = 0; k < n; ++k) resolved += a->ok[k] != 0.0f;
      compared += n;
    }
  }
  EXPECT_GT(resolved, compared / 6);  // the lanes resolved many particles (not all sent away)
}

TEST(SimPlaneRest, BlocksThatShareMassAndRadiusGiveEachParticleItsOwnBits) {
  // An emitter's particles share one mass and radius: collide() then gathers only lane 0 of
  // them (and of the step) for a block, and every later reading of a lane's radius or step
  // (the near test, the general path for an impact, the step out of the plane) must take lane
  // 0's. The lanes are kept between blocks, so a reading of lane k would find an earlier
  // block's values: a block of newborns of other radii and steps goes first to leave them
  // there. Each particle collided in a block must get the bits it gets collided alone.
  const double h = 1.0 / 240;
  const Vec3 q(0.3, -0.2, 0.1);
  detail::Collider ground;
  ground.point = q;
  ground.material = Material(0.5, 0.3);
  detail::ForceParams f{};
  f.gravity[2] = -9.81f;
  f.drag = 2e-4f;
  detail::CollisionContext ctx;
  ctx.threads = 1;  // one thread: the lanes the newborns leave are the ones read next
  detail::ParticleStore newborns = make_store(detail::kPlaneRestLanes, detail::kPlaneRestLanes, q,
                                              Vec3::UnitZ(), false, h, true);
  Rng rng(23);
  for (std::size_t i = 0; i < newborns.count; ++i) newborns.age[i] = float(h * rng.uniform(0.1, 0.9));
  detail::collide(newborns, 0, newborns.count, h, {ground}, ctx, f);
  const std::size_t n = 3000;
  detail::ParticleStore blocked;
  blocked.reserve(n);
  blocked.append(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float r = 0.02f;
    const bool impact = rng.uniform() < 0.3;  // bounces: the general path, with the lane's step
    const double vn = impact ? -rng.uniform(0.5, 5.0) : -rng.uniform(0.0, 0.06);
    const double slide = rng.uniform(0.0, 3.0), phi = rng.uniform(0.0, 6.283185307179586);
    const Vec3 p(q.x() + rng.uniform(-10, 10), q.y() + rng.uniform(-10, 10), q.z() + r + rng.uniform(-4e-4, 2e-5));
    const Vec3 v(slide * std::cos(phi), slide * std::sin(phi), vn);
    for (int a = 0; a < 3; ++a) {
      blocked.position[3 * i + std::size_t(a)] = float(p[a]);
      blocked.velocity[3 * i + std::size_t(a)] = float(v[a]);
    }
    blocked.radius[i] = r;
    blocked.mass[i] = 3e-3f;
    blocked.age[i] = 10.0f;
    blocked.lifetime[i] = 100.0f;
  }
  detail::ParticleStore alone = blocked;
  detail::collide(blocked, 0, n, h, {ground}, ctx, f);
  for (std::size_t i = 0; i < n; ++i) detail::collide(alone, i, i + 1, h, {ground}, ctx, f);
  std::size_t differ = 0, bounced = 0, rest = 0;
  for (std::size_t i = 0; i < n; ++i) {
    differ += std::memcmp(&blocked.position[3 * i], &alone.position[3 * i], 3 * sizeof(float)) != 0 ||
              std::memcmp(&blocked.velocity[3 * i], &alone.velocity[3 * i], 3 * sizeof(float)) != 0;
    bounced += alone.velocity[3 * i + 2] > 0.1f;
    rest += alone.velocity[3 * i + 2] == 0.0f;
  }
  EXPECT_EQ(differ, 0u);
  EXPECT_GT(bounced, n / 5);  // the impacts bounced (the general path ran) ...
  EXPECT_GT(rest, n / 2);     // ... and the rest came to rest on the plane (the lanes ran)
  // Then sparse blocks of particles each with its own mass and radius (the compacted list, which
  // fills every lane it uses): the shared block before them must not make them read lane 0.
  detail::ParticleStore sparse = make_store(n, 0, q, Vec3::UnitZ(), false, h);
  detail::ParticleStore sparse_alone = sparse;
  detail::collide(blocked, 0, n, h, {ground}, ctx, f);  // a shared block last
  detail::collide(sparse, 0, n, h, {ground}, ctx, f);
  for (std::size_t i = 0; i < n; ++i) detail::collide(sparse_alone, i, i + 1, h, {ground}, ctx, f);
  EXPECT_EQ(std::memcmp(sparse.position.data(), sparse_alone.position.data(), 3 * n * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(sparse.velocity.data(), sparse_alone.velocity.data(), 3 * n * sizeof(float)), 0);
}

TEST(SimPlaneRest, LargeSystemIsTheSameAtAnyThreadCount) {
  const double h = 1.0 / 240;
  detail::Collider ground;
  ground.material = Material(0.5, 0.3);
  detail::ForceParams f{};
  f.gravity[2] = -9.81f;
  f.drag = 2e-4f;
  const std::size_t n = 40000;  // over kParallelMin: the blocks are split over the threads
  std::vector<detail::ParticleStore> out;
  for (int threads : {1, 2, 3}) {
    out.push_back(make_store(n, n / 2, Vec3::Zero(), Vec3::UnitZ(), false, h));
    detail::CollisionContext ctx;
    ctx.threads = threads;
    detail::collide(out.back(), 0, n, h, {ground}, ctx, f);
  }
  for (std::size_t t = 1; t < out.size(); ++t) {
    EXPECT_EQ(std::memcmp(out[t].position.data(), out[0].position.data(), 3 * n * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(out[t].velocity.data(), out[0].velocity.data(), 3 * n * sizeof(float)), 0);
  }
}

}  // namespace
}  // namespace simreel::sim
