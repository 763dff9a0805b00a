// colliders[i] "motion": how a box, sphere or cylinder collider moves — "static" (no path),
// "kinematic" (follows its "path") or "dynamic" (Coutinho Ch. 4: falls, tumbles and collides,
// like Unity's Rigidbody or Blender's "Active" rigid body), with the dynamic keys "density" or
// "mass", "velocity", "angular_velocity_deg", "linear_damping", "angular_damping". README
// "Rigid bodies".
#include "scene_read.hpp"

namespace simreel::app::scene_read {

void collider_motion(ObjectReader& r, const std::string& type, bool has_path, ColliderScene& c) {
  const std::string fallback = has_path ? "kinematic" : "static";
  const std::string motion = r.choice("motion", fallback, {"static", "kinematic", "dynamic"});
  if (motion == "static" && has_path)
    r.error_at(r.pointer("motion"), "found \"static\" with a \"path\"; expected \"kinematic\" (or no path)");
  if (motion == "kinematic" && !has_path)
    r.error_at(r.pointer("motion"), "found \"kinematic\" without a \"path\"; expected a \"path\" to follow");
  if (motion != "dynamic") return;
  if (type != "box" && type != "sphere" && type != "cylinder") {
    r.error_at(r.pointer("motion"), "found \"dynamic\" on a " + type +
                                        " collider; expected a box, sphere or cylinder (planes and "
                                        "meshes are static or kinematic)");
    return;
  }
  if (has_path)
    r.error_at(r.pointer("motion"), "found \"dynamic\" with a \"path\"; expected no path (a dynamic "
                                    "body is moved by gravity and contacts)");
  if (r.has("density") && r.has("mass"))
    r.error_at(r.pointer("mass"), "found both \"density\" and \"mass\"; expected one of them");
  DynamicScene& d = c.dynamic;
  d.enabled = true;
  d.density = r.number("density", d.density, 1e-3, 1e6);
  d.mass = r.number("mass", 0.0, 1e-6, 1e6);
  const auto v = r.vec3("velocity", {0, 0, 0});
  d.velocity = to_vec(v);
  const auto w = r.vec3("angular_velocity_deg", {0, 0, 0});
  d.angular_velocity = to_vec(w) * (std::numbers::pi / 180.0);
  d.linear_damping = r.number("linear_damping", 0.0, 0.0, 100.0);
  d.angular_damping = r.number("angular_damping", 0.0, 0.0, 100.0);
}

}  // namespace simreel::app::scene_read
