// colliders[i] "motion": how a box, sphere or cylinder collider moves — "static" (no path),
// "kinematic" (follows its "path") or "dynamic" (Coutinho Ch. 4: falls, tumbles and collides,
// like Unity's Rigidbody or Blender's "Active" rigid body), with the dynamic keys "density" or
// "mass", "velocity", "angular_velocity_deg", "linear_damping", "angular_damping",
// "drag_coefficient", "drag_area_m2" (air drag and blast share, body_coupling.cpp). README
// "Rigid bodies".
#include <array>

#include "scene_read.hpp"

namespace simreel::app::scene_read {

namespace {

/// The keys that only a dynamic collider reads.
constexpr std::array<const char*, 8> kDynamicKeys{
    "density",         "mass",           "velocity",         "angular_velocity_deg",
    "linear_damping",  "angular_damping", "drag_coefficient", "drag_area_m2"};

}  // namespace

void collider_motion(ObjectReader& r, const std::string& type, bool has_path, ColliderScene& c) {
  const std::string fallback = has_path ? "kinematic" : "static";
  const std::string motion = r.choice("motion", fallback, {"static", "kinematic", "dynamic"});
  if (motion == "static" && has_path)
    r.error_at(r.pointer("motion"),
               "expected \"kinematic\" for a collider with a \"path\" (or no \"path\"), found \"static\"");
  if (motion == "kinematic" && !has_path)
    r.error_at(r.pointer("motion"), "expected a \"path\" to follow with \"kinematic\", found no \"path\"");
  if (motion != "dynamic") {
    // A dynamic key on a static or kinematic collider is a mistake, not an unknown key.
    for (const char* key : kDynamicKeys)
      if (r.has(key)) {
        r.known(key);
        r.error_at(r.pointer(key), std::string("expected \"motion\": \"dynamic\" for \"") + key +
                                       "\", found a " + motion + " collider");
      }
    return;
  }
  if (type != "box" && type != "sphere" && type != "cylinder" && type != "capsule") {
    r.error_at(r.pointer("motion"), "expected \"dynamic\" only on a box, sphere, cylinder or capsule collider, found a " +
                                        type + " (planes and meshes are static or kinematic)");
    for (const char* key : kDynamicKeys) r.known(key);
    return;
  }
  if (has_path)
    r.error_at(r.pointer("path"), "expected no \"path\" on a \"dynamic\" collider (gravity and contacts "
                                  "move it; use \"motion\": \"kinematic\" to follow a path), found a path");
  if (r.has("density") && r.has("mass"))
    r.error_at(r.pointer("mass"), "expected \"density\" or \"mass\", found both");
  DynamicScene& d = c.dynamic;
  d.enabled = true;
  d.density = r.number("density", d.density, ranges::kBodyDensity);
  d.mass = r.number("mass", 0.0, ranges::kBodyMass);
  if (!r.has("mass")) d.mass = 0.0;  // 0: from the density
  d.velocity = to_vec(r.vec3("velocity", {0, 0, 0}));
  d.angular_velocity = to_vec(r.vec3("angular_velocity_deg", {0, 0, 0})) * kDeg;
  d.linear_damping = r.number("linear_damping", 0.0, ranges::kBodyDamping);
  d.angular_damping = r.number("angular_damping", 0.0, ranges::kBodyDamping);
  d.drag_coefficient = r.number("drag_coefficient", d.drag_coefficient, ranges::kBodyDragCoefficient);
  d.drag_area = r.number("drag_area_m2", 0.0, ranges::kBodyDragArea);
}

}  // namespace simreel::app::scene_read
