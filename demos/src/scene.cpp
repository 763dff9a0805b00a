#include "scene.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <numbers>
#include <utility>

#include "effect_scene.hpp"
#include "json_reader.hpp"
#include "simreel/assets/mesh.hpp"

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

/// A parameter given as a number (no deviation), {"mean", "deviation", "min", "max"} (Coutinho
/// §3.8: mean + deviation, drawn from a normal distribution, clamped to [min, max]) or
/// {"min", "max"} alone: uniform on [min, max].
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
  sim::Distribution d = fallback;
  if (!o.has("mean") && !o.has("deviation") && o.has("min") && o.has("max")) {
    d.uniform = true;
    d.min = o.number("min", min, min, max);
    d.max = o.number("max", max, min, max);
    if (!std::isfinite(d.min) || !std::isfinite(d.max)) o.error_at(o.pointer(), "expected finite min and max");
    if (d.min > d.max) o.error_at(o.pointer("min"), "expected min <= max");
    d.mean = 0.5 * (d.min + d.max);
    d.deviation = 0.0;
    o.finish();
    return d;
  }
  if (!o.has("mean"))
    o.error_at(o.pointer(), "expected a \"mean\" (" + unit +
                                ") in the distribution, or \"min\" and \"max\" alone for a uniform one");
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

/// "on_hit" (bounce | stick | kill | split) and the droplets of a split hit under `split_key`.
void hit_action(ObjectReader& r, const std::string& split_key, sim::Material& m) {
  const std::string on_hit = r.choice("on_hit", "bounce", {"bounce", "stick", "kill", "split"});
  m.on_hit = on_hit == "stick" ? sim::HitAction::stick
             : on_hit == "kill" ? sim::HitAction::kill
             : on_hit == "split" ? sim::HitAction::split
                                 : sim::HitAction::bounce;
  if (const json* sp = object_member(r, split_key)) {
    ObjectReader o(*sp, r.pointer(split_key), r.file(), r.errors());
    sim::SplitOnHit& x = m.split;
    x.count = int(o.integer("count", x.count, 0, 64));
    x.speed_fraction = o.number("speed_fraction", x.speed_fraction, 0.0, kInf);
    x.size_fraction = o.number("size_fraction", x.size_fraction, 0.0, 1.0, true);
    x.lifetime = o.number("lifetime", x.lifetime, 0.0, kInf, true);
    x.spread_deg = o.number("spread_deg", x.spread_deg, 0.0, 90.0);
    x.min_radius = o.number("min_radius", x.min_radius, 0.0, kInf);
    o.finish();
  }
}

/// Collider response keys (Coutinho §3.6.1, §3.6.3), read from the collider object itself or
/// from its "collider" sub-object.
sim::Material material(ObjectReader& r) {
  sim::Material m;
  m.restitution = r.number("restitution", m.restitution, 0.0, 1.0);
  m.friction = r.number("friction", m.friction, 0.0, kInf);
  if (r.has("static_friction")) m.static_friction = r.number("static_friction", 0.0, 0.0, kInf);
  hit_action(r, "split", m);
  return m;
}

/// An emitter's own "on_hit" and its droplets "on_hit_split" (the emitter's "split" key is the
/// §3.9.1 particle split).
sim::Material material_hit(ObjectReader& r) {
  sim::Material m;
  hit_action(r, "on_hit_split", m);
  return m;
}

/// The response keys of a collider object: flat, or inside "collider": {...} (not both).
sim::Material collider_material(ObjectReader& r) {
  if (const json* cj = object_member(r, "collider")) {
    ObjectReader o(*cj, r.pointer("collider"), r.file(), r.errors());
    const sim::Material m = material(o);
    o.finish();
    return m;
  }
  return material(r);
}

ColliderScene collider(const json& j, const std::string& ptr, const std::string& file,
                       std::vector<std::string>& errors, std::size_t index) {
  ColliderScene c;
  ObjectReader r(j, ptr, file, errors);
  const std::string type = r.choice("type", "", {"plane", "box", "sphere", "cylinder", "mesh"});
  if (!r.has("type"))
    r.error_at(ptr, "expected a \"type\": one of \"plane\", \"box\", \"sphere\", \"cylinder\", \"mesh\"");
  c.name = r.string("name", type + std::to_string(index));
  std::array<double, 4> color = r.color("color", type == "plane" ? std::array<double, 4>{0.55, 0.56, 0.58, 1}
                                                                 : std::array<double, 4>{0.78, 0.36, 0.16, 1});
  if (const json* mj = object_member(r, "material")) {  // the drawing material: {"color": ...}
    ObjectReader o(*mj, r.pointer("material"), file, errors);
    color = o.color("color", color);
    o.finish();
  }
  c.color = {float(color[0]), float(color[1]), float(color[2]), float(color[3])};
  if (type == "plane") {
    c.type = ColliderScene::Type::plane;
    c.plane.point = to_vec(r.vec3("point", {0, 0, 0}));
    c.plane.normal = to_vec(r.vec3("normal", {0, 0, 1}));
    if (c.plane.normal.norm() < 1e-9) r.error_at(r.pointer("normal"), "expected a non-zero normal, found [0, 0, 0]");
    c.plane.material = collider_material(r);
    c.checker_m = float(r.number("checker_m", 1.0, 0.0, kInf));
    c.draw_half_size = float(r.number("draw_half_size", 20.0, 0.0, kInf, true));
  } else if (type == "box") {
    c.type = ColliderScene::Type::box;
    c.box.transform.translation = to_vec(r.vec3("position", {0, 0, 0}));
    c.box.transform.rotation = rotation_from_deg(r.vec3("rotation_deg", {0, 0, 0}));
    const auto he = r.numbers("half_extents", {0.5, 0.5, 0.5}, 3, 0.0, kInf, true);
    c.box.half_extents = {he[0], he[1], he[2]};
    c.box.material = collider_material(r);
    c.box.path = keyframe_path(r, "path");
  } else if (type == "sphere") {
    c.type = ColliderScene::Type::sphere;
    c.sphere.transform.translation = to_vec(r.vec3("position", {0, 0, 0}));
    c.sphere.radius = r.number("radius", 0.5, 0.0, kInf, true);
    c.sphere.material = collider_material(r);
    c.sphere.path = keyframe_path(r, "path");
  } else if (type == "cylinder") {
    c.type = ColliderScene::Type::cylinder;
    c.cylinder.transform.translation = to_vec(r.vec3("position", {0, 0, 0}));
    c.cylinder.transform.rotation = rotation_from_deg(r.vec3("rotation_deg", {0, 0, 0}));
    c.cylinder.radius = r.number("radius", 0.5, 0.0, kInf, true);
    c.cylinder.half_height = r.number("half_height", 0.5, 0.0, kInf, true);
    c.cylinder.material = collider_material(r);
    c.cylinder.path = keyframe_path(r, "path");
  } else if (type == "mesh") {
    c.type = ColliderScene::Type::mesh;
    c.mesh.transform.translation = to_vec(r.vec3("position", {0, 0, 0}));
    c.mesh.transform.rotation = rotation_from_deg(r.vec3("rotation_deg", {0, 0, 0}));
    // "scale": one number (uniform) or [sx, sy, sz], each > 0, applied to the vertices.
    if (const json* sj = r.get("scale"); sj && sj->is_number()) {
      const double k = r.number("scale", 1.0, 0.0, kInf, true);
      c.mesh_scale = {k, k, k};
    } else if (sj) {
      const auto k = r.numbers("scale", {1, 1, 1}, 3, 0.0, kInf, true);
      c.mesh_scale = {k[0], k[1], k[2]};
    }
    c.mesh.material = collider_material(r);
    c.mesh.path = keyframe_path(r, "path");
    if (!r.has("file")) r.error_at(ptr, "expected a \"file\": the mesh file (OBJ, STL, PLY, glTF, ...)");
    const std::string name = r.string("file", "");
    if (!name.empty()) {
      // Relative to the scene file's folder.
      const std::filesystem::path path = std::filesystem::path(file).parent_path() / name;
      try {
        auto mesh = std::make_shared<assets::TriangleMesh>(assets::load_mesh(path));
        c.mesh.vertices.reserve(mesh->positions.size());
        for (const auto& p : mesh->positions)
          c.mesh.vertices.emplace_back(p.x() * c.mesh_scale[0], p.y() * c.mesh_scale[1], p.z() * c.mesh_scale[2]);
        c.mesh.triangles = mesh->triangles;
        c.mesh_asset = std::move(mesh);
      } catch (const assets::AssetError& e) {
        r.error_at(r.pointer("file"), e.what());
      }
    }
  }
  r.finish();
  return c;
}

// ---------------------------------------------------------------------------------------------
// Forces and integrators (Coutinho §3.3, App. B): per-system keys, force fields, attractor springs

/// Calls each(object, pointer, index) for every element of the array r[key]; reports non-arrays
/// and non-object elements.
template <class F>
void object_array(ObjectReader& r, const std::string& key, F&& each) {
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
}

/// The emitter-object keys of the force and integrator half of a particle system.
void particle_forces(ObjectReader& r, sim::ParticleSystemDef& s) {
  static const std::vector<std::string> names = {"semi_implicit_euler", "explicit_euler", "rk2",
                                                 "rk4", "implicit_euler", "adaptive"};
  static const sim::Integrator values[] = {sim::Integrator::semi_implicit_euler, sim::Integrator::explicit_euler,
                                           sim::Integrator::rk2, sim::Integrator::rk4,
                                           sim::Integrator::implicit_euler, sim::Integrator::adaptive};
  const std::string in = r.choice("integrator", "semi_implicit_euler", names);
  s.integrator = values[std::find(names.begin(), names.end(), in) - names.begin()];
  s.tolerance = r.number("tolerance", s.tolerance, 0.0, kInf, true);
  s.charge = distribution(r, "charge", s.charge, -kInf, kInf, "C");
  if (const json* pj = object_member(r, "pair_forces")) {
    ObjectReader o(*pj, r.pointer("pair_forces"), r.file(), r.errors());
    s.pair_forces.gravitational_G = o.number("gravitational_G", 0.0, 0.0, kInf);
    s.pair_forces.coulomb_K = o.number("coulomb_K", 0.0, 0.0, kInf);
    s.pair_forces.cutoff = o.number("cutoff", 1.0, 0.0, kInf, true);
    s.pair_forces.softening = o.number("softening", s.pair_forces.softening, 0.0, kInf);
    o.finish();
  }
  object_array(r, "initial_particles", [&](const json& j, const std::string& p, std::size_t) {
    ObjectReader o(j, p, r.file(), r.errors());
    sim::InitialParticle q;
    if (!o.has("position")) o.error_at(p, "expected a \"position\" [x, y, z] (m)");
    q.position = to_vec(o.vec3("position", {0, 0, 0}));
    q.velocity = to_vec(o.vec3("velocity", {0, 0, 0}));
    q.mass = o.number("mass", s.emitter.mass.mean, 0.0, kInf, true);
    q.radius = o.number("radius", s.emitter.radius.mean, 0.0, kInf, true);
    q.charge = o.number("charge", 0.0);
    o.finish();
    s.initial_particles.push_back(q);
  });
  if (s.initial_particles.size() > s.emitter.max_particles)
    r.error_at(r.pointer("initial_particles"), "expected at most max_particles (" +
                                                   std::to_string(s.emitter.max_particles) + ") particles");
  const long long n_init = (long long)(s.initial_particles.size());
  object_array(r, "springs", [&](const json& j, const std::string& p, std::size_t) {
    ObjectReader o(j, p, r.file(), r.errors());
    sim::SpringDef sp;
    if (n_init < 2) o.error_at(p, "expected springs only between initial_particles (at least 2)");
    if (!o.has("a") || !o.has("b")) o.error_at(p, "expected \"a\" and \"b\" (indices into initial_particles)");
    sp.a = std::uint64_t(o.integer("a", 0, 0, std::max(0LL, n_init - 1)));
    sp.b = std::uint64_t(o.integer("b", 1, 0, std::max(0LL, n_init - 1)));
    if (sp.a == sp.b && o.has("a")) o.error_at(o.pointer("b"), "expected b different from a");
    sp.stiffness = o.number("stiffness", sp.stiffness, 0.0, kInf);
    sp.damping = o.number("damping", sp.damping, 0.0, kInf);
    const json* rl = o.get("rest_length");
    if (rl && rl->is_string() && rl->get<std::string>() == "initial") sp.rest_length = -1.0;
    else if (rl) sp.rest_length = o.number("rest_length", -1.0, 0.0, kInf);
    o.finish();
    s.springs.push_back(sp);
  });
}

/// Names of systems (emitter names) in a "systems" array of strings.
std::vector<std::string> system_names(ObjectReader& r, const std::string& key) {
  std::vector<std::string> out;
  const json* a = r.get(key);
  if (!a) return out;
  if (!a->is_array()) {
    r.error(key, "an array of emitter names", *a);
    return out;
  }
  for (std::size_t i = 0; i < a->size(); ++i) {
    if (!(*a)[i].is_string())
      r.error_at(r.pointer(key) + "/" + std::to_string(i), "expected an emitter name, found " + describe((*a)[i]));
    else
      out.push_back((*a)[i].get<std::string>());
  }
  return out;
}

ForceFieldScene force_field(const json& j, const std::string& ptr, const std::string& file,
                            std::vector<std::string>& errors) {
  ForceFieldScene f;
  sim::ForceFieldDef& d = f.def;
  ObjectReader r(j, ptr, file, errors);
  const std::string type = r.choice("type", "uniform", {"uniform", "attractor", "vortex", "curl_noise"});
  d.kind = type == "attractor" ? sim::FieldKind::attractor
           : type == "vortex"  ? sim::FieldKind::vortex
           : type == "curl_noise" ? sim::FieldKind::curl_noise
                                  : sim::FieldKind::uniform;
  if (const json* rj = object_member(r, "region")) {
    ObjectReader o(*rj, r.pointer("region"), file, errors);
    const std::string shape = o.choice("shape", "everywhere", {"everywhere", "sphere", "box"});
    d.shape = shape == "sphere" ? sim::RegionShape::sphere
              : shape == "box"  ? sim::RegionShape::box
                                : sim::RegionShape::everywhere;
    d.transform.translation = to_vec(o.vec3("center", {0, 0, 0}));
    d.transform.rotation = rotation_from_deg(o.vec3("rotation_deg", {0, 0, 0}));
    if (d.shape == sim::RegionShape::sphere) d.radius = o.number("radius", 1.0, 0.0, kInf, true);
    if (d.shape == sim::RegionShape::box) {
      const auto he = o.numbers("half_extents", {1, 1, 1}, 3, 0.0, kInf, true);
      d.half_extents = sim::Vec3(he[0], he[1], he[2]);
    }
    o.finish();
  }
  const std::string falloff = r.choice("falloff", "none", {"none", "linear", "quadratic"});
  d.falloff = falloff == "linear" ? sim::Falloff::linear
              : falloff == "quadratic" ? sim::Falloff::quadratic
                                       : sim::Falloff::none;
  d.path = keyframe_path(r, "path");
  switch (d.kind) {
    case sim::FieldKind::uniform:
      d.acceleration = to_vec(r.vec3("acceleration", {0, 0, 0}));
      d.force = to_vec(r.vec3("force", {0, 0, 0}));
      break;
    case sim::FieldKind::attractor:
      d.strength = r.number("strength", d.strength);
      break;
    case sim::FieldKind::vortex:
      d.strength = r.number("strength", d.strength);
      d.axis = to_vec(r.vec3("axis", {0, 0, 1}));
      if (d.axis.norm() < 1e-12) r.error_at(r.pointer("axis"), "expected a non-zero axis");
      d.inward_strength = r.number("inward_strength", 0.0);
      break;
    case sim::FieldKind::curl_noise:
      d.amplitude = r.number("amplitude", d.amplitude, 0.0, kInf);
      d.frequency = r.number("frequency", d.frequency, 0.0, kInf, true);
      d.scroll = to_vec(r.vec3("scroll", {0, 0, 0}));
      d.drag = r.number("drag", d.drag, 0.0, kInf);
      break;
  }
  f.systems = system_names(r, "systems");
  r.finish();
  return f;
}

AttractorSpringScene attractor_spring(const json& j, const std::string& ptr, const std::string& file,
                                      std::vector<std::string>& errors) {
  AttractorSpringScene a;
  ObjectReader r(j, ptr, file, errors);
  if (!r.has("system")) r.error_at(ptr, "expected a \"system\" (an emitter name)");
  a.system = r.string("system", "");
  if (const json* ids = r.get("ids")) {
    if (!ids->is_array()) r.error("ids", "an array of particle ids (integers >= 0)", *ids);
    else
      for (std::size_t i = 0; i < ids->size(); ++i) {
        const json& v = (*ids)[i];
        if (!v.is_number_integer() || v.get<long long>() < 0)
          r.error_at(r.pointer("ids") + "/" + std::to_string(i), "expected a particle id (integer >= 0), found " + describe(v));
        else
          a.def.ids.push_back(v.get<std::uint64_t>());
      }
  }
  a.def.anchor = to_vec(r.vec3("anchor", {0, 0, 0}));
  a.def.path = keyframe_path(r, "path");
  a.def.stiffness = r.number("stiffness", a.def.stiffness, 0.0, kInf);
  a.def.damping = r.number("damping", a.def.damping, 0.0, kInf);
  r.finish();
  return a;
}

/// Emitting shape and its size keys; a mesh file is loaded relative to the scene file.
void emitter_shape(ObjectReader& r, sim::EmitterDef& em) {
  const std::string shape =
      r.choice("shape", "disk", {"point", "disk", "quad", "sphere", "box", "mesh", "cube"});
  const std::pair<const char*, sim::EmitterShape> shapes[] = {
      {"point", sim::EmitterShape::point}, {"disk", sim::EmitterShape::disk},
      {"quad", sim::EmitterShape::quad},   {"sphere", sim::EmitterShape::sphere},
      {"box", sim::EmitterShape::box},     {"mesh", sim::EmitterShape::mesh},
      {"cube", sim::EmitterShape::cube}};
  for (const auto& [name, value] : shapes)
    if (shape == name) em.shape = value;
  em.disk_radius = r.number("disk_radius", em.disk_radius, 0.0, kInf, true);
  const auto qs = r.numbers("quad_size", {em.quad_size[0], em.quad_size[1]}, 2, 0.0, kInf, true);
  em.quad_size = {qs[0], qs[1]};
  em.sphere_radius = r.number("sphere_radius", em.sphere_radius, 0.0, kInf, true);
  const auto bs = r.numbers("box_size", {em.box_size[0], em.box_size[1], em.box_size[2]}, 3, 0.0, kInf, true);
  em.box_size = {bs[0], bs[1], bs[2]};
  em.cube_size = r.number("cube_size", em.cube_size, 0.0, kInf, true);
  const std::string mesh_file = r.string("mesh_file", "");
  if (em.shape != sim::EmitterShape::mesh) {
    if (!mesh_file.empty()) r.error_at(r.pointer("mesh_file"), "expected \"mesh_file\" only with \"shape\": \"mesh\"");
    return;
  }
  if (mesh_file.empty()) {
    r.error_at(r.pointer(), "expected a \"mesh_file\" (path relative to the scene file) for \"shape\": \"mesh\"");
    return;
  }
  const std::filesystem::path path = std::filesystem::path(r.file()).parent_path() / mesh_file;
  try {
    const assets::TriangleMesh mesh = assets::load_mesh(path);
    em.mesh_positions.reserve(3 * mesh.positions.size());
    for (const auto& p : mesh.positions)
      em.mesh_positions.insert(em.mesh_positions.end(), {p.x(), p.y(), p.z()});
    em.mesh_triangles.reserve(3 * mesh.triangles.size());
    for (const auto& t : mesh.triangles) em.mesh_triangles.insert(em.mesh_triangles.end(), t.begin(), t.end());
  } catch (const assets::AssetError& e) {
    r.error_at(r.pointer("mesh_file"), std::string("cannot load the mesh: ") + e.what());
  }
}

/// Bursts, inherited velocity, colour variation, size over lifetime and particle split.
void emitter_extras(ObjectReader& r, sim::EmitterDef& em) {
  if (const json* bursts = r.get("bursts")) {
    if (!bursts->is_array()) {
      r.error("bursts", "an array of {\"time\", \"count\", \"repeat_interval\", \"cycles\"}", *bursts);
    } else {
      for (std::size_t i = 0; i < bursts->size(); ++i) {
        const std::string bp = r.pointer("bursts") + "/" + std::to_string(i);
        if (!(*bursts)[i].is_object()) {
          r.error_at(bp, "expected an object {\"time\", \"count\", ...}, found " + describe((*bursts)[i]));
          continue;
        }
        ObjectReader br((*bursts)[i], bp, r.file(), r.errors());
        sim::Burst b;
        b.time = br.number("time", 0.0, 0.0, kInf);
        if (!br.has("count")) br.error_at(bp, "expected a \"count\" (particles per burst)");
        b.count = std::size_t(br.integer("count", 0, 0, 50'000'000));
        b.repeat_interval = br.number("repeat_interval", 0.0, 0.0, kInf);
        b.cycles = std::size_t(br.integer("cycles", 1, 0, 1'000'000'000));
        if (b.cycles == 0 && !(b.repeat_interval > 0.0))
          br.error_at(br.pointer("cycles"), "expected cycles >= 1, or a repeat_interval > 0 for cycles 0 (forever)");
        br.finish();
        em.bursts.push_back(b);
      }
    }
  }
  em.inherit_velocity = r.number("inherit_velocity", 0.0, 0.0, 1.0);
  em.color_deviation = r.number("color_deviation", 0.0, 0.0, kInf);
  if (const json* keys = r.get("size_over_lifetime")) {
    if (!keys->is_array() || keys->empty()) {
      r.error("size_over_lifetime", "a non-empty array of {\"t\": 0..1, \"size\": factor >= 0}", *keys);
    } else {
      for (std::size_t i = 0; i < keys->size(); ++i) {
        const std::string kp = r.pointer("size_over_lifetime") + "/" + std::to_string(i);
        if (!(*keys)[i].is_object()) {
          r.error_at(kp, "expected an object {\"t\", \"size\"}, found " + describe((*keys)[i]));
          continue;
        }
        ObjectReader kr((*keys)[i], kp, r.file(), r.errors());
        sim::SizeKey key;
        key.t = kr.number("t", 0.0, 0.0, 1.0);
        key.size = kr.number("size", 1.0, 0.0, kInf);
        if (!em.size_over_lifetime.empty() && key.t < em.size_over_lifetime.back().t)
          kr.error_at(kr.pointer("t"), "expected keys in increasing t");
        kr.finish();
        em.size_over_lifetime.push_back(key);
      }
    }
  }
  if (const json* sj = object_member(r, "split")) {
    ObjectReader o(*sj, r.pointer("split"), r.file(), r.errors());
    sim::SplitDef& sp = em.split;
    sp.enabled = o.boolean("enabled", true);
    sp.children = std::size_t(o.integer("children", long(sp.children), 1, 1'000'000));
    sp.age = o.number("age", sp.age, 0.0, kInf);
    sp.delay_steps = std::size_t(o.integer("delay_steps", long(sp.delay_steps), 1, 1'000'000));
    sp.depth = std::size_t(o.integer("depth", long(sp.depth), 1, 32));
    sp.velocity_fraction = o.number("velocity_fraction", sp.velocity_fraction, 0.0, kInf);
    sp.direction_deviation_deg = o.number("direction_deviation_deg", sp.direction_deviation_deg, 0.0, 180.0);
    sp.size_fraction = o.number("size_fraction", sp.size_fraction, 0.0, kInf, true);
    sp.lifetime_deviation = o.number("lifetime_deviation", sp.lifetime_deviation, 0.0, kInf);
    o.finish();
  }
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
  emitter_shape(r, em);
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
  emitter_extras(r, em);
  s.gravity = to_vec(r.vec3("gravity", {gravity.x(), gravity.y(), gravity.z()}));
  s.drag = r.number("drag", 0.0, 0.0, kInf);
  particle_forces(r, s);  // integrator, tolerance, charge, pair_forces, initial_particles, springs
  s.collide = r.boolean("collide", true);
  // Particle–particle collisions (Coutinho §2.3.1, §3.6.1–3.6.2).
  s.collide_particles = r.boolean("collide_particles", false);
  s.collision_group = r.string("collision_group", "");
  s.particle_restitution = r.number("particle_restitution", s.particle_restitution, 0.0, 1.0);
  s.particle_friction = r.number("particle_friction", s.particle_friction, 0.0, kInf);
  // The system's own hit action on every collider (rain that splashes wherever it lands).
  if (r.has("on_hit")) {
    const sim::Material m = material_hit(r);
    s.on_hit = m.on_hit;
    s.on_hit_split = m.split;
  } else if (r.has("on_hit_split")) {
    r.error_at(r.pointer("on_hit_split"), "expected \"on_hit_split\" only with \"on_hit\": \"split\"");
  }
  const std::string style = r.choice("render_style", "soft", {"soft", "additive", "streak", "droplet"});
  e.style = style == "additive" ? render::ParticleStyle::additive
            : style == "streak" ? render::ParticleStyle::streak
            : style == "droplet" ? render::ParticleStyle::droplet
                                 : render::ParticleStyle::soft;
  e.streak_s = float(r.number("streak_s", 0.02, 0.0, 10.0));
  r.finish();
  return e;
}

/// Index of the emitter named `name`, or scene.emitters.size().
std::size_t system_index(const Scene& scene, const std::string& name) {
  std::size_t i = 0;
  while (i < scene.emitters.size() && scene.emitters[i].system.name != name) ++i;
  return i;
}

void check_system_name(const Scene& scene, const std::string& name, const std::string& pointer,
                       std::vector<std::string>& errors) {
  if (system_index(scene, name) < scene.emitters.size()) return;
  std::string known;
  for (const auto& e : scene.emitters) known += (known.empty() ? "" : ", ") + std::string("\"") + e.system.name + "\"";
  errors.push_back(scene.file + ": " + pointer + ": expected the name of an emitter (" +
                   (known.empty() ? std::string("none defined") : known) + "), found \"" + name + "\"");
}

// ---------------------------------------------------------------------------------------------
// cloths[i] (Coutinho §3.9.2; README "cloths[i]")

sim::SpringParams spring_params(ObjectReader& r, const std::string& key, sim::SpringParams fallback) {
  const json* v = object_member(r, key);
  if (!v) return fallback;
  ObjectReader o(*v, r.pointer(key), r.file(), r.errors());
  fallback.stiffness = o.number("stiffness", fallback.stiffness, 0.0, kInf);
  fallback.damping = o.number("damping", fallback.damping, 0.0, kInf);
  o.finish();
  return fallback;
}

ClothScene cloth(const json& j, const std::string& ptr, const std::string& file,
                 std::vector<std::string>& errors, std::size_t index, const sim::Vec3& gravity) {
  ClothScene c;
  sim::ClothDef& d = c.def;
  ObjectReader r(j, ptr, file, errors);
  d.name = r.string("name", "cloth" + std::to_string(index));
  d.rows = std::size_t(r.integer("rows", 16, 1, 1024));
  d.columns = std::size_t(r.integer("columns", 16, 1, 1024));
  if (d.rows * d.columns < 2) r.error_at(r.pointer("rows"), "expected rows * columns >= 2");
  const auto size = r.numbers("size_m", {1.0, 1.0}, 2, 0.0, kInf, true);
  d.width = size[0];
  d.height = size[1];
  if (r.has("mass") && r.has("areal_density"))
    r.error_at(r.pointer("areal_density"), "expected either \"mass\" or \"areal_density\", not both");
  if (r.has("areal_density"))
    d.mass = r.number("areal_density", 0.2, 0.0, kInf, true) * d.width * d.height;
  else
    d.mass = r.number("mass", 0.2, 0.0, kInf, true);
  d.transform.translation = to_vec(r.vec3("position", {0, 0, 1}));
  d.transform.rotation = rotation_from_deg(r.vec3("rotation_deg", {0, 0, 0}));
  if (const json* pins = r.get("pins")) {
    if (pins->is_string()) {
      const std::string preset = r.choice("pins", "", {"top_edge", "two_corners", "left_edge", "none"});
      if (preset == "top_edge")
        for (std::size_t col = 0; col < d.columns; ++col) d.pins.push_back({0, col, {}});
      else if (preset == "two_corners")
        d.pins = {{0, 0, {}}, {0, d.columns - 1, {}}};
      else if (preset == "left_edge")
        for (std::size_t row = 0; row < d.rows; ++row) d.pins.push_back({row, 0, {}});
    } else if (pins->is_array()) {
      for (std::size_t i = 0; i < pins->size(); ++i) {
        const std::string pp = r.pointer("pins") + "/" + std::to_string(i);
        if (!(*pins)[i].is_object()) {
          r.error_at(pp, "expected an object {\"row\", \"column\", \"path\"?}, found " + describe((*pins)[i]));
          continue;
        }
        ObjectReader pr((*pins)[i], pp, file, errors);
        sim::ClothPin pin;
        if (!pr.has("row") || !pr.has("column")) pr.error_at(pp, "expected \"row\" and \"column\"");
        pin.row = std::size_t(pr.integer("row", 0, 0, std::max<long long>(0, (long long)d.rows - 1)));
        pin.column = std::size_t(pr.integer("column", 0, 0, std::max<long long>(0, (long long)d.columns - 1)));
        pin.path = keyframe_path(pr, "path");
        pr.finish();
        d.pins.push_back(pin);
      }
    } else {
      r.error("pins", "an array of {\"row\", \"column\", \"path\"?} or one of \"top_edge\", "
                      "\"two_corners\", \"left_edge\", \"none\"", *pins);
    }
  }
  d.stretch = spring_params(r, "stretch", d.stretch);
  d.shear = spring_params(r, "shear", d.shear);
  d.bend = spring_params(r, "bend", d.bend);
  d.max_strain = r.number("max_strain", d.max_strain, 0.0, kInf);
  const std::string integ = r.choice("integrator", "implicit_euler",
                                     {"implicit_euler", "semi_implicit_euler", "explicit_euler"});
  d.integrator = integ == "semi_implicit_euler" ? sim::ClothIntegrator::semi_implicit_euler
                 : integ == "explicit_euler"    ? sim::ClothIntegrator::explicit_euler
                                                : sim::ClothIntegrator::implicit_euler;
  d.damping = r.number("damping", d.damping, 0.0, kInf);
  if (const json* w = object_member(r, "wind")) {
    ObjectReader o(*w, r.pointer("wind"), file, errors);
    d.wind.velocity = to_vec(o.vec3("velocity", {0, 0, 0}));
    d.wind.gust_amplitude = o.number("gust_amplitude", d.wind.gust_amplitude, 0.0, kInf);
    d.wind.gust_frequency = o.number("gust_frequency", d.wind.gust_frequency, 0.0, kInf, true);
    o.finish();
  }
  if (const json* a = object_member(r, "aero")) {
    ObjectReader o(*a, r.pointer("aero"), file, errors);
    d.aero.drag_coefficient = o.number("drag_coefficient", d.aero.drag_coefficient, 0.0, kInf);
    d.aero.lift_coefficient = o.number("lift_coefficient", d.aero.lift_coefficient, 0.0, kInf);
    d.aero.air_density = o.number("air_density", d.aero.air_density, 0.0, kInf);
    o.finish();
  }
  d.thickness = r.number("thickness", d.thickness, 0.0, kInf);
  d.friction = r.number("friction", d.friction, 0.0, kInf);
  d.collide = r.boolean("collide", d.collide);
  d.collide_particles = r.boolean("collide_particles", d.collide_particles);
  d.restitution = r.number("restitution", d.restitution, 0.0, 1.0);
  d.gravity = gravity;
  const auto color = r.color("color", {0.75, 0.12, 0.12, 1});
  c.color = {float(color[0]), float(color[1]), float(color[2]), float(color[3])};
  c.checker_m = float(r.number("checker_m", 0.0, 0.0, kInf));
  r.finish();
  return c;
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
    scene.world.threads = int(s.integer("threads", 0, 0, 1024));
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
  auto read_array = [&](const std::string& key, auto&& each) { object_array(r, key, each); };
  read_array("colliders", [&](const json& j, const std::string& p, std::size_t i) {
    scene.colliders.push_back(collider(j, p, file, errors, i));
  });
  // Emitters, directly or as an effect preset (effects/presets/*.json) expanded into emitters and
  // force fields; names must be unique because fields and springs select systems by name.
  std::vector<std::string> emitter_pointers;
  std::vector<std::pair<json, std::string>> effect_fields;  // derived force field, its effect's pointer
  read_array("emitters", [&](const json& j, const std::string& p, std::size_t i) {
    if (j.contains("effect")) {
      EffectExpansion x = expand_effect(j, p, file, errors, gravity.z());
      for (const ExpandedEmitter& e : x.emitters) {
        scene.emitters.push_back(emitter(e.object, e.pointer, file, errors, i, gravity));
        emitter_pointers.push_back(p);
      }
      for (const json& f : x.force_fields) effect_fields.emplace_back(f, p);
      return;
    }
    scene.emitters.push_back(emitter(j, p, file, errors, i, gravity));
    emitter_pointers.push_back(p);
  });
  for (std::size_t a = 0; a < scene.emitters.size(); ++a)
    for (std::size_t b = 0; b < a; ++b)
      if (scene.emitters[a].system.name == scene.emitters[b].system.name) {
        errors.push_back(file + ": " + emitter_pointers[a] + "/name: expected a name not used by another emitter (" +
                         emitter_pointers[b] + "), found \"" + scene.emitters[a].system.name + "\"");
        break;
      }
  for (const auto& [f, p] : effect_fields) {
    scene.force_fields.push_back(force_field(f, p, file, errors));
    for (const auto& name : scene.force_fields.back().systems) check_system_name(scene, name, p, errors);
  }
  // Force fields and attractor springs name the systems (emitters) they act on.
  read_array("force_fields", [&](const json& j, const std::string& p, std::size_t) {
    scene.force_fields.push_back(force_field(j, p, file, errors));
    for (std::size_t k = 0; k < scene.force_fields.back().systems.size(); ++k)
      check_system_name(scene, scene.force_fields.back().systems[k], p + "/systems/" + std::to_string(k), errors);
  });
  read_array("attractor_springs", [&](const json& j, const std::string& p, std::size_t) {
    scene.attractor_springs.push_back(attractor_spring(j, p, file, errors));
    if (j.contains("system")) check_system_name(scene, scene.attractor_springs.back().system, p + "/system", errors);
  });
  read_array("cloths", [&](const json& j, const std::string& p, std::size_t i) {
    scene.cloths.push_back(cloth(j, p, file, errors, i, gravity));
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
  SceneWorld out{sim::World(def), {}, {}, {}};
  try {
    for (const auto& c : scene.colliders) {
      switch (c.type) {
        case ColliderScene::Type::plane: out.colliders.push_back(out.world.add_plane(c.plane)); break;
        case ColliderScene::Type::box: out.colliders.push_back(out.world.add_box(c.box)); break;
        case ColliderScene::Type::sphere: out.colliders.push_back(out.world.add_sphere(c.sphere)); break;
        case ColliderScene::Type::cylinder: out.colliders.push_back(out.world.add_cylinder(c.cylinder)); break;
        case ColliderScene::Type::mesh: out.colliders.push_back(out.world.add_mesh(c.mesh)); break;
      }
    }
    for (const auto& e : scene.emitters) out.systems.push_back(out.world.add_particle_system(e.system));
    for (const auto& f : scene.force_fields) {
      sim::ForceFieldDef def = f.def;
      for (const auto& name : f.systems) def.systems.push_back(out.systems.at(system_index(scene, name)));
      out.world.add_force_field(def);
    }
    for (const auto& a : scene.attractor_springs) {
      sim::AttractorSpringDef def = a.def;
      def.system = out.systems.at(system_index(scene, a.system));
      out.world.add_attractor_spring(def);
    }
    for (const auto& c : scene.cloths) out.cloths.push_back(out.world.add_cloth(c.def));
  } catch (const std::invalid_argument& e) {
    throw SceneError(scene.file + ": " + e.what());
  }
  return out;
}

}  // namespace simreel::app
