// The articulated-body peer scene of issue 13: twenty ragdolls dropped onto the stairs of
// demos/scenes/ragdolls_stairs.json, run by simreel and (when Debian's libbullet-dev is found) by
// Bullet 3.24 in the same process, alternating for --reps rounds so the ratio is measured under
// the same machine load.
//
// The scene is the demo's stairs (landing + 8 static box steps + ground plane) with its three
// ragdolls replaced by 20 (the scene format's `ragdolls` generator: 15 capsules and boxes, 14
// joints each: cone-twist spherical joints at neck, waist, shoulders, wrists and hips, limited
// hinges at elbows, knees and ankles), a 4 x 5 grid, standing or sitting, yaw varied, their lowest
// point 1 m above the landing's top (z = 2.8 m), at rest. simreel builds it through the program's
// scene loader (app::scene_from_json + app::build_world); Bullet gets the very same bodies and
// joints by walking the loaded app::Scene:
//   bodies   btBoxShape / btCapsuleShapeZ / btStaticPlaneShape at the same poses, the same masses
//            and the same (exact) inertia tensors (simreel's closed forms, sim/src/rigid/
//            mass_properties; Bullet's own capsule inertia is a box approximation)
//   joints   spherical with limits -> btConeTwistConstraint (twist axis = the joint's axis, swing
//            spans = cone_angle, twist span = twist_upper), hinge -> btHingeConstraint (axis, the
//            same [lower, upper] on the angle of b relative to a), fixed -> btFixedConstraint;
//            frames built at the anchor so every angle is 0 at registration; collisions between
//            jointed bodies disabled (addConstraint(c, true)), as simreel does by default
//   contact  the same combined coefficients: every material is friction 0.7, restitution 0.05;
//            simreel mixes sqrt(mu_a mu_b) and max(e_a, e_b), Bullet multiplies, so Bullet's
//            bodies get sqrt(0.7) and sqrt(0.05); restitution only above 0.5 m/s in both
//   step     frames of 1/60 s, N internal steps each (--steps, default 4): simreel
//            WorldDef::max_step = 1/(60 N) (its default 1/240 s is N = 4), Bullet
//            stepSimulation(1/60, N, 1/(60 N)); --bullet-steps M overrides Bullet's alone (M = 1:
//            Bullet as its users get it). Bullet: 10 solver iterations (its default, simreel's
//            contact sweeps). Sleeping on in both (--no-sleep: off in both).
// Joint damping: the generator's default 0.5 N m s/rad is set to 0 here (Bullet's cone-twist and
// hinge have no viscous joint damping), so both engines simulate the same undamped joints.
//
// Reported per engine: CPU time per 1/60 s frame (median over the rounds; the joint and speed
// readings below are taken outside the timed calls), the largest joint separation seen at the end
// of any frame (simreel: World::joint_state().anchor_error; Bullet: the distance between the two
// pivots, body a's frame origin and body b's, in the world), the largest anchor error at the last
// frame, the largest body speed at the end (rest state: m/s and rad/s), bodies below the ground
// (tunnelled) and bodies that left the stairs' footprint.
//
// --simreel-substeps S: simreel's soft step (WorldDef::body_substeps = S), N / S internal steps
// per frame of S substeps each, so its solver runs at the same 1/(60 N) s as Bullet's steps.
// Usage: bench_ragdolls [--reps N] [--steps N] [--simreel-substeps S] [--bullet-steps N] [--frames N] [--no-sleep]
//                       [--simreel-only] [--write-scene FILE]  (writes the 20-ragdoll scene JSON and exits)
// Figures go in docs/benchmarks.md and issue notes, never thresholds in tests.
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rigid/mass_properties.hpp"
#include "scene.hpp"
#include "simreel/sim/world.hpp"

#ifdef SIMREEL_HAVE_BULLET
#include <BulletDynamics/ConstraintSolver/btFixedConstraint.h>
#include <btBulletDynamicsCommon.h>
#endif

namespace {

using namespace simreel;
using sim::Vec3;
using nlohmann::json;

constexpr double kFrame = 1.0 / 60.0;
constexpr double kFriction = 0.7;
constexpr double kRestitution = 0.05;
constexpr double kRestitutionThreshold = 0.5;  // (m/s) simreel's ContactSettings default
int g_frames = 600;
int g_steps = 4;          // internal steps per frame, both engines
int g_bullet_steps = 0;   // 0: g_steps
int g_substeps = 1;       // --simreel-substeps S: simreel takes g_steps / S internal steps of S substeps
bool g_no_sleep = false;
bool g_simreel_only = false;  // --simreel-only: for profiling

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

/// The 20-ragdoll scene: the demo's stairs with every material at (kRestitution, kFriction).
json bench_scene() {
  std::ifstream in(SIMREEL_SOURCE_DIR "/demos/scenes/ragdolls_stairs.json");
  if (!in) {
    std::fprintf(stderr, "bench_ragdolls: cannot read %s\n", SIMREEL_SOURCE_DIR "/demos/scenes/ragdolls_stairs.json");
    std::exit(2);
  }
  json doc = json::parse(in);
  doc["description"] = "bench_ragdolls: 20 ragdolls dropped onto the stairs of ragdolls_stairs.json";
  doc["fps"] = 60;
  doc["frames"] = g_frames;
  doc["simulation"]["max_step"] = kFrame * g_substeps / g_steps;
  if (g_substeps > 1) doc["simulation"]["body_substeps"] = g_substeps;
  for (json& c : doc["colliders"]) {
    c["friction"] = kFriction;
    c["restitution"] = kRestitution;
  }
  json dolls = json::array();
  for (int k = 0; k < 20; ++k) {
    const int i = k % 4, j = k / 4;  // 4 along the stairs (x), 5 across (y)
    json d;
    d["name"] = "doll" + std::to_string(k);
    d["position"] = {-1.5 + 1.0 * i, -1.2 + 0.6 * j, 2.8};
    d["pose"] = k % 3 == 2 ? "sitting" : "standing";
    d["yaw_deg"] = double((k * 67) % 360 - 180);
    d["joint_damping"] = 0.0;
    d["friction"] = kFriction;
    d["restitution"] = kRestitution;
    d["color"] = {0.2 + 0.03 * k, 0.3, 0.7 - 0.03 * k};
    dolls.push_back(d);
  }
  doc["ragdolls"] = dolls;
  return doc;
}

struct Result {
  double seconds_per_frame = 0.0;
  double max_anchor_error = 0.0;    // (m) over every frame end
  double final_anchor_error = 0.0;  // (m) at the last frame
  double mean_anchor_error = 0.0;   // (m) the largest of each frame, averaged over the frames
  std::size_t worst_joint = 0;      // Scene::joints index of max_anchor_error
  double max_speed = 0.0;           // (m/s) largest body speed at the end
  double max_spin = 0.0;            // (rad/s)
  int moving = 0;                   // bodies faster than 0.05 m/s or 2 deg/s at the end (not at rest)
  int tunnelled = 0;                // centre below the ground
  int off_stairs = 0;               // centre beyond the stairs' footprint (x in [-2, 3.2], |y| < 1.6):
                                    // hanging over a side edge or on the ground
  int bodies = 0, joints = 0;

  /// Frame f's largest anchor error e (m), at joint `worst`, into the maximum, mean and last.
  void record_frame(int f, double e, std::size_t worst) {
    if (e > max_anchor_error) max_anchor_error = e, worst_joint = worst;
    mean_anchor_error += e / g_frames;
    if (f + 1 == g_frames) final_anchor_error = e;
  }
};

void classify(const Vec3& p, const Vec3& v, const Vec3& w, Result& r) {
  r.max_speed = std::max(r.max_speed, v.norm());
  r.max_spin = std::max(r.max_spin, w.norm());
  if (v.norm() > 0.05 || w.norm() > 2.0 * 3.141592653589793 / 180.0) ++r.moving;
  if (p.z() < -0.02) ++r.tunnelled;
  if (p.x() < -2.0 || p.x() > 3.2 || std::abs(p.y()) > 1.6) ++r.off_stairs;
}

// ---------------------------------------------------------------------------------------------
// simreel

Result run_simreel(const app::Scene& scene) {
  app::SceneWorld sw = app::build_world(scene);
  sim::World& world = sw.world;
  const std::vector<sim::JointHandle> joints = world.joints();
  Result r;
  r.joints = int(joints.size());
  double seconds = 0.0;
  for (int f = 0; f < g_frames; ++f) {
    const double t0 = cpu_seconds();
    (void)world.advance(kFrame);
    seconds += cpu_seconds() - t0;
    double e = 0.0;
    std::size_t worst = 0;
    for (std::size_t k = 0; k < joints.size(); ++k) {
      const double ek = world.joint_state(joints[k]).anchor_error;
      if (ek > e) e = ek, worst = k;
    }
    r.record_frame(f, e, worst);
  }
  r.seconds_per_frame = seconds / g_frames;
  for (std::size_t i = 0; i < scene.colliders.size(); ++i) {
    if (!scene.colliders[i].dynamic.enabled) continue;
    ++r.bodies;
    const sim::BodyMotion m = world.motion(sw.colliders[i]);
    classify(m.center_of_mass, m.linear_velocity, m.angular_velocity, r);
  }
  return r;
}

// ---------------------------------------------------------------------------------------------
// Bullet

#ifdef SIMREEL_HAVE_BULLET
btVector3 bt(const Vec3& v) { return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())); }
Vec3 from_bt(const btVector3& v) { return Vec3(v.x(), v.y(), v.z()); }
btTransform bt(const sim::Transform& t) {
  const sim::Quat& q = t.rotation;
  return btTransform(btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())), bt(t.translation));
}

/// A world frame at `anchor` whose column `col` is `axis` (unit).
btTransform joint_frame(const Vec3& anchor, const Vec3& axis, int col) {
  const Vec3 a = axis.normalized();
  const Vec3 p = (std::abs(a.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(a).normalized();
  const Vec3 q = a.cross(p);
  sim::Mat3 m;
  // Right-handed columns with `axis` at `col`: (a, p, q) for x, (q, a, p) for y, (p, q, a) for z.
  if (col == 0) m << a, p, q;
  else if (col == 1) m << q, a, p;
  else m << p, q, a;
  btMatrix3x3 b(btScalar(m(0, 0)), btScalar(m(0, 1)), btScalar(m(0, 2)), btScalar(m(1, 0)), btScalar(m(1, 1)),
                btScalar(m(1, 2)), btScalar(m(2, 0)), btScalar(m(2, 1)), btScalar(m(2, 2)));
  return btTransform(b, bt(anchor));
}

struct BulletWorld {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  std::vector<btCollisionShape*> shapes;
  std::vector<btRigidBody*> bodies;  // scene collider order
  std::vector<btDefaultMotionState*> states;
  std::vector<btTypedConstraint*> constraints;
  struct Pivot {
    btRigidBody* a;
    btRigidBody* b;
    btVector3 in_a, in_b;  // pivot in each body's frame
  };
  std::vector<Pivot> pivots;
  int hinge_sign = 1;

  BulletWorld() {
    world.setGravity(btVector3(0, 0, btScalar(-9.81)));
    world.getSolverInfo().m_numIterations = 10;
    world.getSolverInfo().m_restitutionVelocityThreshold = btScalar(kRestitutionThreshold);
  }
  ~BulletWorld() {
    for (btTypedConstraint* c : constraints) world.removeConstraint(c);
    for (btTypedConstraint* c : constraints) delete c;
    for (btRigidBody* b : bodies) world.removeRigidBody(b);
    for (btRigidBody* b : bodies) delete b;
    for (btDefaultMotionState* s : states) delete s;
    for (btCollisionShape* s : shapes) delete s;
  }
  btRigidBody* add(btCollisionShape* shape, double mass, const sim::Mat3& inertia, const btTransform& t) {
    shapes.push_back(shape);
    auto* state = new btDefaultMotionState(t);
    states.push_back(state);
    const btVector3 diag(btScalar(inertia(0, 0)), btScalar(inertia(1, 1)), btScalar(inertia(2, 2)));
    btRigidBody::btRigidBodyConstructionInfo info(btScalar(mass), state, shape, mass > 0 ? diag : btVector3(0, 0, 0));
    info.m_friction = btScalar(std::sqrt(kFriction));
    info.m_restitution = btScalar(std::sqrt(kRestitution));
    auto* body = new btRigidBody(info);
    if (g_no_sleep) body->setActivationState(DISABLE_DEACTIVATION);
    world.addRigidBody(body);
    bodies.push_back(body);
    return body;
  }
  void constrain(btTypedConstraint* c, btRigidBody* a, btRigidBody* b, const btTransform& fa, const btTransform& fb) {
    world.addConstraint(c, true);
    constraints.push_back(c);
    pivots.push_back({a, b, fa.getOrigin(), fb.getOrigin()});
  }
  /// The largest pivot separation (m) and its joint (Scene::joints order).
  double max_anchor_error(std::size_t& worst) const {
    double e = 0.0;
    for (std::size_t k = 0; k < pivots.size(); ++k) {
      const Pivot& p = pivots[k];
      const btVector3 wa = p.a->getCenterOfMassTransform() * p.in_a;
      const btVector3 wb = p.b->getCenterOfMassTransform() * p.in_b;
      const double ek = double((wa - wb).length());
      if (ek > e) e = ek, worst = k;
    }
    return e;
  }
};

/// Sign of Bullet's hinge angle against simreel's (b relative to a, right-handed about the axis).
int bullet_hinge_sign() {
  btBoxShape box(btVector3(1, 1, 1));
  btRigidBody a(1, nullptr, &box), b(1, nullptr, &box);
  const btTransform f = joint_frame(Vec3::Zero(), Vec3(0.3, -0.4, 0.8), 2);
  btHingeConstraint h(a, b, f, f, false);
  btTransform tb;
  tb.setIdentity();
  tb.setRotation(btQuaternion(bt(Vec3(0.3, -0.4, 0.8).normalized()), btScalar(0.3)));
  b.setCenterOfMassTransform(tb);
  const double angle = h.getHingeAngle(a.getCenterOfMassTransform(), b.getCenterOfMassTransform());
  return angle > 0 ? 1 : -1;
}

Result run_bullet(const app::Scene& scene) {
  BulletWorld w;
  w.hinge_sign = bullet_hinge_sign();
  static bool said = false;
  if (!said) std::fprintf(stderr, "Bullet's hinge angle has the sign %+d of simreel's\n", w.hinge_sign);
  said = true;
  const sim::Mat3 none = sim::Mat3::Zero();
  for (const app::ColliderScene& c : scene.colliders) {
    using T = app::ColliderScene::Type;
    const bool dyn = c.dynamic.enabled;
    if (c.type == T::plane) {
      w.add(new btStaticPlaneShape(bt(c.plane.normal.normalized()), btScalar(c.plane.normal.normalized().dot(c.plane.point))),
            0.0, none, btTransform::getIdentity());
    } else if (c.type == T::box) {
      sim::Mat3 inertia = none;
      if (dyn) inertia = sim::detail::with_mass(sim::detail::box_mass(c.box.half_extents, 1000.0), c.dynamic.mass).inertia;
      w.add(new btBoxShape(bt(c.box.half_extents)), dyn ? c.dynamic.mass : 0.0, inertia, bt(c.box.transform));
    } else if (c.type == T::capsule) {
      sim::Mat3 inertia = none;
      if (dyn)
        inertia = sim::detail::with_mass(sim::detail::capsule_mass(c.capsule.radius, c.capsule.half_height, 1000.0),
                                         c.dynamic.mass).inertia;
      w.add(new btCapsuleShapeZ(btScalar(c.capsule.radius), btScalar(2.0 * c.capsule.half_height)),
            dyn ? c.dynamic.mass : 0.0, inertia, bt(c.capsule.transform));
    } else {
      std::fprintf(stderr, "bench_ragdolls: collider %s: only planes, boxes and capsules are mapped to Bullet\n",
                   c.name.c_str());
      std::exit(2);
    }
    if (dyn && c.dynamic.mass <= 0.0) {
      std::fprintf(stderr, "bench_ragdolls: body %s has no explicit mass\n", c.name.c_str());
      std::exit(2);
    }
  }
  for (const app::JointScene& j : scene.joints) {
    if (j.index_a == app::JointScene::kWorld || j.index_b == app::JointScene::kWorld) {
      std::fprintf(stderr, "bench_ragdolls: joint %s: joints to the world are not mapped\n", j.def.name.c_str());
      std::exit(2);
    }
    btRigidBody* a = w.bodies[j.index_a];
    btRigidBody* b = w.bodies[j.index_b];
    const sim::JointDef& d = j.def;
    const int col = d.type == sim::JointType::hinge ? 2 : 0;  // hinge axis = z, twist axis = x
    const btTransform f = joint_frame(d.anchor, d.axis, col);
    const btTransform fa = a->getCenterOfMassTransform().inverse() * f;
    const btTransform fb = b->getCenterOfMassTransform().inverse() * f;
    if (d.type == sim::JointType::hinge) {
      auto* h = new btHingeConstraint(*a, *b, fa, fb, false);
      if (d.limit_enabled) {
        if (w.hinge_sign > 0) h->setLimit(btScalar(d.lower_angle), btScalar(d.upper_angle));
        else h->setLimit(btScalar(-d.upper_angle), btScalar(-d.lower_angle));
      }
      w.constrain(h, a, b, fa, fb);
    } else if (d.type == sim::JointType::spherical) {
      if (d.limit_enabled) {
        auto* ct = new btConeTwistConstraint(*a, *b, fa, fb);
        const double twist = std::max(-d.twist_lower, d.twist_upper);
        ct->setLimit(btScalar(d.cone_angle), btScalar(d.cone_angle), btScalar(std::min(twist, 3.14159)));
        w.constrain(ct, a, b, fa, fb);
      } else {
        auto* p = new btPoint2PointConstraint(*a, *b, fa.getOrigin(), fb.getOrigin());
        w.constrain(p, a, b, fa, fb);
      }
    } else {
      auto* fx = new btFixedConstraint(*a, *b, fa, fb);
      w.constrain(fx, a, b, fa, fb);
    }
  }
  const int steps = g_bullet_steps > 0 ? g_bullet_steps : g_steps;
  Result r;
  r.joints = int(w.pivots.size());
  double seconds = 0.0;
  for (int f = 0; f < g_frames; ++f) {
    const double t0 = cpu_seconds();
    w.world.stepSimulation(btScalar(kFrame), steps, btScalar(kFrame / steps));
    seconds += cpu_seconds() - t0;
    std::size_t worst = 0;
    const double e = w.max_anchor_error(worst);
    r.record_frame(f, e, worst);
  }
  r.seconds_per_frame = seconds / g_frames;
  for (std::size_t i = 0; i < scene.colliders.size(); ++i) {
    if (!scene.colliders[i].dynamic.enabled) continue;
    ++r.bodies;
    const btRigidBody* b = w.bodies[i];
    classify(from_bt(b->getCenterOfMassPosition()), from_bt(b->getLinearVelocity()), from_bt(b->getAngularVelocity()),
             r);
  }
  return r;
}
#endif

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void print(const app::Scene& scene, const char* engine, int steps, const std::vector<Result>& rs) {
  std::vector<double> t;
  double worst = 0.0;
  for (const Result& r : rs) {
    t.push_back(r.seconds_per_frame);
    worst = std::max(worst, r.max_anchor_error);
  }
  const Result& r = rs.back();
  std::printf("%-8s %d steps/frame %8.3f ms/frame\n", engine, steps, 1e3 * median(t));
  std::printf("%-8s anchor error: max %.2e m (%s), frame mean %.2e m, last frame %.2e m\n", engine, worst,
              scene.joints[r.worst_joint].def.name.c_str(), r.mean_anchor_error, r.final_anchor_error);
  std::printf("%-8s end: max speed %.3f m/s %.3f rad/s, %d of %d bodies moving (> 0.05 m/s or 2 deg/s), "
              "tunnelled %d, beyond the stairs %d (%d joints)\n",
              engine, r.max_speed, r.max_spin, r.moving, r.bodies, r.tunnelled, r.off_stairs, r.joints);
}

}  // namespace

int main(int argc, char** argv) {
  int reps = 3;
  std::string write_scene;
  for (int i = 1; i < argc; ++i) {
    auto count = [&](int& v) { v = std::max(1, std::atoi(argv[++i])); };
    if (std::strcmp(argv[i], "--reps") == 0 && i + 1 < argc) count(reps);
    else if (std::strcmp(argv[i], "--steps") == 0 && i + 1 < argc) count(g_steps);
    else if (std::strcmp(argv[i], "--bullet-steps") == 0 && i + 1 < argc) count(g_bullet_steps);
    else if (std::strcmp(argv[i], "--simreel-substeps") == 0 && i + 1 < argc) count(g_substeps);
    else if (std::strcmp(argv[i], "--frames") == 0 && i + 1 < argc) count(g_frames);
    else if (std::strcmp(argv[i], "--no-sleep") == 0) g_no_sleep = true;
    else if (std::strcmp(argv[i], "--simreel-only") == 0) g_simreel_only = true;
    else if (std::strcmp(argv[i], "--write-scene") == 0 && i + 1 < argc) write_scene = argv[++i];
    else {
      std::fprintf(stderr,
                   "usage: bench_ragdolls [--reps N] [--steps N] [--simreel-substeps S] [--bullet-steps N] [--frames N] [--no-sleep] [--simreel-only] "
                   "[--write-scene FILE]\n");
      return 2;
    }
  }
  const json doc = bench_scene();
  if (!write_scene.empty()) {
    std::ofstream(write_scene) << doc.dump(1) << "\n";
    return 0;
  }
  app::Scene scene = app::scene_from_json(doc, "bench_ragdolls");
  scene.world.allow_sleeping = !g_no_sleep;  // not a scene key
  std::vector<Result> ours, peer;
  for (int k = 0; k < reps; ++k) {
    ours.push_back(run_simreel(scene));
#ifdef SIMREEL_HAVE_BULLET
    if (!g_simreel_only) peer.push_back(run_bullet(scene));
#endif
  }
  std::printf("20 ragdolls on the stairs, %d frames of 1/60 s, %d rounds (CPU time, median)%s\n", g_frames, reps,
              g_no_sleep ? ", no sleeping" : "");
  print(scene, "simreel", g_steps, ours);
  if (g_substeps > 1)
    std::printf("simreel  (soft step: %d internal steps/frame of %d substeps)\n", g_steps / g_substeps, g_substeps);
  if (peer.empty()) {
    std::printf("Bullet   not built (libbullet-dev not found)\n");
    return 0;
  }
  print(scene, "Bullet", g_bullet_steps > 0 ? g_bullet_steps : g_steps, peer);
  std::vector<double> a, b;
  for (const Result& r : ours) a.push_back(r.seconds_per_frame);
  for (const Result& r : peer) b.push_back(r.seconds_per_frame);
  std::printf("ratio simreel / Bullet = %.2f\n", median(a) / median(b));
  return 0;
}
