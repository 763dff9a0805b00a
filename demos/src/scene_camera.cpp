// The top-level "render", "camera" (with its path or orbit) and "light" objects; README
// "render", "camera", "light".
#include "scene_read.hpp"
#include "simreel/sim/ranges.hpp"

#include <sstream>

namespace simreel::app::scene_read {

namespace {

/// A camera point beyond the world's bound (simulation.max_distance, on each coordinate) sees
/// nothing of a scene the engine keeps inside it; 1e300 was infinite as a float and drew an
/// empty frame with no error.
void inside_world(ObjectReader& s, const std::string& key, const Eigen::Vector3f& p, double reach) {
  if (!s.has(key) || (p.cwiseAbs().maxCoeff() <= reach)) return;
  std::ostringstream m;
  m.precision(10);  // as sim::format_number
  m << "expected each coordinate within +-" << reach << " m (simulation.max_distance), found [" << p.x() << ", "
    << p.y() << ", " << p.z() << "]";
  s.error_at(s.pointer(key), m.str());
}

/// camera.path (keyframes) or camera.orbit; see README "camera".
void camera_motion(ObjectReader& s, const render::Camera& base, render::CameraMotion& motion, double reach) {
  if (s.has("path") && s.has("orbit")) s.error_at(s.pointer(), "expected either \"path\" or \"orbit\", not both");
  if (const json* keys = s.get("path")) {
    if (!keys->is_array() || keys->empty()) {
      s.error("path", "a non-empty array of {\"time\", \"position\", \"target\", \"fov_deg\"}", *keys);
      return;
    }
    for (std::size_t i = 0; i < keys->size(); ++i) {
      const std::string kp = s.pointer("path") + "/" + std::to_string(i);
      if (!(*keys)[i].is_object()) {
        s.error_at(kp, "expected an object {\"time\", \"position\", \"target\", \"fov_deg\"}, found " +
                           describe((*keys)[i]));
        continue;
      }
      ObjectReader k((*keys)[i], kp, s.file(), s.errors());
      render::CameraKey key;
      if (!k.has("time")) k.error_at(kp, "expected a \"time\" (s)");
      key.time = k.number("time", 0.0, 0.0, kInf);
      key.position = to_vec3f(k.vec3("position", {base.position.x(), base.position.y(), base.position.z()}));
      key.target = to_vec3f(k.vec3("target", {base.target.x(), base.target.y(), base.target.z()}));
      inside_world(k, "position", key.position, reach);
      inside_world(k, "target", key.target, reach);
      key.fov_deg = float(k.number("fov_deg", base.fov_deg, 1.0, 170.0));
      if ((key.target - key.position).norm() < 1e-6f)
        k.error_at(k.pointer("target"), "expected a target different from the position");
      if (!motion.keys.empty() && !(key.time > motion.keys.back().time))
        k.error_at(k.pointer("time"), "expected times strictly increasing, found " + sim::format_number(key.time) +
                                          " after " + sim::format_number(motion.keys.back().time));
      k.finish();
      motion.keys.push_back(key);
    }
  }
  if (const json* oj = object_member(s, "orbit")) {
    ObjectReader o(*oj, s.pointer("orbit"), s.file(), s.errors());
    render::CameraOrbit orbit;
    orbit.center = to_vec3f(o.vec3("center", {base.target.x(), base.target.y(), base.target.z()}));
    inside_world(o, "center", orbit.center, reach);
    orbit.radius = float(o.number("radius", orbit.radius, 0.0, reach, true));
    orbit.height = float(o.number("height", orbit.height, -reach, reach));
    orbit.period_s = float(o.number("period_s", orbit.period_s, 0.0, kInf, true));
    orbit.start_deg = float(o.number("start_deg", orbit.start_deg));
    o.finish();
    motion.orbit = orbit;
  }
}

}  // namespace

void render_settings(ObjectReader& r, Scene& scene) {
  const json* rj = object_member(r, "render");
  if (!rj) return;
  ObjectReader s(*rj, r.pointer("render"), r.file(), r.errors());
  scene.render.width = int(s.integer("width", scene.render.width, 16, 8192));
  scene.render.height = int(s.integer("height", scene.render.height, 16, 8192));
  scene.render.msaa_samples = int(s.integer("msaa", scene.render.msaa_samples, 0, 16));
  scene.backend = render::parse_backend(s.choice("backend", "osmesa", {"osmesa", "egl"}));
  const auto top = s.color("sky_top", {scene.render.sky_top.x(), scene.render.sky_top.y(), scene.render.sky_top.z(), 1});
  const auto bottom = s.color("sky_bottom", {scene.render.sky_bottom.x(), scene.render.sky_bottom.y(),
                                             scene.render.sky_bottom.z(), 1});
  scene.render.sky_top = to_vec3f(top);
  scene.render.sky_bottom = to_vec3f(bottom);
  // "background": "sky" (the gradient), "transparent" (alpha 0) or a colour [r, g, b].
  if (const json* bg = s.get("background")) {
    if (bg->is_string() && bg->get<std::string>() == "sky") {
      scene.render.background = render::Background::sky_gradient;
    } else if (bg->is_string() && bg->get<std::string>() == "transparent") {
      scene.render.background = render::Background::transparent;
    } else if (bg->is_array()) {
      scene.render.background = render::Background::solid;
      scene.render.background_color = to_vec3f(s.color("background", {0, 0, 0, 1}));
    } else {
      s.error("background", "\"sky\", \"transparent\" or a colour [r, g, b] in [0, 1]", *bg);
    }
  }
  scene.render.particle_shadows = s.boolean("particle_shadows", false);
  // "bloom": {"intensity", "radius"}; intensity 0 turns it off.
  if (const json* bo = object_member(s, "bloom")) {
    ObjectReader b(*bo, s.pointer("bloom"), s.file(), s.errors());
    scene.render.bloom.intensity = float(b.number("intensity", scene.render.bloom.intensity, 0.0, 1.0));
    scene.render.bloom.radius = float(b.number("radius", scene.render.bloom.radius, 0.0, 1.0));
    b.finish();
  }
  scene.render.shutter_deg = float(s.number("shutter_deg", scene.render.shutter_deg, 0.0, 360.0));
  scene.render.shutter_samples = int(s.integer("shutter_samples", scene.render.shutter_samples, 2, 64));
  s.finish();
}

/// Also sets scene.camera_motion.base (the default camera when there is no "camera" object).
void camera(ObjectReader& r, Scene& scene) {
  if (const json* cj = object_member(r, "camera")) {
    ObjectReader s(*cj, r.pointer("camera"), r.file(), r.errors());
    const auto& c = scene.camera;
    scene.camera.position = to_vec3f(s.vec3("position", {c.position.x(), c.position.y(), c.position.z()}));
    scene.camera.target = to_vec3f(s.vec3("target", {c.target.x(), c.target.y(), c.target.z()}));
    inside_world(s, "position", scene.camera.position, scene.world.max_distance);
    inside_world(s, "target", scene.camera.target, scene.world.max_distance);
    scene.camera.up = to_vec3f(s.vec3("up", {0, 0, 1}));
    // Looking along "up" is drawn (look_at picks a perpendicular), but a zero "up" is no direction.
    if (scene.camera.up.norm() < 1e-6f) s.error_at(s.pointer("up"), "expected a non-zero up direction");
    scene.camera.fov_deg = float(s.number("fov_deg", c.fov_deg, 1.0, 170.0));
    if ((scene.camera.target - scene.camera.position).norm() < 1e-6f)
      s.error_at(s.pointer("target"), "expected a target different from the camera position");
    camera_motion(s, scene.camera, scene.camera_motion, scene.world.max_distance);
    s.finish();
  }
  scene.camera_motion.base = scene.camera;
}

void light(ObjectReader& r, Scene& scene) {
  const json* lj = object_member(r, "light");
  if (!lj) return;
  ObjectReader s(*lj, r.pointer("light"), r.file(), r.errors());
  const auto& l = scene.light;
  scene.light.direction = to_vec3f(s.vec3("direction", {l.direction.x(), l.direction.y(), l.direction.z()}));
  if (scene.light.direction.norm() < 1e-6f) s.error_at(s.pointer("direction"), "expected a non-zero direction");
  // Intensities: 1 is full, above it over-exposes (HDR before tone mapping); a negative light
  // darkened the sky to garbage and 1e300 became infinite in the shader.
  const double most = kMaxLightIntensity;
  scene.light.color = to_vec3f(s.vec3("color", {l.color.x(), l.color.y(), l.color.z()}, 0.0, most));
  scene.light.ambient = to_vec3f(s.vec3("ambient", {l.ambient.x(), l.ambient.y(), l.ambient.z()}, 0.0, most));
  const auto& g = l.ground_ambient;
  scene.light.ground_ambient = to_vec3f(s.vec3("ground_ambient", {g.x(), g.y(), g.z()}, 0.0, most));
  s.finish();
}

}  // namespace simreel::app::scene_read
