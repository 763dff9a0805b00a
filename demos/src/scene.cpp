// The scene loader's top level: scene_from_json reads the document in file order and hands each
// object kind to its reader (scene_read.hpp); load_scene applies --set overrides; build_world
// registers everything with the engine.
#include "scene.hpp"

#include <algorithm>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "effect_scene.hpp"
#include "json_reader.hpp"
#include "scene_read.hpp"

namespace simreel::app {

using namespace scene_read;

namespace {

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

}  // namespace

Scene scene_from_json(const json& doc, const std::string& file) {
  std::vector<std::string> errors;
  Scene scene;
  scene.file = file;
  if (!doc.is_object()) throw SceneError(file + ": /: expected a scene object, found " + describe(doc));
  ObjectReader r(doc, "", file, errors);
  r.string("$schema", "");  // the JSON Schema an editor checks the file with (`simreel schema`)
  r.string("description", "");
  scene.seed = std::uint64_t(r.integer("seed", 0, 0, std::numeric_limits<long long>::max()));
  scene.fps = r.number("fps", 30.0, 0.0, 1000.0, true);
  scene.frames = int(r.integer("frames", 120, 1, kMaxFrames));

  sim::Vec3 gravity{0, 0, -9.81};
  if (const json* sim_j = object_member(r, "simulation")) {
    ObjectReader s(*sim_j, r.pointer("simulation"), file, errors);
    scene.world.max_step = s.number("max_step", scene.world.max_step, sim::ranges::kWorldMaxStep);
    scene.world.contact_speed = s.number("contact_speed", scene.world.contact_speed, sim::ranges::kWorldContactSpeed);
    scene.world.max_speed = s.number("max_speed", scene.world.max_speed, sim::ranges::kWorldMaxSpeed);
    scene.world.max_distance = s.number("max_distance", scene.world.max_distance, sim::ranges::kWorldMaxDistance);
    gravity = to_vec(s.vec3("gravity", {0, 0, -9.81}));
    scene.world.threads = int(s.integer("threads", 0, 0, 1024));
    scene.world.body_substeps = int(s.integer("body_substeps", 1, 1, 16));
    s.finish();
  }
  if (std::string m = steps_per_frame_problem(scene.fps, scene.world.max_step); !m.empty())
    errors.push_back(file + ": /fps, /simulation/max_step: " + m);
  render_settings(r, scene);
  camera(r, scene);
  light(r, scene);
  auto read_array = [&](const std::string& key, auto&& each) { object_array(r, key, each); };
  read_array("colliders", [&](const json& j, const std::string& p, std::size_t i) {
    scene.colliders.push_back(collider(j, p, file, errors, i));
    scene.colliders.back().dynamic.gravity = gravity;  // dynamic bodies fall with the scene's gravity
  });
  // bodies[i] join the colliders (one list of named bodies for joints, springs and drawing).
  read_array("bodies", [&](const json& j, const std::string& p, std::size_t i) {
    scene.colliders.push_back(body(j, p, file, errors, i, gravity));
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
  // A particle born beyond the world's bound, faster than simulation.max_speed or larger than
  // the world is reported as diverged at the first step (exit 1, after the run began): a bad
  // scene, said here. The emitter's position, then each draw's largest likely value (a uniform
  // one's max, else the mean plus 5 deviations up to the max) and its shape's sizes are compared
  // with the bounds.
  for (std::size_t a = 0; a < scene.emitters.size(); ++a) {
    const sim::ParticleSystemDef& sys = scene.emitters[a].system;
    const sim::EmitterDef& em = sys.emitter;
    if (!scene.emitters[a].follow_camera && em.transform.translation.cwiseAbs().maxCoeff() > scene.world.max_distance) {
      const sim::Vec3& at = em.transform.translation;
      std::ostringstream m;
      m.precision(10);  // as sim::format_number: a coordinate just past the bound must not read as it
      m << file << ": " << emitter_pointers[a] << "/position: expected each coordinate within +-"
        << scene.world.max_distance << " m (simulation.max_distance), found [" << at.x() << ", " << at.y() << ", "
        << at.z() << "]";
      errors.push_back(m.str());
    }
    const auto over = [&](const std::string& key, double value, double bound, const char* unit,
                          const char* bound_key, const char* what) {
      if (value <= bound) return;
      std::ostringstream m;
      m.precision(10);  // as sim::format_number
      m << file << ": " << emitter_pointers[a] << "/" << key << ": expected " << what << " of at most " << bound
        << " " << unit << " (" << bound_key << "), found " << value;
      errors.push_back(m.str());
    };
    const auto beyond = [&](const sim::Distribution& d, double bound, const char* key, const char* unit,
                            const char* bound_key) {
      if (d.uniform) return over(key, d.max, bound, unit, bound_key, "a max");
      over(key, std::min(d.max, d.mean + 5.0 * d.deviation), bound, unit, bound_key,
           d.deviation > 0.0 ? "a mean + 5 deviations (or max)" : "a mean");
    };
    const double reach = scene.world.max_distance, fastest = scene.world.max_speed;
    beyond(em.start_speed, fastest, "start_speed", "m/s", "simulation.max_speed");
    beyond(em.radius, reach, "particle_radius", "m", "simulation.max_distance");
    const char* world = "simulation.max_distance";
    over("disk_radius", em.disk_radius, reach, "m", world, "a radius");
    over("sphere_radius", em.sphere_radius, reach, "m", world, "a radius");
    over("cube_size", em.cube_size, reach, "m", world, "a size");
    for (std::size_t k = 0; k < 2; ++k) over("quad_size/" + std::to_string(k), em.quad_size[k], reach, "m", world, "a size");
    for (std::size_t k = 0; k < 3; ++k) over("box_size/" + std::to_string(k), em.box_size[k], reach, "m", world, "a size");
    for (std::size_t i = 0; i < sys.initial_particles.size(); ++i) {
      const sim::InitialParticle& q = sys.initial_particles[i];
      const std::string at = "initial_particles/" + std::to_string(i) + "/";
      over(at + "position", q.position.cwiseAbs().maxCoeff(), reach, "m", world, "each coordinate");
      over(at + "velocity", q.velocity.cwiseAbs().maxCoeff(), fastest, "m/s", "simulation.max_speed", "each component");
      over(at + "radius", q.radius, reach, "m", world, "a radius");
    }
  }
  // Sub-emitters name the emitter their particles are born in.
  for (const auto& e : scene.emitters)
    for (const auto& se : e.sub_emitters) check_system_name(scene, se.emitter, se.pointer + "/emitter", errors);
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
  // Articulated bodies (Coutinho Ch. 5): the generators add bodies and joints, then joints[i]
  // may name any body, the generated ones included (scene_joints.cpp, scene_generators.cpp).
  read_array("chains", [&](const json& j, const std::string& p, std::size_t i) {
    chain(j, p, file, errors, i, gravity, scene);
  });
  read_array("ragdolls", [&](const json& j, const std::string& p, std::size_t i) {
    ragdoll(j, p, file, errors, i, gravity, scene);
  });
  check_body_names(scene, errors);
  read_array("joints", [&](const json& j, const std::string& p, std::size_t i) {
    scene.joints.push_back(joint(j, p, file, errors, i, scene));
  });
  read_array("springs", [&](const json& j, const std::string& p, std::size_t i) {
    scene.springs.push_back(body_spring(j, p, file, errors, i, scene));
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

sim::BodyDef dynamic_body_def(const ColliderScene& c) {
  sim::BodyDef b;
  b.type = sim::BodyType::dynamic;
  b.name = c.name;
  sim::ShapeDef s;
  switch (c.type) {
    case ColliderScene::Type::box:
      b.pose = c.box.transform;
      s = sim::ShapeDef::box(c.box.half_extents);
      s.material = c.box.material;
      break;
    case ColliderScene::Type::sphere:
      b.pose = c.sphere.transform;
      s = sim::ShapeDef::sphere(c.sphere.radius);
      s.material = c.sphere.material;
      break;
    case ColliderScene::Type::cylinder:
      b.pose = c.cylinder.transform;
      s = sim::ShapeDef::cylinder(c.cylinder.radius, c.cylinder.half_height);
      s.material = c.cylinder.material;
      break;
    case ColliderScene::Type::capsule:
      b.pose = c.capsule.transform;
      s = sim::ShapeDef::capsule(c.capsule.radius, c.capsule.half_height);
      s.material = c.capsule.material;
      break;
    case ColliderScene::Type::body: return c.body;
    case ColliderScene::Type::plane:
    case ColliderScene::Type::mesh:
      // The reader rejects "dynamic" on these; the engine would reject the shape too.
      throw std::invalid_argument("a dynamic collider must be a box, sphere or cylinder (" + c.name + ")");
  }
  s.density = c.dynamic.density;
  b.shapes.push_back(s);
  b.mass = c.dynamic.mass;
  b.linear_velocity = c.dynamic.velocity;
  b.angular_velocity = c.dynamic.angular_velocity;
  b.linear_damping = c.dynamic.linear_damping;
  b.drag_coefficient = c.dynamic.drag_coefficient;
  b.drag_area = c.dynamic.drag_area;
  b.angular_damping = c.dynamic.angular_damping;
  b.gravity = c.dynamic.gravity;
  return b;
}

SceneWorld build_world(const Scene& scene) {
  sim::WorldDef def = scene.world;
  def.seed = scene.seed;
  SceneWorld out{sim::World(def), {}, {}, {}, {}, {}, {}, {}};
  try {
    for (const auto& c : scene.colliders) {
      if (c.type == ColliderScene::Type::body) {
        out.colliders.push_back(out.world.add_body(c.body));
        continue;
      }
      if (c.dynamic.enabled) {
        out.colliders.push_back(out.world.add_body(dynamic_body_def(c)));
        continue;
      }
      switch (c.type) {
        case ColliderScene::Type::plane: out.colliders.push_back(out.world.add_plane(c.plane)); break;
        case ColliderScene::Type::box: out.colliders.push_back(out.world.add_box(c.box)); break;
        case ColliderScene::Type::sphere: out.colliders.push_back(out.world.add_sphere(c.sphere)); break;
        case ColliderScene::Type::cylinder: out.colliders.push_back(out.world.add_cylinder(c.cylinder)); break;
        case ColliderScene::Type::mesh: out.colliders.push_back(out.world.add_mesh(c.mesh)); break;
        case ColliderScene::Type::capsule: {
          // No single-collider def for a capsule: a one-shape static or kinematic body.
          sim::BodyDef b;
          b.name = c.name;
          b.type = c.capsule.path.empty() ? sim::BodyType::static_body : sim::BodyType::kinematic;
          b.pose = c.capsule.transform;
          b.path = c.capsule.path;
          sim::ShapeDef s = sim::ShapeDef::capsule(c.capsule.radius, c.capsule.half_height);
          s.material = c.capsule.material;
          b.shapes.push_back(s);
          out.colliders.push_back(out.world.add_body(b));
          break;
        }
        case ColliderScene::Type::body: break;  // added above
      }
    }
    for (const JointScene& j : scene.joints) {
      sim::JointDef d = j.def;
      if (j.index_a != JointScene::kWorld) d.body_a = out.colliders.at(j.index_a);
      if (j.index_b != JointScene::kWorld) d.body_b = out.colliders.at(j.index_b);
      out.joints.push_back(out.world.add_joint(d));
    }
    for (const BodySpringScene& s : scene.springs) {
      sim::BodySpringDef d = s.def;
      if (s.index_a != JointScene::kWorld) d.body_a = out.colliders.at(s.index_a);
      if (s.index_b != JointScene::kWorld) d.body_b = out.colliders.at(s.index_b);
      out.springs.push_back(out.world.add_body_spring(d));
    }
    for (const auto& e : scene.emitters) {
      if (!e.follow_camera) {
        out.systems.push_back(out.world.add_particle_system(e.system));
        continue;
      }
      sim::ParticleSystemDef def = e.system;
      def.emitter.path = follow_camera_path(scene.camera_motion, scene.fps, scene.frames, def.emitter.transform);
      out.systems.push_back(out.world.add_particle_system(def));
    }
    for (std::size_t i = 0; i < scene.emitters.size(); ++i)
      for (const auto& se : scene.emitters[i].sub_emitters) {
        sim::SubEmitterDef def = se.def;
        def.system = out.systems.at(system_index(scene, se.emitter));
        out.world.add_sub_emitter(out.systems.at(i), def);
      }
    for (const auto& f : scene.force_fields) {
      sim::ForceFieldDef def = f.def;
      for (const auto& name : f.systems) def.systems.push_back(out.systems.at(system_index(scene, name)));
      out.force_fields.push_back(out.world.add_force_field(def));
    }
    for (const auto& a : scene.attractor_springs) {
      sim::AttractorSpringDef def = a.def;
      def.system = out.systems.at(system_index(scene, a.system));
      out.attractor_springs.push_back(out.world.add_attractor_spring(def));
    }
    for (const auto& c : scene.cloths) out.cloths.push_back(out.world.add_cloth(c.def));
  } catch (const std::invalid_argument& e) {
    throw SceneError(scene.file + ": " + e.what());
  }
  return out;
}

sim::KeyframePath follow_camera_path(const render::CameraMotion& motion, double fps, int frames,
                                     const sim::Transform& pose) {
  sim::KeyframePath path;
  path.smooth = false;
  const bool moves = !motion.keys.empty() || motion.orbit.has_value();
  const int last = moves ? std::max(frames, 1) : 0;
  for (int k = 0; k <= last; ++k) {
    const double t = double(k) / fps;
    const render::Vec3f eye = render::camera_at(motion, t).position;
    sim::Keyframe key;
    key.time = t;
    key.position = pose.translation + sim::Vec3(double(eye.x()), double(eye.y()), 0.0);
    key.rotation = pose.rotation;
    path.keys.push_back(key);
  }
  return path;
}

}  // namespace simreel::app
