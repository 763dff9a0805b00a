// chains[i] and ragdolls[i]: generators that expand into dynamic colliders (bodies) and joints,
// what a user would otherwise write by hand (Coutinho Ch. 5, articulated systems). README
// "chains[i]" and "ragdolls[i]".
#include <algorithm>
#include <cmath>

#include "scene_read.hpp"
#include "simreel/sim/ranges.hpp"

namespace simreel::app::scene_read {

namespace {

using sim::Quat;
using sim::Vec3;

/// A dynamic collider of one shape, as a colliders[i] entry with "motion": "dynamic" would be.
ColliderScene dynamic_collider(const std::string& name, ColliderScene::Type type, const sim::Transform& pose,
                               const sim::Material& material, const render::Vec4f& color, double mass,
                               double density, const Vec3& gravity) {
  ColliderScene c;
  c.name = name;
  c.type = type;
  c.color = color;
  c.box.transform = pose;
  c.box.material = material;
  c.sphere.transform = pose;
  c.sphere.material = material;
  c.capsule.transform = pose;
  c.capsule.material = material;
  c.dynamic.enabled = true;
  c.dynamic.mass = mass;
  c.dynamic.density = density;
  c.dynamic.gravity = gravity;
  return c;
}

JointScene make_joint(sim::JointType type, const std::string& name, std::size_t a, std::size_t b,
                      const Scene& scene, const Vec3& anchor, const Vec3& axis) {
  JointScene j;
  j.def.type = type;
  j.def.name = name;
  j.def.anchor = anchor;
  j.def.axis = axis;
  j.index_a = a;
  j.index_b = b;
  j.body_a = a == JointScene::kWorld ? "world" : scene.colliders[a].name;
  j.body_b = b == JointScene::kWorld ? "world" : scene.colliders[b].name;
  return j;
}

/// The response keys shared by every body a generator makes.
sim::Material generated_material(ObjectReader& r, double restitution, double friction) {
  sim::Material m;
  m.restitution = r.number("restitution", restitution, ranges::kRestitution);
  m.friction = r.number("friction", friction, ranges::kFriction);
  return m;
}

render::Vec4f color4(const std::array<double, 4>& c) {
  return {float(c[0]), float(c[1]), float(c[2]), float(c[3])};
}

/// The n + 1 joint points of a chain of n equal links of total length `length` hanging between
/// the pinned ends a and b (a discrete catenary: with equal link weights the horizontal tension
/// is the same in every link and the vertical one changes by one link's weight from link to
/// link, so tan θ_i = s + k (i - (n - 1) / 2) for the slope θ_i of link i). `up` is the unit
/// vector against gravity; a - b must not be parallel to it. Solved by nested bisection: s for
/// the height difference at a given k, k for the horizontal span.
std::vector<Vec3> catenary_points(const Vec3& a, const Vec3& b, int n, double length, const Vec3& up) {
  const Vec3 c = b - a;
  const double dz = c.dot(up);
  const Vec3 h = c - dz * up;
  const double span = h.norm();
  const Vec3 hu = h / span;
  const double l = length / n;
  auto sums = [&](double k, double s, double& sx, double& sz) {
    sx = sz = 0.0;
    for (int i = 0; i < n; ++i) {
      const double t = s + k * (i - 0.5 * (n - 1));
      const double q = 1.0 / std::sqrt(1.0 + t * t);
      sx += l * q;
      sz += l * t * q;
    }
  };
  auto solve_s = [&](double k) {  // Σ l sin θ_i increases with s
    double lo = -1e9, hi = 1e9;
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      double sx, sz;
      sums(k, mid, sx, sz);
      (sz < dz ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  };
  double klo = 0.0, khi = 1e6;  // the span shrinks as the curvature k grows
  for (int it = 0; it < 200; ++it) {
    const double k = std::sqrt(std::max(klo, 1e-12) * khi);  // bisection on log k
    const double mid = klo == 0.0 && it == 0 ? 1.0 : k;
    double sx, sz;
    sums(mid, solve_s(mid), sx, sz);
    (sx > span ? klo : khi) = mid;
  }
  const double k = 0.5 * (klo + khi), s = solve_s(k);
  std::vector<Vec3> p{a};
  for (int i = 0; i < n; ++i) {
    const double t = s + k * (i - 0.5 * (n - 1));
    const double q = 1.0 / std::sqrt(1.0 + t * t);
    p.push_back(p.back() + l * (q * hu + t * q * up));
  }
  p.back() = b;  // exact end (the solve leaves ~1e-12 m)
  return p;
}

}  // namespace

void chain(const json& j, const std::string& ptr, const std::string& file, std::vector<std::string>& errors,
           std::size_t index, const Vec3& gravity, Scene& scene) {
  ObjectReader r(j, ptr, file, errors);
  GeneratedGroup g;
  g.kind = "chain";
  g.name = r.string("name", "chain" + std::to_string(index));
  for (const char* key : {"from", "to"})
    if (!r.has(key)) r.error_at(ptr, std::string("expected \"") + key + "\": an end point [x, y, z] (m)");
  const Vec3 a = to_vec(r.vec3("from", {0, 0, 2}));
  const Vec3 b = to_vec(r.vec3("to", {1, 0, 2}));
  const int n = int(r.integer("links", 10, 1, 10000));
  const std::string shape = r.choice("shape", "capsule", {"capsule", "box", "sphere"});
  const bool pin_start = r.boolean("pin_start", true);
  const bool pin_end = r.boolean("pin_end", false);
  const double slack = r.number("slack", 0.0, 0.0, 10.0);
  const double chord = (b - a).norm();
  if (r.has("from") && r.has("to") && !(chord > 1e-6))
    r.error_at(r.pointer("to"), "expected a point other than \"from\" (the chain needs a length), found the same point");
  const double length = chord * (1.0 + slack);
  const double l = length / std::max(n, 1);
  const double radius = r.number("radius", shape == "sphere" ? 0.5 * l : 0.02, ranges::kColliderSize);
  const double thickness = r.number("thickness", 2.0 * radius, ranges::kColliderSize);
  if (shape == "capsule" && chord > 1e-6 && !(radius < 0.5 * l))
    r.error_at(r.pointer("radius"), "expected a capsule radius below half the link length (" + sim::format_number(0.5 * l) +
                                        " m), found " + sim::format_number(radius));
  if (r.has("density") && r.has("mass")) r.error_at(r.pointer("mass"), "expected \"density\" or \"mass\", found both");
  const double density = r.number("density", 7800.0, ranges::kBodyDensity);
  const double mass = r.number("mass", 0.0, ranges::kBodyMass);  // the whole chain's
  const sim::Material material = generated_material(r, 0.1, 0.5);
  const render::Vec4f color = color4(r.color("color", {0.45, 0.45, 0.48, 1}));
  const double damping = r.number("damping", 0.0, 0.0, kInf);
  const double break_force = r.number("break_force_n", kInf, 0.0, kInf, true);
  const double linear_damping = r.number("linear_damping", 0.0, ranges::kBodyDamping);
  const double angular_damping = r.number("angular_damping", 0.0, ranges::kBodyDamping);
  Vec3 up = -gravity;
  up = up.norm() > 1e-12 ? up.normalized() : Vec3::UnitZ();
  const bool hanging = pin_start && pin_end && slack > 0.0;
  const Vec3 horizontal = (b - a) - (b - a).dot(up) * up;
  if (hanging && chord > 1e-6 && horizontal.norm() < 1e-6 * chord)
    r.error_at(r.pointer("slack"), "expected no slack for a chain pinned at both ends straight above each other, found " +
                                       sim::format_number(slack));
  else if (hanging && n < 2)
    r.error_at(r.pointer("links"), "expected at least 2 links for a slack chain pinned at both ends, found 1");
  r.finish();
  if (errors.size() > 0 && !(chord > 1e-6)) return;

  std::vector<Vec3> p;
  if (hanging && n >= 2 && horizontal.norm() >= 1e-6 * chord) {
    p = catenary_points(a, b, n, length, up);
  } else {
    const Vec3 dir = (b - a) / chord;
    for (int i = 0; i <= n; ++i) p.push_back(a + dir * (l * i));
  }
  g.first_collider = scene.colliders.size();
  g.first_joint = scene.joints.size();
  for (int i = 0; i < n; ++i) {
    const Vec3 d = (p[std::size_t(i) + 1] - p[std::size_t(i)]).normalized();
    sim::Transform pose;
    pose.translation = 0.5 * (p[std::size_t(i)] + p[std::size_t(i) + 1]);
    pose.rotation = Quat::FromTwoVectors(Vec3::UnitZ(), d);
    const auto type = shape == "box" ? ColliderScene::Type::box
                      : shape == "sphere" ? ColliderScene::Type::sphere
                                          : ColliderScene::Type::capsule;
    ColliderScene c = dynamic_collider(g.name + "_" + std::to_string(i), type, pose, material, color, mass / n, density,
                                       gravity);
    c.sphere.radius = radius;
    c.capsule.radius = radius;
    c.capsule.half_height = std::max(0.5 * l - radius, 1e-6);
    c.box.half_extents = {0.5 * thickness, 0.5 * thickness, 0.5 * l};
    c.dynamic.linear_damping = linear_damping;
    c.dynamic.angular_damping = angular_damping;
    scene.colliders.push_back(std::move(c));
  }
  // Joint k at point k joins link k - 1 and link k (the world at a pinned end).
  for (int k = 0; k <= n; ++k) {
    if ((k == 0 && !pin_start) || (k == n && !pin_end)) continue;
    const std::size_t la = k == 0 ? JointScene::kWorld : g.first_collider + std::size_t(k) - 1;
    const std::size_t lb = k == n ? JointScene::kWorld : g.first_collider + std::size_t(k);
    const Vec3 axis = (p[std::size_t(std::min(k + 1, n))] - p[std::size_t(std::max(k - 1, 0))]).normalized();
    JointScene js = make_joint(sim::JointType::spherical, g.name + "_j" + std::to_string(k), la, lb, scene,
                               p[std::size_t(k)], axis);
    js.def.damping = damping;
    js.def.break_force = break_force;
    scene.joints.push_back(std::move(js));
  }
  g.collider_count = scene.colliders.size() - g.first_collider;
  g.joint_count = scene.joints.size() - g.first_joint;
  scene.generated.push_back(g);
}

// --- ragdolls ------------------------------------------------------------------------------
//
// A standard humanoid of 15 segments (11 without hands and feet), with proportions from Winter,
// *Biomechanics and Motor Control of Human Movement* (4th ed., 2009), Fig. 4.1 (segment lengths
// as fractions of the height H: shoulder 0.818 H, elbow 0.632 H, wrist 0.485 H, hip 0.530 H, knee
// 0.285 H, ankle 0.039 H, foot 0.152 H long, hand 0.108 H) and Table 4.1 (segment masses as
// fractions of the body mass, after Dempster: hand 0.006, forearm 0.016, upper arm 0.028, foot
// 0.0145, leg 0.0465, thigh 0.100, head and neck 0.081, thorax and abdomen 0.355, pelvis 0.142;
// they sum to 1). Widths and radii are typical adult values as fractions of H.
//
// The template stands at the origin facing +x, left = +y, z up, feet on z = 0, every segment
// frame aligned with the world (capsules along z). A pose turns joints in that frame; forward
// kinematics places the segments; the joints are registered where the pose put them.

namespace {

enum class Seg : int { capsule, box };

struct SegmentSpec {
  const char* name;
  int parent;  ///< -1: the root (pelvis)
  Seg shape;
  Vec3 a, b;          ///< capsule: end points (×H); box: centre and half extents (×H)
  double radius;      ///< capsule radius (×H)
  double mass;        ///< fraction of the body mass
  bool skin;          ///< drawn in skin_color
  // The joint to the parent (none for the root), in the template's frame.
  sim::JointType joint;
  const char* joint_name;
  Vec3 anchor;        ///< (×H)
  Vec3 axis;          ///< hinge: flexion axis; spherical: the twist axis (the limb's)
  double lo_deg, hi_deg;           ///< hinge: anatomical range of the flexion angle
  double cone_deg, twist_deg;      ///< spherical: swing cone half angle, twist ±
};

constexpr double kArmY = 0.125, kLegY = 0.06;

// Order matters: a parent comes before its children.
const SegmentSpec kSegments[] = {
    {"pelvis", -1, Seg::box, {0, 0, 0.565}, {0.05, 0.085, 0.065}, 0, 0.142, false, sim::JointType::fixed, "", {}, {}, 0, 0, 0, 0},
    {"chest", 0, Seg::box, {0, 0, 0.73}, {0.055, 0.095, 0.10}, 0, 0.355, false, sim::JointType::spherical, "waist",
     {0, 0, 0.63}, {0, 0, 1}, 0, 0, 30, 30},
    {"head", 1, Seg::capsule, {0, 0, 0.84}, {0, 0, 1.0}, 0.06, 0.081, true, sim::JointType::spherical, "neck",
     {0, 0, 0.835}, {0, 0, 1}, 0, 0, 40, 60},
    {"upper_arm_l", 1, Seg::capsule, {0, kArmY, 0.818}, {0, kArmY, 0.632}, 0.03, 0.028, false, sim::JointType::spherical,
     "shoulder_l", {0, kArmY, 0.818}, {0, 0, -1}, 0, 0, 80, 60},
    {"forearm_l", 3, Seg::capsule, {0, kArmY, 0.632}, {0, kArmY, 0.486}, 0.025, 0.016, false, sim::JointType::hinge,
     "elbow_l", {0, kArmY, 0.632}, {0, -1, 0}, 0, 145, 0, 0},
    {"hand_l", 4, Seg::box, {0, kArmY, 0.432}, {0.025, 0.012, 0.054}, 0, 0.006, true, sim::JointType::spherical,
     "wrist_l", {0, kArmY, 0.486}, {0, 0, -1}, 0, 0, 50, 15},
    {"upper_arm_r", 1, Seg::capsule, {0, -kArmY, 0.818}, {0, -kArmY, 0.632}, 0.03, 0.028, false,
     sim::JointType::spherical, "shoulder_r", {0, -kArmY, 0.818}, {0, 0, -1}, 0, 0, 80, 60},
    {"forearm_r", 6, Seg::capsule, {0, -kArmY, 0.632}, {0, -kArmY, 0.486}, 0.025, 0.016, false, sim::JointType::hinge,
     "elbow_r", {0, -kArmY, 0.632}, {0, -1, 0}, 0, 145, 0, 0},
    {"hand_r", 7, Seg::box, {0, -kArmY, 0.432}, {0.025, 0.012, 0.054}, 0, 0.006, true, sim::JointType::spherical,
     "wrist_r", {0, -kArmY, 0.486}, {0, 0, -1}, 0, 0, 50, 15},
    {"thigh_l", 0, Seg::capsule, {0, kLegY, 0.53}, {0, kLegY, 0.285}, 0.037, 0.100, false, sim::JointType::spherical,
     "hip_l", {0, kLegY, 0.53}, {0, 0, -1}, 0, 0, 60, 30},
    {"shin_l", 9, Seg::capsule, {0, kLegY, 0.285}, {0, kLegY, 0.039}, 0.028, 0.0465, false, sim::JointType::hinge,
     "knee_l", {0, kLegY, 0.285}, {0, 1, 0}, 0, 140, 0, 0},
    {"foot_l", 10, Seg::box, {0.041, kLegY, 0.0195}, {0.076, 0.028, 0.0195}, 0, 0.0145, false, sim::JointType::hinge,
     "ankle_l", {0, kLegY, 0.039}, {0, 1, 0}, -20, 40, 0, 0},
    {"thigh_r", 0, Seg::capsule, {0, -kLegY, 0.53}, {0, -kLegY, 0.285}, 0.037, 0.100, false, sim::JointType::spherical,
     "hip_r", {0, -kLegY, 0.53}, {0, 0, -1}, 0, 0, 60, 30},
    {"shin_r", 12, Seg::capsule, {0, -kLegY, 0.285}, {0, -kLegY, 0.039}, 0.028, 0.0465, false, sim::JointType::hinge,
     "knee_r", {0, -kLegY, 0.285}, {0, 1, 0}, 0, 140, 0, 0},
    {"foot_r", 13, Seg::box, {0.041, -kLegY, 0.0195}, {0.076, 0.028, 0.0195}, 0, 0.0145, false, sim::JointType::hinge,
     "ankle_r", {0, -kLegY, 0.039}, {0, 1, 0}, -20, 40, 0, 0},
};
constexpr int kSegmentCount = int(sizeof kSegments / sizeof kSegments[0]);

Quat about(const Vec3& axis, double deg) { return Quat(Eigen::AngleAxisd(deg * kDeg, axis.normalized())); }

}  // namespace

void ragdoll(const json& j, const std::string& ptr, const std::string& file, std::vector<std::string>& errors,
             std::size_t index, const Vec3& gravity, Scene& scene) {
  ObjectReader r(j, ptr, file, errors);
  GeneratedGroup g;
  g.kind = "ragdoll";
  g.name = r.string("name", "ragdoll" + std::to_string(index));
  const Vec3 position = to_vec(r.vec3("position", {0, 0, 0}));
  const double H = r.number("height_m", 1.8, 0.05, 10.0);
  const double M = r.number("mass_kg", 75.0, ranges::kBodyMass);
  const std::string pose = r.choice("pose", "standing", {"standing", "t-pose", "sitting", "lying", "lying_face_down"});
  const double yaw = r.number("yaw_deg", 0.0, -360.0, 360.0);
  const bool hands = r.boolean("hands", true);
  const bool feet = r.boolean("feet", true);
  const Vec3 velocity = to_vec(r.vec3("velocity", {0, 0, 0}));
  const render::Vec4f color = color4(r.color("color", {0.25, 0.35, 0.60, 1}));
  const render::Vec4f skin = color4(r.color("skin_color", {0.86, 0.68, 0.55, 1}));
  const sim::Material material = generated_material(r, 0.05, 0.7);
  const double joint_damping = r.number("joint_damping", 0.5, 0.0, kInf);
  const double linear_damping = r.number("linear_damping", 0.0, ranges::kBodyDamping);
  const double angular_damping = r.number("angular_damping", 0.0, ranges::kBodyDamping);
  r.finish();

  // The pose: joint rotations in the template frame (flexion of a hinge about its axis, so the
  // hinge's limits shift by it) and a rotation of the whole body about the pelvis.
  Quat root = Quat::Identity();
  std::vector<Quat> local(kSegmentCount, Quat::Identity());
  std::vector<double> flexion(kSegmentCount, 0.0);  // (deg) of each hinge in the pose
  auto seg = [](const char* name) {
    for (int i = 0; i < kSegmentCount; ++i)
      if (std::string(kSegments[i].name) == name) return i;
    return -1;
  };
  auto flex = [&](const char* name, double deg) {
    const int i = seg(name);
    flexion[std::size_t(i)] = deg;
    local[std::size_t(i)] = about(kSegments[i].axis, deg);
  };
  if (pose == "t-pose") {
    local[std::size_t(seg("upper_arm_l"))] = about(Vec3::UnitX(), 90);
    local[std::size_t(seg("upper_arm_r"))] = about(Vec3::UnitX(), -90);
  } else if (pose == "sitting") {
    local[std::size_t(seg("thigh_l"))] = about(Vec3::UnitY(), -90);
    local[std::size_t(seg("thigh_r"))] = about(Vec3::UnitY(), -90);
    flex("shin_l", 90);
    flex("shin_r", 90);
    flex("forearm_l", 30);
    flex("forearm_r", 30);
  } else if (pose == "lying") {
    root = about(Vec3::UnitY(), -90);  // on its back, head towards -x
  } else if (pose == "lying_face_down") {
    root = about(Vec3::UnitY(), 90);
  }

  // Forward kinematics in the template frame (×H): R_s and the world point of each joint.
  std::vector<Quat> rot(kSegmentCount);
  std::vector<Vec3> joint_at(kSegmentCount);
  auto map = [&](int s, const Vec3& x) {  // template point on segment s -> posed frame
    const SegmentSpec& sp = kSegments[s];
    if (sp.parent < 0) return Vec3(root * x);
    return Vec3(rot[std::size_t(s)] * (x - sp.anchor) + joint_at[std::size_t(s)]);
  };
  for (int s = 0; s < kSegmentCount; ++s) {
    const SegmentSpec& sp = kSegments[s];
    if (sp.parent < 0) {
      rot[std::size_t(s)] = root;
      continue;
    }
    joint_at[std::size_t(s)] = map(sp.parent, sp.anchor);
    rot[std::size_t(s)] = rot[std::size_t(sp.parent)] * local[std::size_t(s)];
  }
  auto included = [&](int s) {
    const std::string n = kSegments[s].name;
    return !((!hands && n.rfind("hand", 0) == 0) || (!feet && n.rfind("foot", 0) == 0));
  };
  // Lowest point of the posed body -> on z = 0 (plus 2 mm), then yaw and move to `position`.
  double zmin = kInf;
  for (int s = 0; s < kSegmentCount; ++s) {
    if (!included(s)) continue;
    const SegmentSpec& sp = kSegments[s];
    if (sp.shape == Seg::capsule) {
      const Vec3 axis = (sp.b - sp.a).normalized();
      for (const Vec3& e : {Vec3(sp.a + axis * sp.radius), Vec3(sp.b - axis * sp.radius)})
        zmin = std::min(zmin, map(s, e).z() - sp.radius);
    } else {
      for (int c = 0; c < 8; ++c) {
        const Vec3 corner = sp.a + Vec3(c & 1 ? 1 : -1, c & 2 ? 1 : -1, c & 4 ? 1 : -1).cwiseProduct(sp.b);
        zmin = std::min(zmin, map(s, corner).z());
      }
    }
  }
  const Quat yawq = about(Vec3::UnitZ(), yaw);
  auto place = [&](const Vec3& x) { return Vec3(position + yawq * ((x - Vec3(0, 0, zmin)) * H) + Vec3(0, 0, 0.002)); };

  g.first_collider = scene.colliders.size();
  g.first_joint = scene.joints.size();
  std::vector<std::size_t> body(kSegmentCount, JointScene::kWorld);
  for (int s = 0; s < kSegmentCount; ++s) {
    if (!included(s)) continue;
    const SegmentSpec& sp = kSegments[s];
    double m = sp.mass;
    // Without hands/feet, their mass goes to the forearm/leg (Winter's "forearm and hand"
    // 0.022, "leg and foot" 0.061), so the total stays `mass_kg`.
    const std::string n = sp.name;
    if (!hands && n.rfind("forearm", 0) == 0) m += 0.006;
    if (!feet && n.rfind("shin", 0) == 0) m += 0.0145;
    sim::Transform pose_t;
    ColliderScene::Type type = ColliderScene::Type::box;
    Vec3 centre = sp.a;
    double half_height = 0.0;
    if (sp.shape == Seg::capsule) {
      type = ColliderScene::Type::capsule;
      centre = 0.5 * (sp.a + sp.b);
      half_height = 0.5 * (sp.a - sp.b).norm() - sp.radius;
    }
    pose_t.translation = place(map(s, centre));
    pose_t.rotation = (yawq * rot[std::size_t(s)]).normalized();
    ColliderScene c = dynamic_collider(g.name + "_" + sp.name, type, pose_t, material, sp.skin ? skin : color, m * M,
                                       1000.0, gravity);
    c.box.half_extents = sp.b * H;
    c.capsule.radius = sp.radius * H;
    c.capsule.half_height = half_height * H;
    c.dynamic.velocity = velocity;
    c.dynamic.linear_damping = linear_damping;
    c.dynamic.angular_damping = angular_damping;
    body[std::size_t(s)] = scene.colliders.size();
    scene.colliders.push_back(std::move(c));
  }
  for (int s = 0; s < kSegmentCount; ++s) {
    const SegmentSpec& sp = kSegments[s];
    if (sp.parent < 0 || !included(s)) continue;
    // Axis in the posed world: a hinge's is fixed in the parent; a spherical joint's twist axis
    // is the child's long axis as posed.
    const Quat frame = yawq * (sp.joint == sim::JointType::hinge ? rot[std::size_t(sp.parent)] : rot[std::size_t(s)]);
    JointScene js = make_joint(sp.joint, g.name + "_" + sp.joint_name, body[std::size_t(sp.parent)],
                               body[std::size_t(s)], scene, place(joint_at[std::size_t(s)]), frame * sp.axis);
    sim::JointDef& d = js.def;
    d.limit_enabled = true;
    d.damping = joint_damping;
    if (sp.joint == sim::JointType::hinge) {
      // Anatomical range [lo, hi] of the flexion; the engine measures from the posed angle.
      d.lower_angle = std::min(0.0, (sp.lo_deg - flexion[std::size_t(s)]) * kDeg);
      d.upper_angle = std::max(0.0, (sp.hi_deg - flexion[std::size_t(s)]) * kDeg);
    } else {
      d.cone_angle = sp.cone_deg * kDeg;
      d.twist_lower = -sp.twist_deg * kDeg;
      d.twist_upper = sp.twist_deg * kDeg;
    }
    scene.joints.push_back(std::move(js));
  }
  g.collider_count = scene.colliders.size() - g.first_collider;
  g.joint_count = scene.joints.size() - g.first_joint;
  scene.generated.push_back(g);
}

}  // namespace simreel::app::scene_read
