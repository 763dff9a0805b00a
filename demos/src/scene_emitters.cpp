// emitters[i] (Coutinho §3.8-3.9.1): shape, rate, parameter distributions, colour and size over
// lifetime, bursts, particle split; README "emitters[i]".
#include <filesystem>
#include <utility>

#include "scene_read.hpp"
#include "simreel/assets/mesh.hpp"

namespace simreel::app::scene_read {

namespace {

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
  em.disk_radius = r.number("disk_radius", em.disk_radius, ranges::kEmitterSize);
  const auto qs = r.numbers("quad_size", {em.quad_size[0], em.quad_size[1]}, 2, ranges::kEmitterSize);
  em.quad_size = {qs[0], qs[1]};
  em.sphere_radius = r.number("sphere_radius", em.sphere_radius, ranges::kEmitterSize);
  const auto bs = r.numbers("box_size", {em.box_size[0], em.box_size[1], em.box_size[2]}, 3, ranges::kEmitterSize);
  em.box_size = {bs[0], bs[1], bs[2]};
  em.cube_size = r.number("cube_size", em.cube_size, ranges::kEmitterSize);
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
        b.time = br.number("time", 0.0, ranges::kBurstTime);
        if (!br.has("count")) br.error_at(bp, "expected a \"count\" (particles per burst)");
        b.count = std::size_t(br.integer("count", 0, 0, 50'000'000));
        b.repeat_interval = br.number("repeat_interval", 0.0, ranges::kBurstRepeatInterval);
        b.cycles = std::size_t(br.integer("cycles", 1, 0, 1'000'000'000));
        if (b.cycles == 0 && !(b.repeat_interval > 0.0))
          br.error_at(br.pointer("cycles"), "expected cycles >= 1, or a repeat_interval > 0 for cycles 0 (forever)");
        br.finish();
        em.bursts.push_back(b);
      }
    }
  }
  em.inherit_velocity = r.number("inherit_velocity", 0.0, ranges::kEmitterInheritVelocity);
  em.color_deviation = r.number("color_deviation", 0.0, ranges::kEmitterColorDeviation);
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
        key.t = kr.number("t", 0.0, ranges::kSizeKeyT);
        key.size = kr.number("size", 1.0, ranges::kSizeKeySize);
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
    sp.children = std::size_t(o.integer("children", long(sp.children), ranges::kSplitChildren));
    sp.age = o.number("age", sp.age, ranges::kSplitAge);
    sp.delay_steps = std::size_t(o.integer("delay_steps", long(sp.delay_steps), ranges::kSplitDelaySteps));
    sp.depth = std::size_t(o.integer("depth", long(sp.depth), ranges::kSplitDepth));
    sp.velocity_fraction = o.number("velocity_fraction", sp.velocity_fraction, ranges::kSplitVelocityFraction);
    sp.direction_deviation_deg = o.number("direction_deviation_deg", sp.direction_deviation_deg, ranges::kSplitDirectionDeviationDeg);
    sp.size_fraction = o.number("size_fraction", sp.size_fraction, ranges::kSplitSizeFraction);
    sp.lifetime_deviation = o.number("lifetime_deviation", sp.lifetime_deviation, ranges::kSplitLifetimeDeviation);
    o.finish();
  }
}

/// sub_emitters[k] (Unity's sub-emitters): particles born in another emitter when one of this
/// emitter's particles dies; the target's name is checked once every emitter is read (scene.cpp).
void sub_emitters(ObjectReader& r, std::vector<SubEmitterScene>& out) {
  object_array(r, "sub_emitters", [&](const json& j, const std::string& p, std::size_t) {
    ObjectReader o(j, p, r.file(), r.errors());
    SubEmitterScene se;
    se.pointer = p;
    if (!o.has("emitter")) o.error_at(p, "expected an \"emitter\" (the name of the emitter whose particles are born)");
    se.emitter = o.string("emitter", "");
    (void)o.choice("trigger", "death", {"death"});
    se.def.trigger = sim::SubEmitterTrigger::death;
    se.def.count = std::size_t(o.integer("count", 10, 1, 1'000'000));
    se.def.probability = o.number("probability", 1.0, 0.0, 1.0);
    se.def.inherit_velocity = o.number("inherit_velocity", 1.0, 0.0, 1.0);
    se.def.split_children = o.boolean("split_children", true);
    o.finish();
    out.push_back(se);
  });
}

}  // namespace

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
  em.rate = r.number("rate", em.rate, ranges::kEmitterRate);
  em.start_time = r.number("start_time", 0.0, 0.0, kInf);
  em.stop_time = r.number("stop_time", 1e300, 0.0, kInf);
  em.lifetime = distribution(r, "lifetime", em.lifetime, 0.0, kInf, "s");
  em.start_speed = distribution(r, "start_speed", em.start_speed, 0.0, kInf, "m/s");
  em.spread_deg = distribution(r, "spread_deg", em.spread_deg, 0.0, 180.0, "degrees");
  em.mass = distribution(r, "mass", em.mass, 0.0, sim::ranges::kParticleFloatMax, "kg");
  if (em.mass.mean <= 0.0) r.error_at(r.pointer("mass"), "expected a mean mass > 0 kg");
  em.radius = distribution(r, "particle_radius", em.radius, 0.0, sim::ranges::kParticleFloatMax, "m");
  if (em.radius.mean <= 0.0) r.error_at(r.pointer("particle_radius"), "expected a mean radius > 0 m");
  em.max_particles = std::size_t(r.integer("max_particles", 100000, ranges::kEmitterMaxParticles));

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
  e.follow_camera = r.boolean("follow_camera", false);
  if (e.follow_camera && !em.path.empty())
    r.error_at(r.pointer("follow_camera"), "expected either \"follow_camera\": true or a \"path\", not both");
  emitter_extras(r, em);
  sub_emitters(r, e.sub_emitters);
  s.gravity = to_vec(r.vec3("gravity", {gravity.x(), gravity.y(), gravity.z()}));
  s.drag = r.number("drag", 0.0, ranges::kSystemDrag);
  s.drag_quadratic = r.number("drag_quadratic", 0.0, ranges::kSystemDragQuadratic);
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
  e.trail_s = float(r.number("trail_s", 0.0, 0.0, 10.0));
  e.emissive = float(r.number("emissive", 1.0, 0.0, 100.0));
  e.strobe_hz = float(r.number("strobe_hz", 0.0, 0.0, 1000.0));
  e.strobe_duty = float(r.number("strobe_duty", 0.5, 0.0, 1.0, true));
  if ((r.has("strobe_hz") || r.has("strobe_duty")) && e.style != render::ParticleStyle::additive)
    r.error_at(r.pointer(r.has("strobe_hz") ? "strobe_hz" : "strobe_duty"),
               "expected \"strobe_hz\" and \"strobe_duty\" only with \"render_style\": \"additive\"");
  const std::string texture = r.choice("texture", "none", {"none", "smoke", "flame"});
  e.texture = texture == "smoke"   ? render::ParticleTexture::smoke
              : texture == "flame" ? render::ParticleTexture::flame
                                   : render::ParticleTexture::none;
  if (e.texture == render::ParticleTexture::smoke && e.style != render::ParticleStyle::soft)
    r.error_at(r.pointer("texture"), "expected \"smoke\" only with \"render_style\": \"soft\"");
  if (e.texture == render::ParticleTexture::flame && e.style != render::ParticleStyle::additive)
    r.error_at(r.pointer("texture"), "expected \"flame\" only with \"render_style\": \"additive\"");
  r.finish();
  return e;
}

}  // namespace simreel::app::scene_read
