// colliders[i]: planes, boxes, spheres, cylinders and triangle meshes with their response keys
// (Coutinho §3.6.1, §3.6.3); README "colliders[i]".
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "scene_read.hpp"
#include "simreel/assets/mesh.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::app::scene_read {

namespace {

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
    x.count = int(o.integer("count", x.count, ranges::kHitSplitCount));
    x.speed_fraction = o.number("speed_fraction", x.speed_fraction, ranges::kHitSplitSpeedFraction);
    x.size_fraction = o.number("size_fraction", x.size_fraction, ranges::kHitSplitSizeFraction);
    x.lifetime = o.number("lifetime", x.lifetime, ranges::kHitSplitLifetime);
    x.spread_deg = o.number("spread_deg", x.spread_deg, ranges::kHitSplitSpreadDeg);
    x.min_radius = o.number("min_radius", x.min_radius, ranges::kHitSplitMinRadius);
    o.finish();
  }
}

/// Collider response keys (Coutinho §3.6.1, §3.6.3), read from the collider object itself or
/// from its "collider" sub-object.
sim::Material material(ObjectReader& r) {
  sim::Material m;
  m.restitution = r.number("restitution", m.restitution, ranges::kRestitution);
  m.friction = r.number("friction", m.friction, ranges::kFriction);
  if (r.has("static_friction")) m.static_friction = r.number("static_friction", 0.0, 0.0, kInf);
  hit_action(r, "split", m);
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

}  // namespace

sim::Material material_hit(ObjectReader& r) {
  sim::Material m;
  hit_action(r, "on_hit_split", m);
  return m;
}

ColliderScene collider(const json& j, const std::string& ptr, const std::string& file,
                       std::vector<std::string>& errors, std::size_t index) {
  ColliderScene c;
  ObjectReader r(j, ptr, file, errors);
  const std::string type = r.choice("type", "", {"plane", "box", "sphere", "cylinder", "capsule", "mesh"});
  if (!r.has("type"))
    r.error_at(ptr, "expected a \"type\": one of \"plane\", \"box\", \"sphere\", \"cylinder\", \"capsule\", \"mesh\"");
  c.name = r.string("name", type + std::to_string(index));
  c.color_given = r.has("color");
  std::array<double, 4> color = r.color("color", type == "plane" ? std::array<double, 4>{0.55, 0.56, 0.58, 1}
                                                                 : std::array<double, 4>{0.78, 0.36, 0.16, 1});
  if (const json* mj = object_member(r, "material")) {  // the drawing material: {"color": ...}
    ObjectReader o(*mj, r.pointer("material"), file, errors);
    c.color_given = c.color_given || o.has("color");
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
    const auto he = r.numbers("half_extents", {0.5, 0.5, 0.5}, 3, ranges::kColliderSize);
    c.box.half_extents = {he[0], he[1], he[2]};
    c.box.material = collider_material(r);
    c.box.path = keyframe_path(r, "path");
  } else if (type == "sphere") {
    c.type = ColliderScene::Type::sphere;
    c.sphere.transform.translation = to_vec(r.vec3("position", {0, 0, 0}));
    c.sphere.radius = r.number("radius", 0.5, ranges::kColliderSize);
    c.sphere.material = collider_material(r);
    c.sphere.path = keyframe_path(r, "path");
  } else if (type == "cylinder") {
    c.type = ColliderScene::Type::cylinder;
    c.cylinder.transform.translation = to_vec(r.vec3("position", {0, 0, 0}));
    c.cylinder.transform.rotation = rotation_from_deg(r.vec3("rotation_deg", {0, 0, 0}));
    c.cylinder.radius = r.number("radius", 0.5, ranges::kColliderSize);
    c.cylinder.half_height = r.number("half_height", 0.5, ranges::kColliderSize);
    c.cylinder.material = collider_material(r);
    c.cylinder.path = keyframe_path(r, "path");
  } else if (type == "capsule") {
    // Local z is the capsule's axis (rotation_deg turns it); total length 2 (half_height + radius).
    c.type = ColliderScene::Type::capsule;
    c.capsule.transform.translation = to_vec(r.vec3("position", {0, 0, 0}));
    c.capsule.transform.rotation = rotation_from_deg(r.vec3("rotation_deg", {0, 0, 0}));
    c.capsule.radius = r.number("radius", c.capsule.radius, ranges::kColliderSize);
    c.capsule.half_height = r.number("half_height", c.capsule.half_height, ranges::kColliderSize);
    c.capsule.material = collider_material(r);
    c.capsule.path = keyframe_path(r, "path");
  } else if (type == "mesh") {
    c.type = ColliderScene::Type::mesh;
    c.mesh.transform.translation = to_vec(r.vec3("position", {0, 0, 0}));
    c.mesh.transform.rotation = rotation_from_deg(r.vec3("rotation_deg", {0, 0, 0}));
    c.mesh_scale = mesh_scale(r);  // applied to the vertices
    c.mesh.material = collider_material(r);
    c.mesh.path = keyframe_path(r, "path");
    if (!r.has("file")) r.error_at(ptr, "expected a \"file\": the mesh file (OBJ, STL, PLY, glTF, ...)");
    const std::string name = r.string("file", "");
    if (!name.empty()) {
      // Relative to the scene file's folder.
      const std::filesystem::path path = std::filesystem::path(file).parent_path() / name;
      try {
        auto mesh = std::make_shared<assets::TriangleMesh>(assets::load_mesh(path));
        if (mesh_textures_readable(r, "file", path, *mesh) &&
            scale_keeps_mesh_finite(r, c.mesh_scale, mesh->positions)) {
          c.mesh.vertices.reserve(mesh->positions.size());
          for (const auto& p : mesh->positions)
            c.mesh.vertices.emplace_back(p.x() * c.mesh_scale[0], p.y() * c.mesh_scale[1], p.z() * c.mesh_scale[2]);
          c.mesh.triangles = mesh->triangles;
          c.mesh_asset = std::move(mesh);
          // The engine's own checks (finite vertices, some non-degenerate triangle), reported here
          // with the file and pointer instead of later by build_world with neither.
          try {
            sim::World probe;
            (void)probe.add_mesh(c.mesh);
          } catch (const std::invalid_argument& e) {
            r.error_at(r.pointer("file"), path.string() + ": " + e.what());
          }
        }
      } catch (const assets::AssetError& e) {
        r.error_at(r.pointer("file"), e.what());
      }
    }
  }
  if (type != "") collider_motion(r, type, r.has("path"), c);
  r.finish();
  return c;
}

}  // namespace simreel::app::scene_read
