// joints[i]: spherical, hinge and fixed joints between named scene bodies (Coutinho Ch. 5: the
// ball-and-socket joint of §5.2; hinges, fixed joints, limits, motors and breaking are beyond
// the book). Angles are degrees in JSON ("_deg" keys) and radians in sim::JointDef. README
// "joints[i]".
#include <cmath>
#include <optional>

#include "scene_read.hpp"

namespace simreel::app::scene_read {

namespace {

constexpr double kRpm = 2.0 * std::numbers::pi / 60.0;  // rad/s per rev/min

std::string in_quotes(const std::string& s) { return "\"" + s + "\""; }

}  // namespace

void check_body_names(const Scene& scene, std::vector<std::string>& errors) {
  for (std::size_t a = 0; a < scene.colliders.size(); ++a) {
    const std::string where =
        scene.colliders[a].pointer.empty() ? "/colliders/" + std::to_string(a) : scene.colliders[a].pointer;
    if (scene.colliders[a].name == "world")
      errors.push_back(scene.file + ": " + where +
                       "/name: expected a name other than \"world\" (joints use it for the static world), found "
                       "\"world\"");
    for (std::size_t b = 0; b < a; ++b)
      if (scene.colliders[a].name == scene.colliders[b].name) {
        errors.push_back(scene.file + ": body " + std::to_string(a) + " (" + in_quotes(scene.colliders[a].name) +
                         (scene.colliders[a].pointer.empty() ? "" : ", " + where) +
                         "): expected a name not used by another collider, body, chain link or ragdoll segment (body " +
                         std::to_string(b) + "), found " + in_quotes(scene.colliders[a].name));
        break;
      }
  }
}

std::optional<std::size_t> body_index(const Scene& scene, const std::string& name, const std::string& pointer,
                                      std::vector<std::string>& errors) {
  if (name == "world") return JointScene::kWorld;
  std::string hint = "world";
  std::size_t best = edit_distance("world", name);
  for (std::size_t i = 0; i < scene.colliders.size(); ++i) {
    if (scene.colliders[i].name == name) return i;
    const std::size_t d = edit_distance(scene.colliders[i].name, name);
    if (d < best) {
      best = d;
      hint = scene.colliders[i].name;
    }
  }
  std::string msg = scene.file + ": " + pointer + ": expected \"world\" or the name of a collider, chain link or " +
                    "ragdoll segment, found " + in_quotes(name);
  if (!hint.empty() && best <= std::max<std::size_t>(2, name.size() / 3)) msg += "; did you mean " + in_quotes(hint) + "?";
  errors.push_back(msg);
  return std::nullopt;
}

JointScene joint(const json& j, const std::string& ptr, const std::string& file,
                 std::vector<std::string>& errors, std::size_t index, const Scene& scene) {
  JointScene out;
  sim::JointDef& d = out.def;
  ObjectReader r(j, ptr, file, errors);
  const std::string type = r.choice("type", "spherical", {"spherical", "hinge", "fixed"});
  d.type = type == "hinge" ? sim::JointType::hinge : type == "fixed" ? sim::JointType::fixed : sim::JointType::spherical;
  d.name = r.string("name", "joint" + std::to_string(index));
  for (const char* key : {"body_a", "body_b"}) {
    if (!r.has(key)) {
      r.error_at(ptr, std::string("expected a \"") + key + "\": a body name or \"world\"");
      continue;
    }
    const std::string name = r.string(key, "world");
    const bool a = key[5] == 'a';
    (a ? out.body_a : out.body_b) = name;
    if (auto i = body_index(scene, name, r.pointer(key), errors)) (a ? out.index_a : out.index_b) = *i;
  }
  if (!r.has("anchor")) r.error_at(ptr, "expected an \"anchor\": the joint point [x, y, z] (m, world frame at t = 0)");
  d.anchor = to_vec(r.vec3("anchor", {0, 0, 0}));
  d.axis = to_vec(r.vec3("axis", {0, 0, 1}));
  if (!(d.axis.norm() > 1e-9)) r.error_at(r.pointer("axis"), "expected a non-zero axis, found [0, 0, 0]");

  if (r.has("body_a") && r.has("body_b") && out.body_a == out.body_b)
    r.error_at(r.pointer("body_b"), "expected a body other than body_a, found " + in_quotes(out.body_b) + " twice");
  // The engine needs a dynamic body on one side (a static or kinematic one acts as the world).
  auto dynamic = [&](std::size_t i) { return i != JointScene::kWorld && scene.colliders[i].dynamic.enabled; };
  if (r.has("body_a") && r.has("body_b") && out.body_a != out.body_b &&
      (out.index_a != JointScene::kWorld || out.body_a == "world") &&
      (out.index_b != JointScene::kWorld || out.body_b == "world") && !dynamic(out.index_a) && !dynamic(out.index_b))
    r.error_at(r.pointer("body_b"), "expected a \"motion\": \"dynamic\" body on at least one side, found " +
                                        in_quotes(out.body_a) + " and " + in_quotes(out.body_b) + " (static, kinematic or world)");

  if (const json* lj = object_member(r, "limits")) {
    ObjectReader o(*lj, r.pointer("limits"), file, errors);
    d.limit_enabled = true;
    if (d.type == sim::JointType::hinge) {
      const double lo = o.number("lower_deg", -90.0, -360.0, 0.0);
      const double hi = o.number("upper_deg", 90.0, 0.0, 360.0);
      d.lower_angle = lo * kDeg;
      d.upper_angle = hi * kDeg;
    } else if (d.type == sim::JointType::spherical) {
      const double cone = o.number("cone_deg", 45.0, 0.0, 179.0, true);
      const double tlo = o.number("twist_lower_deg", -180.0, -180.0, 0.0);
      const double thi = o.number("twist_upper_deg", 180.0, 0.0, 180.0);
      d.cone_angle = cone * kDeg;
      d.twist_lower = tlo * kDeg;
      d.twist_upper = thi * kDeg;
    } else {
      r.error_at(r.pointer("limits"), "expected no \"limits\" on a fixed joint (it allows no motion), found an object");
      d.limit_enabled = false;
    }
    o.finish();
  }
  d.damping = r.number("damping", 0.0, 0.0, kInf);
  if (const json* mj = object_member(r, "motor")) {
    ObjectReader o(*mj, r.pointer("motor"), file, errors);
    if (d.type != sim::JointType::hinge)
      r.error_at(r.pointer("motor"), "expected a motor only on a \"hinge\" joint, found one on a " + type + " joint");
    if (o.has("speed_deg_s") && o.has("rpm"))
      o.error_at(o.pointer("rpm"), "expected \"speed_deg_s\" or \"rpm\", found both");
    d.motor_enabled = d.type == sim::JointType::hinge;
    const double deg_s = o.number("speed_deg_s", 0.0);
    const double rpm = o.number("rpm", 0.0);
    d.motor_speed = o.has("rpm") ? rpm * kRpm : deg_s * kDeg;
    if (!o.has("max_torque_n_m"))
      o.error_at(o.pointer(), "expected a \"max_torque_n_m\": the largest torque the motor applies (N m, > 0)");
    d.max_motor_torque = o.number("max_torque_n_m", 0.0, 0.0, kInf, true);
    o.finish();
  }
  d.break_force = r.number("break_force_n", kInf, 0.0, kInf, true);
  if (!r.has("break_force_n")) d.break_force = kInf;
  d.collide_connected = r.boolean("collide_connected", false);
  r.finish();
  return out;
}

BodySpringScene body_spring(const json& j, const std::string& ptr, const std::string& file,
                            std::vector<std::string>& errors, std::size_t index, const Scene& scene) {
  BodySpringScene out;
  sim::BodySpringDef& d = out.def;
  ObjectReader r(j, ptr, file, errors);
  d.name = r.string("name", "spring" + std::to_string(index));
  for (const char* key : {"body_a", "body_b"}) {
    const bool a = key[5] == 'a';
    const std::string name = r.string(key, "world");
    (a ? out.body_a : out.body_b) = name;
    if (auto i = body_index(scene, name, r.pointer(key), errors)) (a ? out.index_a : out.index_b) = *i;
  }
  for (const char* key : {"anchor_a", "anchor_b"})
    if (!r.has(key))
      r.error_at(ptr, std::string("expected an \"") + key + "\": the spring's end [x, y, z] (m, world frame at t = 0)");
  d.anchor_a = to_vec(r.vec3("anchor_a", {0, 0, 0}));
  d.anchor_b = to_vec(r.vec3("anchor_b", {0, 0, 0}));
  if (!r.has("stiffness")) r.error_at(ptr, "expected a \"stiffness\" (N/m, > 0)");
  d.stiffness = r.number("stiffness", 0.0, 0.0, kInf, true);
  d.damping = r.number("damping", 0.0, 0.0, kInf);
  d.rest_length = r.has("rest_length") ? r.number("rest_length", 0.0, 0.0, kInf) : -1.0;
  if (out.body_a == out.body_b)
    r.error_at(r.pointer("body_b"), "expected a body other than body_a, found " + in_quotes(out.body_b) + " twice");
  auto dynamic = [&](std::size_t i) { return i != JointScene::kWorld && scene.colliders[i].dynamic.enabled; };
  if (out.body_a != out.body_b && (out.index_a != JointScene::kWorld || out.body_a == "world") &&
      (out.index_b != JointScene::kWorld || out.body_b == "world") && !dynamic(out.index_a) && !dynamic(out.index_b))
    r.error_at(r.pointer("body_b"), "expected a \"motion\": \"dynamic\" body on at least one side, found " +
                                        in_quotes(out.body_a) + " and " + in_quotes(out.body_b));
  r.finish();
  return out;
}

}  // namespace simreel::app::scene_read
