// Particle–particle collisions (issue 19's `internal_world` cloud) run by simreel and, when
// Debian's libbullet-dev is found, by Bullet 3.24 in the same process, the engines alternating
// for --reps rounds, so that the ratio is measured under the same machine load.
//
// The scene (bench_collisions' cloud(), the same draws): N spheres of radius 1 cm and mass 1 g at
// ~30 % volume fraction, uniform in a cube of side cbrt(N 4.19e-6 / 0.3) m, velocities uniform in
// [-1, 1] m/s per axis; no gravity, no walls; restitution 0.5 and friction 0.1 between spheres;
// steps of 1/240 s; 16 velocity iterations; one thread each.
//   simreel  a particle system with collide_particles (points that do not rotate; sequential
//            impulses, 16 Gauss–Seidel sweeps, warm started, then 2 sweeps of position
//            projection: particle_collisions.hpp, Coutinho §2.3.1 and §3.6)
//   Bullet   btRigidBody spheres sharing one btSphereShape, btDbvtBroadphase,
//            btSequentialImpulseConstraintSolver with m_numIterations = 16, restitution threshold
//            0.05 m/s (simreel's contact speed), each body's restitution sqrt(0.5) and friction
//            sqrt(0.1) (Bullet multiplies a pair's two), deactivation off, split impulse at
//            Bullet's default; its spheres rotate (as its users get them). The scene is scaled
//            100x for it (g_bullet_scale: Bullet's margins are sized for objects of ~1 m) and its
//            results scaled back.
// Timed, per engine (process CPU time, each step on its own): steps 1-10 from the start (what
// internal_world/N/1 times) and steps 3-32 (internal_world_steady/N/1); medians over the rounds.
// After step 32 each engine's spheres are measured the same way, so that the two are seen to
// solve the same problem: total momentum against the start (pair impulses are equal and
// opposite, so it should stay), kinetic energy over the start's, and the overlapping pairs
// (count, mean and deepest overlap).
//
// Usage: bench_peer_cloud [--n N] [--reps R] [--bullet-scale S]
//        (default 100000 spheres, 3 rounds, Bullet's scene scaled by 100)
// Figures go in issue notes, never thresholds in tests.
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "simreel/sim/random.hpp"
#include "simreel/sim/world.hpp"

#ifdef SIMREEL_HAVE_BULLET
#include <btBulletDynamicsCommon.h>
#endif

namespace {

using namespace simreel::sim;

constexpr double kStep = 1.0 / 240.0;
constexpr double kRadius = 0.01, kMass = 1e-3;
constexpr double kRestitution = 0.5, kFriction = 0.1, kContactSpeed = 0.05;
constexpr int kIterations = 16;
constexpr int kSteps = 32;
/// Bullet is given the scene 100 times larger (lengths and speeds; masses and times as they are),
/// which the collisions do not notice, but which puts its 1 cm spheres at 1 m: Bullet's wiki
/// ("Scaling The World") puts moving objects at 0.05-10 units and scales small ones up (its
/// pool balls by 100), and its absolute margins are sized for ~1 m (the dynamic AABB tree's
/// 5 cm, the 2 cm contact-breaking threshold). At 1 cm its tree reported 353,000
/// overlapping pairs among 1,000 spheres and stepped them in ~100 ms; 10,000 spheres held
/// 74,000, 26,000 and 16,000 pairs scaled by 10, 30 and 100, and stepped in 91, 59 and 57 ms.
double g_bullet_scale = 100.0;  // --bullet-scale

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

/// The start: bench_collisions' cloud(n), draw for draw.
struct Cloud {
  std::vector<Vec3> x, v;
};
Cloud cloud(std::size_t n) {
  Cloud c;
  Rng rng(9);
  const double side = std::cbrt(double(n) * 4.19e-6 / 0.3);
  for (std::size_t i = 0; i < n; ++i) {
    const double px = rng.uniform(0, side), py = rng.uniform(0, side), pz = rng.uniform(0, side);
    c.x.emplace_back(px, py, pz);
    const double vx = rng.uniform(-1, 1), vy = rng.uniform(-1, 1), vz = rng.uniform(-1, 1);
    c.v.emplace_back(vx, vy, vz);
  }
  return c;
}

/// What both engines' spheres are measured by after the last step.
struct State {
  Vec3 momentum = Vec3::Zero();  // (kg m/s)
  double kinetic = 0.0;          // (J)
  std::size_t overlaps = 0;      // pairs closer than two radii
  double mean_overlap = 0.0, max_overlap = 0.0;  // (m) of those pairs
};

/// Momentum, kinetic energy and the overlapping pairs of equal spheres (a counting sort into
/// cells of one diameter, then the 27 cells around each sphere; each pair once).
State measure(const std::vector<Vec3>& x, const std::vector<Vec3>& v) {
  State s;
  for (const Vec3& u : v) {
    s.momentum += kMass * u;
    s.kinetic += 0.5 * kMass * u.squaredNorm();
  }
  const double cell = 2.0 * kRadius;
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (const Vec3& p : x) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  // (Eigen expressions evaluated into arrays: an `auto` would keep references to temporaries)
  using Cell = Eigen::Array<std::int64_t, 3, 1>;
  const auto cell_xyz = [&](const Vec3& p) -> Cell {
    return ((p - lo) / cell).array().floor().cast<std::int64_t>();
  };
  const Cell dims = cell_xyz(hi) + 1;
  const auto cell_of = [&](const Vec3& p) {
    const Cell c = cell_xyz(p);
    return (c[0] * dims[1] + c[1]) * dims[2] + c[2];
  };
  const std::size_t cells = std::size_t(dims[0] * dims[1] * dims[2]);
  std::vector<std::uint32_t> start(cells + 1, 0), order(x.size());
  for (const Vec3& p : x) ++start[std::size_t(cell_of(p)) + 1];
  for (std::size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
  std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
  for (std::size_t i = 0; i < x.size(); ++i) order[fill[std::size_t(cell_of(x[i]))]++] = std::uint32_t(i);
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Cell c = cell_xyz(x[i]);
    for (std::int64_t dx = -1; dx <= 1; ++dx)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const std::int64_t a = c[0] + dx, b = c[1] + dy, d = c[2] + dz;
          if (a < 0 || b < 0 || d < 0 || a >= dims[0] || b >= dims[1] || d >= dims[2]) continue;
          const std::size_t k = std::size_t((a * dims[1] + b) * dims[2] + d);
          for (std::uint32_t q = start[k]; q < start[k + 1]; ++q) {
            const std::uint32_t j = order[q];
            if (j <= i) continue;
            const double depth = 2.0 * kRadius - (x[j] - x[i]).norm();
            if (depth <= 0.0) continue;
            ++s.overlaps;
            s.mean_overlap += depth;
            s.max_overlap = std::max(s.max_overlap, depth);
          }
        }
  }
  if (s.overlaps > 0) s.mean_overlap /= double(s.overlaps);
  return s;
}

struct Result {
  double first10 = 0.0;  // (s) a step, steps 1-10
  double steady = 0.0;   // (s) a step, steps 3-32
  State start, end;
  std::size_t pairs = 0, manifolds = 0;  // Bullet's broadphase pairs and contact manifolds
};

/// Times the steps of `step` (called for steps 1..kSteps) into r.
template <class F>
void time_steps(Result& r, const F& step) {
  for (int s = 1; s <= kSteps; ++s) {
    const double t0 = cpu_seconds();
    step();
    const double dt = cpu_seconds() - t0;
    if (s <= 10) r.first10 += dt / 10.0;
    if (s >= 3) r.steady += dt / double(kSteps - 2);
  }
}

Result run_simreel(const Cloud& c) {
  World world(WorldDef{kStep, 1, kContactSpeed, 1});
  ParticleSystemDef def;
  def.emitter.rate = 0.0;
  def.emitter.max_particles = c.x.size();
  def.gravity = Vec3::Zero();
  def.collide_particles = true;
  def.particle_restitution = kRestitution;
  def.particle_friction = kFriction;
  const auto ps = world.add_particle_system(def);
  for (std::size_t i = 0; i < c.x.size(); ++i) world.spawn_particle(ps, c.x[i], c.v[i], kMass, kRadius, 1e9);
  Result r;
  r.start = measure(c.x, c.v);
  time_steps(r, [&] { (void)world.advance(kStep); });
  const ParticleView view = world.particles(ps);
  std::vector<Vec3> x(view.count), v(view.count);
  for (std::size_t i = 0; i < view.count; ++i) {
    x[i] = Vec3(view.position[3 * i], view.position[3 * i + 1], view.position[3 * i + 2]);
    v[i] = Vec3(view.velocity[3 * i], view.velocity[3 * i + 1], view.velocity[3 * i + 2]);
  }
  r.end = measure(x, v);
  return r;
}

#ifdef SIMREEL_HAVE_BULLET
/// Bullet's world, every part on the heap. It is never destroyed: its teardown removes each
/// body's broadphase pairs by a scan of the whole pair cache (btHashedOverlappingPairCache::
/// removeOverlappingPairsContainingProxy), O(bodies x pairs), minutes for 100k spheres, which
/// no user waits for at the end of a simulation.
struct BulletCloud {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  btSphereShape sphere{btScalar(g_bullet_scale * kRadius)};
  std::vector<btDefaultMotionState> states;
  std::vector<btRigidBody*> bodies;
};

Result run_bullet(const Cloud& c) {
  auto* w = new BulletCloud;  // (never deleted: see BulletCloud)
  w->world.setGravity(btVector3(0, 0, 0));
  w->world.getSolverInfo().m_numIterations = kIterations;
  w->world.getSolverInfo().m_restitutionVelocityThreshold = btScalar(g_bullet_scale * kContactSpeed);
  btVector3 inertia(0, 0, 0);
  w->sphere.calculateLocalInertia(btScalar(kMass), inertia);
  const auto bt = [](const Vec3& a) {
    return btVector3(btScalar(g_bullet_scale * a.x()), btScalar(g_bullet_scale * a.y()),
                     btScalar(g_bullet_scale * a.z()));
  };
  w->states.resize(c.x.size());
  w->bodies.reserve(c.x.size());
  for (std::size_t i = 0; i < c.x.size(); ++i) {
    btTransform t;
    t.setIdentity();
    t.setOrigin(bt(c.x[i]));
    w->states[i] = btDefaultMotionState(t);
    btRigidBody::btRigidBodyConstructionInfo info(btScalar(kMass), &w->states[i], &w->sphere, inertia);
    info.m_restitution = btScalar(std::sqrt(kRestitution));
    info.m_friction = btScalar(std::sqrt(kFriction));
    auto* b = new btRigidBody(info);
    b->setLinearVelocity(bt(c.v[i]));
    b->setActivationState(DISABLE_DEACTIVATION);
    w->world.addRigidBody(b);
    w->bodies.push_back(b);
  }
  Result r;
  r.start = measure(c.x, c.v);
  time_steps(r, [&] { w->world.stepSimulation(btScalar(kStep), 1, btScalar(kStep)); });
  std::vector<Vec3> x(w->bodies.size()), v(w->bodies.size());
  for (std::size_t i = 0; i < w->bodies.size(); ++i) {
    const btVector3& o = w->bodies[i]->getWorldTransform().getOrigin();
    const btVector3& u = w->bodies[i]->getLinearVelocity();
    x[i] = Vec3(o.x(), o.y(), o.z()) / g_bullet_scale;
    v[i] = Vec3(u.x(), u.y(), u.z()) / g_bullet_scale;
  }
  r.end = measure(x, v);
  r.pairs = std::size_t(w->broadphase.getOverlappingPairCache()->getNumOverlappingPairs());
  r.manifolds = std::size_t(w->dispatcher.getNumManifolds());
  return r;
}
#endif

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void print_state(const char* engine, const Result& r) {
  std::printf("  %-8s after %d steps: |momentum - start| %.2e kg m/s (start |p| %.2e), kinetic "
              "energy %.3f of the start's, %zu overlapping pairs (start %zu), mean %.3f mm, "
              "deepest %.3f mm\n",
              engine, kSteps, (r.end.momentum - r.start.momentum).norm(), r.start.momentum.norm(),
              r.end.kinetic / r.start.kinetic, r.end.overlaps, r.start.overlaps,
              1e3 * r.end.mean_overlap, 1e3 * r.end.max_overlap);
}

}  // namespace

int main(int argc, char** argv) {
  std::size_t n = 100000;
  int reps = 3;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--n") == 0 && i + 1 < argc)
      n = std::size_t(std::max(2L, std::atol(argv[++i])));
    else if (std::strcmp(argv[i], "--bullet-scale") == 0 && i + 1 < argc)
      g_bullet_scale = std::max(1e-3, std::atof(argv[++i]));
    else if (std::strcmp(argv[i], "--reps") == 0 && i + 1 < argc)
      reps = std::max(1, std::atoi(argv[++i]));
    else {
      std::fprintf(stderr, "usage: bench_peer_cloud [--n N] [--reps R] [--bullet-scale S]\n");
      return 2;
    }
  }
  const Cloud c = cloud(n);
  std::vector<Result> ours, peer;
  for (int k = 0; k < reps; ++k) {
    ours.push_back(run_simreel(c));
#ifdef SIMREEL_HAVE_BULLET
    peer.push_back(run_bullet(c));
#endif
  }
  const auto col = [](const std::vector<Result>& rs, double Result::*f) {
    std::vector<double> a;
    for (const Result& r : rs) a.push_back(r.*f);
    return median(a);
  };
  std::printf("cloud of %zu spheres, one thread, medians of %d rounds (CPU time a step)\n", n, reps);
  for (const auto& [label, field] : {std::pair{"steps 1-10", &Result::first10},
                                     std::pair{"steps 3-32", &Result::steady}}) {
    const double a = col(ours, field);
    std::printf("  %s  simreel %8.2f ms (%6.3f M particle-steps/s)", label, 1e3 * a, double(n) / a * 1e-6);
    if (peer.empty()) {
      std::printf("  Bullet not built (libbullet-dev not found)\n");
      continue;
    }
    const double b = col(peer, field);
    std::printf("  Bullet %9.2f ms (%6.3f M/s)  Bullet / simreel = %.1f\n", 1e3 * b,
                double(n) / b * 1e-6, b / a);
  }
  print_state("simreel", ours.back());
  if (!peer.empty()) {
    print_state("Bullet", peer.back());
    std::printf("  Bullet   scene scaled by %g; after %d steps its broadphase held %zu pairs and its "
                "dispatcher %zu contact manifolds\n",
                g_bullet_scale, kSteps, peer.back().pairs, peer.back().manifolds);
  }
  return 0;
}
