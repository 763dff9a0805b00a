// The rigid-body peer scenes of issue 12, run by simreel and (when Debian's libbullet-dev is
// found) by Bullet 3.24 in the same process, one after the other, alternating for --reps rounds,
// so the ratio is measured under the same machine load:
//   pyramid  20 rows of 0.5 m boxes (210) on a ground plane, 600 steps of 1/60 s
//   terrain  500 mixed convex bodies (spheres, boxes, capsules, hulls) dropped onto a 2048-triangle
//            height-field mesh, 600 steps of 1/60 s (after Jolt's ConvexVsMesh)
// Frames of 1/60 s. Each engine runs as its users get it: simreel at its default internal step
// (WorldDef::max_step = 1/240 s, 4 steps per frame; --simreel-steps N for N per frame), Bullet
// with stepSimulation(1/60, 1, 1/60) (one step per frame); both 10 velocity iterations, friction
// 0.5, no restitution, density 1000 kg/m³, gravity 9.81, sleeping on (Bullet's deactivation,
// simreel's WorldDef::allow_sleeping; --bullet-no-sleep turns Bullet's off).
// Reported per engine: CPU time per frame (median over the rounds), the pyramid's top-box drift
// from its start (m), and the number of bodies that ended below the ground / terrain (tunnelled).
// The hulls are one irregular 10-point rock (its hull has fewer vertices), scaled by the body's
// size: btConvexHullShape with Bullet's default collision margin, and the mass simreel computes
// from the hull's boundary (App. D), the centre of mass near the frame origin in both.
//
// Usage: bench_bodies [--reps N] [--scene pyramid|terrain|all] [--bullet-no-sleep] [--simreel-steps N]
//                     [--simreel-substeps N] (WorldDef::body_substeps: the soft step when >= 2).
// Figures go in issue notes, never
// thresholds in tests.
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "simreel/sim/body.hpp"
#include "simreel/sim/world.hpp"

#ifdef SIMREEL_HAVE_BULLET
#include <btBulletDynamicsCommon.h>
#endif

namespace {

using namespace simreel::sim;

constexpr double kStep = 1.0 / 60.0;
constexpr int kSteps = 600;
constexpr int kRows = 20;
constexpr double kBox = 0.5;       // (m) pyramid box side
constexpr double kGap = 0.02;      // (m) horizontal gap between pyramid boxes
constexpr int kTerrainCells = 32;  // 32 x 32 cells, 2 triangles each: 2048 triangles
constexpr double kTerrainSize = 40.0;
constexpr int kDropped = 500;
bool g_bullet_no_sleep = false;  // --bullet-no-sleep: Bullet without deactivation
int g_simreel_steps = 4;         // --simreel-steps N: simreel's internal steps per frame
int g_simreel_substeps = 1;      // --simreel-substeps N: WorldDef::body_substeps (soft step when >= 2)

WorldDef simreel_world() {
  WorldDef def{kStep / g_simreel_steps, 1, 0.05, 1};
  def.body_substeps = g_simreel_substeps;
  return def;
}

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

struct Result {
  double seconds_per_step = 0.0;
  double top_drift = 0.0;  // (m) pyramid only
  int tunnelled = 0;       // below the ground or the terrain surface under it (by > 5 cm)
  int off_edge = 0;        // terrain: rolled off the edge of the 40 m mesh (not a tunnelling)
};

/// Terrain scene: counts a body at p as off the edge or as tunnelled (below the surface).
void classify_terrain(const Vec3& p, Result& r);

/// Pyramid box k (row r, column c): rows sit exactly on each other, columns kGap apart.
std::vector<Vec3> pyramid_centres() {
  std::vector<Vec3> p;
  for (int r = 0; r < kRows; ++r) {
    const int n = kRows - r;
    for (int c = 0; c < n; ++c)
      p.emplace_back((c - 0.5 * (n - 1)) * (kBox + kGap), 0.0, 0.5 * kBox + r * kBox);
  }
  return p;
}

double terrain_height(double x, double y) { return 0.8 * std::sin(0.35 * x) * std::cos(0.3 * y); }

void classify_terrain(const Vec3& p, Result& r) {
  if (std::abs(p.x()) > 0.5 * kTerrainSize || std::abs(p.y()) > 0.5 * kTerrainSize)
    ++r.off_edge;
  else if (p.z() < terrain_height(p.x(), p.y()) - 0.05)
    ++r.tunnelled;
}

void terrain_mesh(std::vector<Vec3>& v, std::vector<std::array<std::uint32_t, 3>>& t) {
  const int n = kTerrainCells;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = -0.5 * kTerrainSize + kTerrainSize * i / n;
      const double y = -0.5 * kTerrainSize + kTerrainSize * j / n;
      v.emplace_back(x, y, terrain_height(x, y));
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const auto a = std::uint32_t(j * (n + 1) + i), b = a + 1, c = a + std::uint32_t(n + 1), d = c + 1;
      t.push_back({a, b, d});
      t.push_back({a, d, c});
    }
}

/// Body k of the terrain scene: kind k % 4 (sphere, box, capsule, hull), on a 10 x 10 grid in 5
/// layers, 1.6 m apart, starting 3 m above the terrain's highest point.
struct Drop {
  int kind;
  Vec3 p;
  double size;
};
/// The terrain scene's hull: ten points of an irregular rock about `size` (m) across its
/// half-width, their centroid at the origin.
std::vector<Vec3> rock(double size) {
  std::vector<Vec3> p{{1.0, 0.0, 0.2},   {-0.8, 0.5, 0.0}, {-0.6, -0.7, 0.1}, {0.3, 0.9, -0.2},
                      {0.2, -0.8, -0.3}, {0.0, 0.0, 0.9},  {0.1, 0.2, -0.8},  {0.7, 0.4, 0.5},
                      {-0.5, 0.1, 0.7},  {-0.3, -0.3, -0.7}};
  Vec3 c = Vec3::Zero();
  for (const Vec3& v : p) c += v / double(p.size());
  for (Vec3& v : p) v = size * (v - c);
  return p;
}

/// (kg) Mass of the rock of size 1 at density 1000, as simreel computes it from the hull's
/// boundary (App. D); a rock of size s has s³ times this.
double rock_unit_mass() {
  World world;
  BodyDef b;
  b.type = BodyType::dynamic;
  b.shapes = {ShapeDef::convex_hull(rock(1.0))};
  b.shapes[0].density = 1000.0;
  return world.motion(world.add_body(b)).mass;
}

std::vector<Drop> drops() {
  std::vector<Drop> d;
  for (int k = 0; k < kDropped; ++k) {
    const int i = k % 10, j = (k / 10) % 10, layer = k / 100;
    d.push_back({k % 4, Vec3((i - 4.5) * 1.6, (j - 4.5) * 1.6, 3.0 + 1.6 * layer),
                 0.25 + 0.05 * double((k * 7) % 5)});
  }
  return d;
}

// ---------------------------------------------------------------------------------------------
// simreel

Result run_simreel_pyramid() {
  World world(simreel_world());
  BodyDef ground;
  ground.shapes = {ShapeDef::plane()};
  ground.shapes[0].material = Material(0.0, 0.5);
  world.add_body(ground);
  std::vector<BodyHandle> boxes;
  for (const Vec3& c : pyramid_centres()) {
    BodyDef b;
    b.type = BodyType::dynamic;
    b.pose.translation = c;
    b.shapes = {ShapeDef::box(Vec3::Constant(0.5 * kBox))};
    b.shapes[0].material = Material(0.0, 0.5);
    b.shapes[0].density = 1000.0;
    boxes.push_back(world.add_body(b));
  }
  const Vec3 top0 = pyramid_centres().back();
  const double t0 = cpu_seconds();
  for (int s = 0; s < kSteps; ++s) (void)world.advance(kStep);
  Result r;
  r.seconds_per_step = (cpu_seconds() - t0) / kSteps;
  r.top_drift = (world.pose(boxes.back()).translation - top0).norm();
  for (const BodyHandle h : boxes) r.tunnelled += world.pose(h).translation.z() < 0.0 ? 1 : 0;
  return r;
}

Result run_simreel_terrain() {
  World world(simreel_world());
  BodyDef ground;
  ShapeDef mesh;
  mesh.type = ShapeType::mesh;
  terrain_mesh(mesh.vertices, mesh.triangles);
  mesh.material = Material(0.0, 0.5);
  ground.shapes = {mesh};
  world.add_body(ground);
  std::vector<BodyHandle> bodies;
  for (const Drop& d : drops()) {
    BodyDef b;
    b.type = BodyType::dynamic;
    b.pose.translation = d.p;
    b.shapes = {d.kind == 0   ? ShapeDef::sphere(d.size)
                : d.kind == 1 ? ShapeDef::box(Vec3::Constant(d.size))
                : d.kind == 2 ? ShapeDef::capsule(0.6 * d.size, d.size)
                              : ShapeDef::convex_hull(rock(d.size))};
    b.shapes[0].material = Material(0.0, 0.5);
    bodies.push_back(world.add_body(b));
  }
  const double t0 = cpu_seconds();
  for (int s = 0; s < kSteps; ++s) (void)world.advance(kStep);
  Result r;
  r.seconds_per_step = (cpu_seconds() - t0) / kSteps;
  for (const BodyHandle h : bodies) classify_terrain(world.pose(h).translation, r);
  return r;
}

// ---------------------------------------------------------------------------------------------
// Bullet

#ifdef SIMREEL_HAVE_BULLET
struct BulletWorld {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  std::vector<btCollisionShape*> shapes;
  std::vector<btRigidBody*> bodies;
  std::vector<btDefaultMotionState*> states;

  BulletWorld() {
    world.setGravity(btVector3(0, 0, -9.81));
    world.getSolverInfo().m_numIterations = 10;
  }
  ~BulletWorld() {
    for (btRigidBody* b : bodies) world.removeRigidBody(b);
    for (btRigidBody* b : bodies) delete b;
    for (btDefaultMotionState* s : states) delete s;
    for (btCollisionShape* s : shapes) delete s;
  }
  btRigidBody* add(btCollisionShape* shape, double mass, const Vec3& p) {
    shapes.push_back(shape);
    btVector3 inertia(0, 0, 0);
    if (mass > 0.0) shape->calculateLocalInertia(btScalar(mass), inertia);
    btTransform t;
    t.setIdentity();
    t.setOrigin(btVector3(btScalar(p.x()), btScalar(p.y()), btScalar(p.z())));
    auto* state = new btDefaultMotionState(t);
    states.push_back(state);
    btRigidBody::btRigidBodyConstructionInfo info(btScalar(mass), state, shape, inertia);
    info.m_friction = 0.5;
    info.m_restitution = 0.0;
    auto* body = new btRigidBody(info);
    if (g_bullet_no_sleep) body->setActivationState(DISABLE_DEACTIVATION);
    world.addRigidBody(body);
    bodies.push_back(body);
    return body;
  }
  void run() {
    for (int s = 0; s < kSteps; ++s) world.stepSimulation(btScalar(kStep), 1, btScalar(kStep));
  }
};

Vec3 position(const btRigidBody* b) {
  const btVector3& o = b->getWorldTransform().getOrigin();
  return Vec3(o.x(), o.y(), o.z());
}

Result run_bullet_pyramid() {
  BulletWorld w;
  w.add(new btStaticPlaneShape(btVector3(0, 0, 1), 0), 0.0, Vec3::Zero());
  const double mass = 1000.0 * kBox * kBox * kBox;
  std::vector<btRigidBody*> boxes;
  for (const Vec3& c : pyramid_centres()) {
    const btScalar h = btScalar(0.5 * kBox);
    boxes.push_back(w.add(new btBoxShape(btVector3(h, h, h)), mass, c));
  }
  const Vec3 top0 = pyramid_centres().back();
  const double t0 = cpu_seconds();
  w.run();
  Result r;
  r.seconds_per_step = (cpu_seconds() - t0) / kSteps;
  r.top_drift = (position(boxes.back()) - top0).norm();
  for (const btRigidBody* b : boxes) r.tunnelled += position(b).z() < 0.0 ? 1 : 0;
  return r;
}

Result run_bullet_terrain() {
  btTriangleMesh mesh;  // declared before the world, so it outlives the shape that points to it
  BulletWorld w;
  std::vector<Vec3> v;
  std::vector<std::array<std::uint32_t, 3>> t;
  terrain_mesh(v, t);
  for (const auto& tri : t)
    mesh.addTriangle(btVector3(btScalar(v[tri[0]].x()), btScalar(v[tri[0]].y()), btScalar(v[tri[0]].z())),
                      btVector3(btScalar(v[tri[1]].x()), btScalar(v[tri[1]].y()), btScalar(v[tri[1]].z())),
                      btVector3(btScalar(v[tri[2]].x()), btScalar(v[tri[2]].y()), btScalar(v[tri[2]].z())));
  w.add(new btBvhTriangleMeshShape(&mesh, true), 0.0, Vec3::Zero());
  std::vector<btRigidBody*> bodies;
  const double pi = 3.14159265358979323846;
  const double rock_mass = rock_unit_mass();
  for (const Drop& d : drops()) {
    const double s = d.size;
    if (d.kind == 0) {
      bodies.push_back(w.add(new btSphereShape(btScalar(s)), 1000.0 * 4.0 / 3.0 * pi * s * s * s, d.p));
    } else if (d.kind == 1) {
      bodies.push_back(w.add(new btBoxShape(btVector3(btScalar(s), btScalar(s), btScalar(s))),
                             1000.0 * 8.0 * s * s * s, d.p));
    } else if (d.kind == 2) {
      const double r = 0.6 * s;  // capsule: radius r, segment 2 s
      bodies.push_back(w.add(new btCapsuleShapeZ(btScalar(r), btScalar(2.0 * s)),
                             1000.0 * (pi * r * r * 2.0 * s + 4.0 / 3.0 * pi * r * r * r), d.p));
    } else {
      auto* hull = new btConvexHullShape();
      for (const Vec3& p : rock(s)) hull->addPoint(btVector3(btScalar(p.x()), btScalar(p.y()), btScalar(p.z())));
      bodies.push_back(w.add(hull, rock_mass * s * s * s, d.p));
    }
  }
  const double t0 = cpu_seconds();
  w.run();
  Result r;
  r.seconds_per_step = (cpu_seconds() - t0) / kSteps;
  for (const btRigidBody* b : bodies) classify_terrain(position(b), r);
  return r;
}
#endif

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void report(const char* scene, const std::vector<Result>& ours, const std::vector<Result>& peer) {
  std::vector<double> a, b;
  for (const Result& r : ours) a.push_back(r.seconds_per_step);
  for (const Result& r : peer) b.push_back(r.seconds_per_step);
  std::printf("%-8s simreel %8.3f ms/frame  top drift %.4f m  tunnelled %d  off the edge %d\n", scene,
              1e3 * median(a), ours.back().top_drift, ours.back().tunnelled, ours.back().off_edge);
  if (peer.empty()) {
    std::printf("%-8s Bullet   not built (libbullet-dev not found)\n", scene);
    return;
  }
  std::printf("%-8s Bullet  %8.3f ms/frame  top drift %.4f m  tunnelled %d  off the edge %d\n", scene,
              1e3 * median(b), peer.back().top_drift, peer.back().tunnelled, peer.back().off_edge);
  std::printf("%-8s ratio simreel / Bullet = %.2f (median of %zu rounds, CPU time; simreel %d "
              "steps per frame, %d substeps)\n", scene, median(a) / median(b), a.size(), g_simreel_steps, g_simreel_substeps);
}

}  // namespace

int main(int argc, char** argv) {
  int reps = 3;
  std::string scene = "all";
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--reps") == 0 && i + 1 < argc) reps = std::max(1, std::atoi(argv[++i]));
    else if (std::strcmp(argv[i], "--scene") == 0 && i + 1 < argc) scene = argv[++i];
    else if (std::strcmp(argv[i], "--bullet-no-sleep") == 0) g_bullet_no_sleep = true;
    else if (std::strcmp(argv[i], "--simreel-steps") == 0 && i + 1 < argc)
      g_simreel_steps = std::max(1, std::atoi(argv[++i]));
    else if (std::strcmp(argv[i], "--simreel-substeps") == 0 && i + 1 < argc)
      g_simreel_substeps = std::max(1, std::atoi(argv[++i]));
    else {
      std::fprintf(stderr, "usage: bench_bodies [--reps N] [--scene pyramid|terrain|all] [--bullet-no-sleep] [--simreel-steps N] [--simreel-substeps N]\n");
      return 2;
    }
  }
  for (const std::string s : {"pyramid", "terrain"}) {
    if (scene != "all" && scene != s) continue;
    std::vector<Result> ours, peer;
    for (int k = 0; k < reps; ++k) {
      ours.push_back(s == "pyramid" ? run_simreel_pyramid() : run_simreel_terrain());
#ifdef SIMREEL_HAVE_BULLET
      peer.push_back(s == "pyramid" ? run_bullet_pyramid() : run_bullet_terrain());
#endif
    }
    report(s.c_str(), ours, peer);
  }
  return 0;
}
