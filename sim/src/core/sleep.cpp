// Sleeping of dynamic bodies (body_dynamics.hpp): rest timers, islands by union–find over this
// step's contact manifolds, waking by touch, by removal and by the World API. After Box2D v2's
// b2Island sleep rule (Catto) and Bullet's deactivation; Coutinho does not treat it, but a
// scene of bodies at rest otherwise pays the full contact solve every step forever.
//
// Determinism: everything runs serially in rigid-entry and manifold order; island ids are the
// smallest rigid index of the island.
#include <algorithm>

#include "core/union_find.hpp"
#include "core/world_state.hpp"
#include "rigid/integrate.hpp"

namespace simreel::sim::detail {
namespace {

void fit(BodyDynamics& d) {
  const std::size_t n = d.rigid.size();
  d.rest_time.resize(n, 0.0);
  d.island.resize(n, 0);
}

bool asleep(const RigidBodies& r, std::uint32_t i) { return i != kStaticBody && r.asleep[i]; }

/// Moves: an awake dynamic body, or a kinematic one with a velocity.
bool moving(const RigidBodies& r, std::uint32_t i) {
  if (i == kStaticBody || r.asleep[i]) return false;
  if (r.is_dynamic(i)) return true;
  return !r.linear_velocity[i].isZero(0.0) || !r.angular_velocity[i].isZero(0.0);
}

}  // namespace

void wake_island(WorldState& w, std::uint32_t i) {
  BodyDynamics& d = w.dyn;
  if (!asleep(d.rigid, i)) return;
  fit(d);
  const std::uint32_t id = d.island[i];
  for (std::uint32_t k = 0; k < d.rigid.size(); ++k)
    if (d.rigid.asleep[k] && d.island[k] == id) {
      wake(d.rigid, k);
      d.rest_time[k] = 0.0;
    }
}

void wake_all(WorldState& w) {
  BodyDynamics& d = w.dyn;
  fit(d);
  for (std::uint32_t k = 0; k < d.rigid.size(); ++k) {
    wake(d.rigid, k);
    d.rest_time[k] = 0.0;
  }
}

void wake_particles_near(WorldState& w, const Collider& c) {
  std::vector<ParticleSystemState>& systems = w.systems.dense();
  std::vector<bool> wake(systems.size(), false);
  for (std::size_t u = 0; u < systems.size(); ++u) {
    const ParticleStore& s = systems[u].store;
    if (!s.track_rest) continue;
    for (std::size_t i = 0; i < s.count && !wake[u]; ++i) {
      if (s.rest[4 * i + 3] < kSleepTime) continue;  // awake: an impact wakes what it meets
      const Vec3 x(s.position[3 * i], s.position[3 * i + 1], s.position[3 * i + 2]);
      const double reach = 1.5 * double(s.radius[i]) + 1e-3;
      wake[u] = c.shape == Collider::Shape::plane
                    ? c.normal.dot(x - c.point) < reach
                    : ((x - c.aabb_center).cwiseAbs() - c.aabb_half).maxCoeff() < reach;
    }
  }
  wake_systems(w, wake);
}

void wake_systems(WorldState& w, std::vector<bool> wake) {
  std::vector<ParticleSystemState>& systems = w.systems.dense();
  for (std::size_t u = 0; u < systems.size(); ++u) {
    const std::string& g = systems[u].def.collision_group;
    if (!wake[u] || g.empty()) continue;
    for (std::size_t v = 0; v < systems.size(); ++v)
      if (systems[v].def.collision_group == g) wake[v] = true;
  }
  for (std::size_t u = 0; u < systems.size(); ++u) {
    ParticleStore& s = systems[u].store;
    if (!wake[u] || !s.track_rest) continue;
    for (std::size_t i = 0; i < s.count; ++i) s.rest[4 * i + 3] = 0.0f;
  }
}

bool wake_touched(WorldState& w) {
  BodyDynamics& d = w.dyn;
  bool woke = false;
  for (const BodyManifold& m : d.manifolds) {
    if (m.manifold.count == 0) continue;
    if (asleep(d.rigid, m.rigid_a) && moving(d.rigid, m.rigid_b)) {
      wake_island(w, m.rigid_a);
      woke = true;
    }
    if (asleep(d.rigid, m.rigid_b) && moving(d.rigid, m.rigid_a)) {
      wake_island(w, m.rigid_b);
      woke = true;
    }
  }
  // A joint pulls: a sleeping body joined to a moving one wakes (joints.cpp gathers them).
  for (const auto* links : {&d.joint_bodies, &d.spring_bodies})
  for (const JointBodies& j : *links) {
    if (asleep(d.rigid, j.a) && moving(d.rigid, j.b)) {
      wake_island(w, j.a);
      woke = true;
    }
    if (asleep(d.rigid, j.b) && moving(d.rigid, j.a)) {
      wake_island(w, j.b);
      woke = true;
    }
  }
  return woke;
}

void update_sleep(WorldState& w, double h) {
  BodyDynamics& d = w.dyn;
  RigidBodies& r = d.rigid;
  fit(d);
  const std::uint32_t n = std::uint32_t(r.size());
  d.parent.resize(n);
  // Only a body that touches something rests: a free body costs nothing to integrate, and one
  // drifting slowly through space (or floating without gravity) must keep its momentum.
  for (std::uint32_t i = 0; i < n; ++i) d.parent[i] = kStaticBody;  // "touching" marks for now
  for (const BodyManifold& m : d.manifolds) {
    if (m.manifold.count == 0 || m.first_point == kCarriedManifold) continue;
    if (m.rigid_a != kStaticBody) d.parent[m.rigid_a] = 0;
    if (m.rigid_b != kStaticBody) d.parent[m.rigid_b] = 0;
  }
  for (const auto* links : {&d.joint_bodies, &d.spring_bodies})
  for (const JointBodies& j : *links) {  // a joint or spring holds a body as a contact does
    if (j.a != kStaticBody) d.parent[j.a] = 0;
    if (j.b != kStaticBody) d.parent[j.b] = 0;
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    if (!r.is_dynamic(i)) continue;
    const bool resting = d.parent[i] == 0 &&
                         r.linear_velocity[i].squaredNorm() <= kSleepLinearSpeed * kSleepLinearSpeed &&
                         r.angular_velocity[i].squaredNorm() <= kSleepAngularSpeed * kSleepAngularSpeed;
    d.rest_time[i] = resting && d.allow_sleeping ? d.rest_time[i] + h : 0.0;
  }
  for (std::uint32_t i = 0; i < n; ++i) d.parent[i] = i;
  // Islands: dynamic bodies joined by a contact; static and kinematic bodies do not join
  // islands (a floor does not make everything on it one island). A body touching a moving
  // kinematic body never rests.
  for (const BodyManifold& m : d.manifolds) {
    if (m.manifold.count == 0 || m.first_point == kCarriedManifold) continue;
    const bool da = m.rigid_a != kStaticBody && r.is_dynamic(m.rigid_a);
    const bool db = m.rigid_b != kStaticBody && r.is_dynamic(m.rigid_b);
    if (da && db) uf_unite(d.parent, m.rigid_a, m.rigid_b);
    if (da && moving(r, m.rigid_b) && !db) d.rest_time[m.rigid_a] = 0.0;
    if (db && moving(r, m.rigid_a) && !da) d.rest_time[m.rigid_b] = 0.0;
  }
  for (const auto* links : {&d.joint_bodies, &d.spring_bodies})
  for (const JointBodies& j : *links) {  // joined bodies sleep and wake together
    const bool da = j.a != kStaticBody && r.is_dynamic(j.a);
    const bool db = j.b != kStaticBody && r.is_dynamic(j.b);
    if (da && db) uf_unite(d.parent, j.a, j.b);
    if (da && moving(r, j.b) && !db) d.rest_time[j.a] = 0.0;
    if (db && moving(r, j.a) && !da) d.rest_time[j.b] = 0.0;
  }
  if (!d.allow_sleeping) return;
  // An island sleeps when its least-rested body has rested long enough: the root keeps the
  // island's minimum rest time in island[] scratch (as a flag: 1 = some body is not ready).
  for (std::uint32_t i = 0; i < n; ++i)
    if (r.is_dynamic(i)) d.island[uf_find(d.parent, i)] = 0;
  for (std::uint32_t i = 0; i < n; ++i)
    if (r.is_dynamic(i) && d.rest_time[i] < kTimeToSleep) d.island[uf_find(d.parent, i)] = 1;
  // Non-roots first (island[] of a root is still its flag), then the roots; the island id is
  // the root's index.
  for (std::uint32_t i = 0; i < n; ++i) {
    if (!r.is_dynamic(i)) continue;
    const std::uint32_t root = uf_find(d.parent, i);
    if (root != i && d.island[root] == 0) {
      d.island[i] = root;
      sleep(r, i);
    }
  }
  for (std::uint32_t i = 0; i < n; ++i)
    if (r.is_dynamic(i) && uf_find(d.parent, i) == i && d.island[i] == 0) {
      d.island[i] = i;
      sleep(r, i);
    }
}

}  // namespace simreel::sim::detail
