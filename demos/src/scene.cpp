#include "scene.hpp"

#include <cmath>
#include <numbers>

#include "json_reader.hpp"

namespace simreel::app {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDeg = std::numbers::pi / 180.0;

sim::Vec3 to_vec(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }
render::Vec3f to_vec3f(const std::array<double, 3>& a) { return {float(a[0]), float(a[1]), float(a[2])}; }
render::Vec3f to_vec3f(const std::array<double, 4>& a) { return {float(a[0]), float(a[1]), float(a[2])}; }

/// rotation_deg = [rx, ry, rz]: rotations about the world x, then y, then z axes (R = Rz Ry Rx).
sim::Quat rotation_from_deg(const std::array<double, 3>& r) {
  return sim::Quat(Eigen::AngleAxisd(r[2] * kDeg, sim::Vec3::UnitZ()) *
                   Eigen::AngleAxisd(r[1] * kDeg, sim::Vec3::UnitY()) *
                   Eigen::AngleAxisd(r[0] * kDeg, sim::Vec3::UnitX()));
}

/// Reads an object member; reports and returns nullptr if present but not an object.
const json* object_member(ObjectReader& r, const std::string& key) {
  const json* v = r.get(key);
  if (v && !v->is_object()) {
    r.error(key, "an object", *v);
    return nullptr;
  }
  return v;
}

/// A parameter given as a number (no deviation) or {"mean", "deviation", "min", "max"}
/// (Coutinho §3.8: mean + deviation, drawn from a normal distribution).
sim::Distribution distribution(ObjectReader& r, const std::string& key, sim::Distribution fallback,
                               double min, double max, const std::string& unit) {
  const json* v = r.get(key);
  if (!v) return fallback;
  const std::string range = std::string(" in [") + (std::isfinite(min) ? std::to_string(min) : "-inf") + ", " +
                            (std::isfinite(max) ? std::to_string(max) : "inf") + "]";
  if (v->is_number()) {
    const double x = r.number(key, fallback.mean, min, max);
    fallback.mean = x;
    fallback.deviation = 0.0;
    return fallback;
  }
  if (!v->is_object()) {
    r.error(key, "a number (" + unit + ") or {\"mean\": ..., \"deviation\": ...}", *v);
    return fallback;
  }
  ObjectReader o(*v, r.pointer(key), r.file(), r.errors());
  if (!o.has("mean")) o.error_at(o.pointer(), "expected a \"mean\" (" + unit + ") in the distribution");
  sim::Distribution d = fallback;
  d.mean = o.number("mean", fallback.mean, min, max);
  d.deviation = o.number("deviation", 0.0, 0.0, kInf);
  d.min = o.number("min", std::max(min, fallback.min), min, max);
  d.max = o.number("max", std::min(max, fallback.max), min, max);
  if (d.min > d.max) o.error_at(o.pointer("min"), "expected min <= max");
  o.finish();
  return d;
}

sim::KeyframePath keyframe_path(ObjectReader& r, const std::string& key) {
  sim::KeyframePath path;
  const json* v = object_member(r, key);
  if (!v) return path;
  ObjectReader o(*v, r.pointer(key), r.file(), r.errors());
  path.loop = o.boolean("loop", false);
  path.smooth = o.boolean("smooth", true);
  const json* keys = o.get("keys");
  if (!keys || !keys->is_array() || keys->empty()) {
    o.error("keys", "a non-empty array of {\"time\", \"position\", \"rotation_deg\"}", keys ? *keys : json());
  } else {
    for (std::size_t i = 0; i < keys->size(); ++i) {
      const json& k = (*keys)[i];
      const std::string kp = o.pointer("keys") + "/" + std::to_string(i);
      if (!k.is_object()) {
        o.error_at(kp, "expected an object, found " + describe(k));
        continue;
      }
      ObjectReader kr(k, kp, r.file(), r.errors());
      sim::Keyframe kf;
      if (!kr.has("time")) kr.error_at(kp, "expected a \"time\" (s)");
      kf.time = kr.number("time", 0.0, 0.0, kInf);
      kf.position = to_vec(kr.vec3("position", {0, 0, 0}));
      kf.rotation = rotation_from_deg(kr.vec3("rotation_deg", {0, 0, 0}));
      kr.finish();
      if (!path.keys.empty() && !(kf.time > path.keys.back().time))
        kr.error_at(kr.pointer("time"), "expected times strictly increasing, found " + describe(k.value("time", json())) +
                                            " after " + describe(json(path.keys.back().time)));
      path.keys.push_back(kf);
    }
  }
  o.finish();
  return path;
}

sim::Material material(ObjectReader& r) {
  sim::Material m;
  m.restitution = r.number("restitution", m.restitution, 0.0, 1.0);
  m.friction = r.number("friction", m.friction, 0.0, kInf);
  return m;
}

ColliderScene collider(const json& j, const std::string& ptr, const std::string& file,
                       std::vector<std::string>& errors, std::size_t index) {
  ColliderScene c;
  ObjectReader r(j, ptr, file, errors);
  const std::string type = r.choice("type", "", {"plane", "box"});
  if (!r.has("type")) r.error_at(ptr, "expected a \"type\": one of \"plane\", \"box\"");
  c.name = r.string("name", type + std::to_string(index));
  const auto color = r.color("color", type == "box" ? std::array<double, 4>{0.78, 0.36, 0.16, 1}
                                                    : std::array<double, 4>{0.55, 0.56, 0.58, 1});
  c.color = {float(color[0]), float(color[1]), float(color[2]), float(color[3])};
  if (type == "plane") {
    c.type = ColliderScene::Type::plane;
    c.plane.point = to_vec(r.vec3("point", {0, 0, 0}));
    c.plane.normal = to_vec(r.vec3("normal", {0, 0, 1}));
    if (c.plane.normal.norm() < 1e-9) r.error_at(r.pointer("normal"), "expected a non-zero normal, found [0, 0, 0]");
    c.plane.material = material(r);
    c.checker_m = float(r.number("checker_m", 1.0, 0.0, kInf));
    c.draw_half_size = float(r.number("draw_half_size", 20.0, 0.0, kInf, true));
  } else if (type == "box") {
    c.type = ColliderScene::Type::box;
    c.box.transform.translation = to_vec(r.vec3("position", {0, 0, 0}));
    c.box.transform.rotation = rotation_from_deg(r.vec3("rotation_deg", {0, 0, 0}));
    const auto he = r.numbers("half_extents", {0.5, 0.5, 0.5}, 3, 0.0, kInf, true);
    c.box.half_extents = {he[0], he[1], he[2]};
    c.box.material = material(r);
    c.box.path = keyframe_path(r, "path");
  }
  r.finish();
  return c;
}

/// camera.path (keyframes) or camera.orbit; see README "camera".
void camera_motion(ObjectReader& s, const render::Camera& base, render::CameraMotion& motion) {
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
      key.fov_deg = float(k.number("fov_deg", base.fov_deg, 1.0, 170.0));
      if ((key.target - key.position).norm() < 1e-6f)
        k.error_at(k.pointer("target"), "expected a target different from the position");
      if (!motion.keys.empty() && !(key.time > motion.keys.back().time))
        k.error_at(k.pointer("time"), "expected times strictly increasing, found " + std::to_string(key.time) +
                                          " after " + std::to_string(motion.keys.back().time));
      k.finish();
      motion.keys.push_back(key);
    }
  }
  if (const json* oj = object_member(s, "orbit")) {
    ObjectReader o(*oj, s.pointer("orbit"), s.file(), s.errors());
    render::CameraOrbit orbit;
    orbit.center = to_vec3f(o.vec3("center", {base.target.x(), base.target.y(), base.target.z()}));
    orbit.radius = float(o.number("radius", orbit.radius, 0.0, kInf, true));
    orbit.height = float(o.number("height", orbit.height));
    orbit.period_s = float(o.number("period_s", orbit.period_s, 0.0, kInf, true));
    orbit.start_deg = float(o.number("start_deg", orbit.start_deg));
    o.finish();
    motion.orbit = orbit;
  }
}

EmitterScene emitter(const json& j, const std::string& ptr, const std::string& file,
                     std::vector<std::string>& errors, std::size_t index, const sim::Vec3& gravity) {
  EmitterScene e;
  ObjectReader r(j, ptr, file, errors);
  sim::ParticleSystemDef& s = e.system;
  sim::EmitterDef& em = s.emitter;
  s.name = r.string("name", "emitter" + std::to_string(index));
  const std::string shape = r.choice("shape", "disk", {"disk", "quad"});
  em.shape = shape == "quad" ? sim::EmitterShape::quad : sim::EmitterShape::disk;
  em.disk_radius = r.number("disk_radius", em.disk_radius, 0.0, kInf, true);
  const auto qs = r.numbers("quad_size", {em.quad_size[0], em.quad_size[1]}, 2, 0.0, kInf, true);
  em.quad_size = {qs[0], qs[1]};
  em.transform.translation = to_vec(r.vec3("position", {0, 0, 0}));
  sim::Vec3 dir = to_vec(r.vec3("direction", {0, 0, 1}));
  if (dir.norm() < 1e-9) {
    r.error_at(r.pointer("direction"), "expected a non-zero direction, found [0, 0, 0]");
    dir = sim::Vec3::UnitZ();
  }
  em.transform.rotation = sim::Quat::FromTwoVectors(sim::Vec3::UnitZ(), dir.normalized());
  em.rate = r.number("rate", em.rate, 0.0, 1e9);
  em.start_time = r.number("start_time", 0.0, 0.0, kInf);
  em.stop_time = r.number("stop_time", 1e300, 0.0, kInf);
  em.lifetime = distribution(r, "lifetime", em.lifetime, 0.0, kInf, "s");
  em.start_speed = distribution(r, "start_speed", em.start_speed, 0.0, kInf, "m/s");
  em.spread_deg = distribution(r, "spread_deg", em.spread_deg, 0.0, 180.0, "degrees");
  em.mass = distribution(r, "mass", em.mass, 0.0, kInf, "kg");
  if (em.mass.mean <= 0.0) r.error_at(r.pointer("mass"), "expected a mean mass > 0 kg");
  em.radius = distribution(r, "particle_radius", em.radius, 0.0, kInf, "m");
  if (em.radius.mean <= 0.0) r.error_at(r.pointer("particle_radius"), "expected a mean radius > 0 m");
  em.max_particles = std::size_t(r.integer("max_particles", 100000, 1, 50'000'000));

  if (r.has("color") && r.has("color_over_lifetime"))
    r.error_at(ptr, "expected either \"color\" or \"color_over_lifetime\", not both");
  const auto color = r.color("color", {0.9, 0.9, 0.9, 1.0});
  em.color_over_lifetime = {sim::ColorKey{0.0, {float(color[0]), float(color[1]), float(color[2]), float(color[3])}}};
  if (const json* keys = r.get("color_over_lifetime")) {
    if (!keys->is_array() || keys->empty()) {
      r.error("color_over_lifetime", "a non-empty array of {\"t\": 0..1, \"color\": [r, g, b, a]}", *keys);
    } else {
      em.color_over_lifetime.clear();
      for (std::size_t i = 0; i < keys->size(); ++i) {
        const std::string kp = r.pointer("color_over_lifetime") + "/" + std::to_string(i);
        if (!(*keys)[i].is_object()) {
          r.error_at(kp, "expected an object {\"t\", \"color\"}, found " + describe((*keys)[i]));
          continue;
        }
        ObjectReader kr((*keys)[i], kp, file, errors);
        sim::ColorKey key;
        key.t = kr.number("t", 0.0, 0.0, 1.0);
        const auto c = kr.color("color", {1, 1, 1, 1});
        key.rgba = {float(c[0]), float(c[1]), float(c[2]), float(c[3])};
        if (!em.color_over_lifetime.empty() && key.t < em.color_over_lifetime.back().t)
          kr.error_at(kr.pointer("t"), "expected keys in increasing t");
        kr.finish();
        em.color_over_lifetime.push_back(key);
      }
      if (em.color_over_lifetime.empty()) em.color_over_lifetime = {sim::ColorKey{}};
    }
  }
  em.path = keyframe_path(r, "path");
  s.gravity = to_vec(r.vec3("gravity", {gravity.x(), gravity.y(), gravity.z()}));
  s.drag = r.number("drag", 0.0, 0.0, kInf);
  s.integrator = r.choice("integrator", "semi_implicit_euler", {"semi_implicit_euler", "rk4"}) == "rk4"
                     ? sim::Integrator::rk4
                     : sim::Integrator::semi_implicit_euler;
  s.collide = r.boolean("collide", true);
  const std::string style = r.choice("render_style", "soft", {"soft", "additive", "streak", "droplet"});
  e.style = style == "additive" ? render::ParticleStyle::additive
            : style == "streak" ? render::ParticleStyle::streak
            : style == "droplet" ? render::ParticleStyle::droplet
                                 : render::ParticleStyle::soft;
  e.streak_s = float(r.number("streak_s", 0.02, 0.0, 10.0));
  r.finish();
  return e;
}

}  // namespace

Scene scene_from_json(const json& doc, const std::string& file) {
  std::vector<std::string> errors;
  Scene scene;
  scene.file = file;
  if (!doc.is_object()) throw SceneError(file + ": /: expected a scene object, found " + describe(doc));
  ObjectReader r(doc, "", file, errors);
  r.string("description", "");
  scene.seed = std::uint64_t(r.integer("seed", 0, 0, std::numeric_limits<long long>::max()));
  scene.fps = r.number("fps", 30.0, 0.0, 1000.0, true);
  scene.frames = int(r.integer("frames", 120, 1, 1'000'000));

  sim::Vec3 gravity{0, 0, -9.81};
  if (const json* sim_j = object_member(r, "simulation")) {
    ObjectReader s(*sim_j, r.pointer("simulation"), file, errors);
    scene.world.max_step = s.number("max_step", scene.world.max_step, 0.0, 1.0, true);
    scene.world.contact_speed = s.number("contact_speed", scene.world.contact_speed, 0.0, kInf);
    gravity = to_vec(s.vec3("gravity", {0, 0, -9.81}));
    s.finish();
  }
  if (const json* rj = object_member(r, "render")) {
    ObjectReader s(*rj, r.pointer("render"), file, errors);
    scene.render.width = int(s.integer("width", scene.render.width, 16, 8192));
    scene.render.height = int(s.integer("height", scene.render.height, 16, 8192));
    scene.render.msaa_samples = int(s.integer("msaa", scene.render.msaa_samples, 0, 16));
    scene.backend = render::parse_backend(s.choice("backend", "osmesa", {"osmesa", "egl"}));
    const auto top = s.color("sky_top", {scene.render.sky_top.x(), scene.render.sky_top.y(), scene.render.sky_top.z(), 1});
    const auto bottom = s.color("sky_bottom", {scene.render.sky_bottom.x(), scene.render.sky_bottom.y(),
                                               scene.render.sky_bottom.z(), 1});
    scene.render.sky_top = to_vec3f(top);
    scene.render.sky_bottom = to_vec3f(bottom);
    // "background": "sky" (the gradient) or a colour [r, g, b].
    if (const json* bg = s.get("background")) {
      if (bg->is_string() && bg->get<std::string>() == "sky") {
        scene.render.background = render::Background::sky_gradient;
      } else if (bg->is_array()) {
        scene.render.background = render::Background::solid;
        scene.render.background_color = to_vec3f(s.color("background", {0, 0, 0, 1}));
      } else {
        s.error("background", "\"sky\" or a colour [r, g, b] in [0, 1]", *bg);
      }
    }
    scene.render.particle_shadows = s.boolean("particle_shadows", false);
    s.finish();
  }
  if (const json* cj = object_member(r, "camera")) {
    ObjectReader s(*cj, r.pointer("camera"), file, errors);
    const auto& c = scene.camera;
    scene.camera.position = to_vec3f(s.vec3("position", {c.position.x(), c.position.y(), c.position.z()}));
    scene.camera.target = to_vec3f(s.vec3("target", {c.target.x(), c.target.y(), c.target.z()}));
    scene.camera.up = to_vec3f(s.vec3("up", {0, 0, 1}));
    scene.camera.fov_deg = float(s.number("fov_deg", c.fov_deg, 1.0, 170.0));
    if ((scene.camera.target - scene.camera.position).norm() < 1e-6f)
      s.error_at(s.pointer("target"), "expected a target different from the camera position");
    camera_motion(s, scene.camera, scene.camera_motion);
    s.finish();
  }
  scene.camera_motion.base = scene.camera;
  if (const json* lj = object_member(r, "light")) {
    ObjectReader s(*lj, r.pointer("light"), file, errors);
    const auto& l = scene.light;
    scene.light.direction = to_vec3f(s.vec3("direction", {l.direction.x(), l.direction.y(), l.direction.z()}));
    if (scene.light.direction.norm() < 1e-6f) s.error_at(s.pointer("direction"), "expected a non-zero direction");
    scene.light.color = to_vec3f(s.vec3("color", {l.color.x(), l.color.y(), l.color.z()}));
    scene.light.ambient = to_vec3f(s.vec3("ambient", {l.ambient.x(), l.ambient.y(), l.ambient.z()}));
    const auto& g = l.ground_ambient;
    scene.light.ground_ambient = to_vec3f(s.vec3("ground_ambient", {g.x(), g.y(), g.z()}));
    s.finish();
  }
  auto read_array = [&](const std::string& key, auto&& each) {
    const json* a = r.get(key);
    if (!a) return;
    if (!a->is_array()) {
      r.error(key, "an array of objects", *a);
      return;
    }
    for (std::size_t i = 0; i < a->size(); ++i) {
      const std::string p = r.pointer(key) + "/" + std::to_string(i);
      if (!(*a)[i].is_object()) {
        r.error_at(p, "expected an object, found " + describe((*a)[i]));
        continue;
      }
      each((*a)[i], p, i);
    }
  };
  read_array("colliders", [&](const json& j, const std::string& p, std::size_t i) {
    scene.colliders.push_back(collider(j, p, file, errors, i));
  });
  read_array("emitters", [&](const json& j, const std::string& p, std::size_t i) {
    scene.emitters.push_back(emitter(j, p, file, errors, i, gravity));
  });
  r.finish();
  if (!errors.empty()) throw SceneError(errors);
  return scene;
}

Scene load_scene(const std::filesystem::path& path, const std::vector<std::string>& overrides) {
  json doc = parse_json_file(path);
  for (const auto& o : overrides) apply_override(doc, o, path.string());
  return scene_from_json(doc, path.string());
}

SceneWorld build_world(const Scene& scene) {
  sim::WorldDef def = scene.world;
  def.seed = scene.seed;
  SceneWorld out{sim::World(def), {}, {}};
  try {
    for (const auto& c : scene.colliders)
      out.colliders.push_back(c.type == ColliderScene::Type::plane ? out.world.add_plane(c.plane)
                                                                   : out.world.add_box(c.box));
    for (const auto& e : scene.emitters) out.systems.push_back(out.world.add_particle_system(e.system));
  } catch (const std::invalid_argument& e) {
    throw SceneError(scene.file + ": " + e.what());
  }
  return out;
}

}  // namespace simreel::app
