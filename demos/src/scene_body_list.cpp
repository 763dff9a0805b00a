// bodies[i]: bodies with one or more shapes (Coutinho Ch. 4; Box2D's body/shape split): type
// dynamic | kinematic | static, "shapes": [...] at offsets (a compound) or one shape's keys
// inline ("shape": "box", ...), density or mass, pose, velocities, damping, a material for
// contacts and drawing, a path for a kinematic body. A convex_hull shape comes from "points" or
// from a mesh file's vertices (§2.2.4); a dynamic "mesh" shape becomes a compound of the convex
// pieces of each closed part of the file (convex decomposition, App. F).
// README "bodies[i]".
#include <algorithm>
#include <array>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <string>

#include "scene_read.hpp"
#include "simreel/assets/mesh.hpp"
#include "simreel/render/image.hpp"
#include "simreel/sim/convex_decomposition.hpp"
#include "simreel/sim/hull_mesh.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::app::scene_read {

namespace {

const std::vector<std::string> kShapeTypes{"sphere", "box", "capsule", "cylinder", "convex_hull", "mesh"};

/// The keys only a dynamic body reads.
constexpr std::array<const char*, 8> kDynamicKeys{
    "density",        "mass",            "velocity",         "angular_velocity_deg",
    "linear_damping", "angular_damping", "drag_coefficient", "drag_area_m2"};

/// "points": [[x, y, z], ...] (m), at least 4.
std::vector<sim::Vec3> points(ObjectReader& r) {
  std::vector<sim::Vec3> out;
  const json* a = r.get("points");
  if (!a) return out;
  if (!a->is_array() || a->size() < 4) {
    r.error("points", "an array of at least 4 points [x, y, z] (m)", *a);
    return out;
  }
  for (std::size_t i = 0; i < a->size(); ++i) {
    const json& p = (*a)[i];
    if (!p.is_array() || p.size() != 3 || !p[0].is_number() || !p[1].is_number() || !p[2].is_number()) {
      r.error_at(r.pointer("points") + "/" + std::to_string(i), "expected a point [x, y, z] (m), found " + describe(p));
      return {};
    }
    out.emplace_back(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
  }
  return out;
}

/// Connected parts of a triangle mesh, vertices welded by position (an exporter splits a vertex
/// where normals or UVs change): the welded vertex positions of each part and whether the part is
/// closed (every edge shared by exactly two of its triangles).
struct MeshPart {
  std::vector<sim::Vec3> points;
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< into `points`
  bool closed = true;
};

std::vector<MeshPart> mesh_parts(const std::vector<sim::Vec3>& v, const std::vector<std::array<std::uint32_t, 3>>& t) {
  // Weld: the first vertex of each position stands for all.
  std::vector<std::uint32_t> order(v.size()), weld(v.size());
  std::iota(order.begin(), order.end(), 0u);
  auto less = [&](std::uint32_t a, std::uint32_t b) {
    return std::lexicographical_compare(v[a].data(), v[a].data() + 3, v[b].data(), v[b].data() + 3) ||
           (v[a] == v[b] && a < b);
  };
  std::sort(order.begin(), order.end(), less);
  for (std::size_t i = 0; i < order.size(); ++i)
    weld[order[i]] = i > 0 && v[order[i]] == v[order[i - 1]] ? weld[order[i - 1]] : order[i];
  // Union-find over the triangles' welded vertices.
  std::vector<std::uint32_t> parent(v.size());
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& tri : t)
    for (int k = 1; k < 3; ++k) {
      const std::uint32_t a = find(weld[tri[0]]), b = find(weld[tri[std::size_t(k)]]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  std::map<std::uint32_t, std::size_t> part_of;  // root -> part, in order of first triangle
  std::vector<MeshPart> parts;
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> edges;
  constexpr std::uint32_t kNone = ~0u;
  std::vector<std::uint32_t> local(v.size(), kNone);  // welded vertex → index in its part
  for (const auto& tri : t) {
    const std::uint32_t root = find(weld[tri[0]]);
    auto [it, fresh] = part_of.emplace(root, parts.size());
    if (fresh) {
      parts.emplace_back();
      edges.emplace_back();
    }
    MeshPart& part = parts[it->second];
    std::array<std::uint32_t, 3> lt{};
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = weld[tri[std::size_t(k)]], b = weld[tri[std::size_t((k + 1) % 3)]];
      edges[it->second].emplace_back(std::min(a, b), std::max(a, b));
      if (local[a] == kNone) {
        local[a] = std::uint32_t(part.points.size());
        part.points.push_back(v[a]);
      }
      lt[std::size_t(k)] = local[a];
    }
    part.triangles.push_back(lt);
  }
  for (std::size_t p = 0; p < parts.size(); ++p) {
    auto& e = edges[p];
    std::sort(e.begin(), e.end());
    for (std::size_t i = 0; i < e.size();) {
      std::size_t j = i;
      while (j < e.size() && e[j] == e[i]) ++j;
      if (j - i != 2) parts[p].closed = false;
      i = j;
    }
  }
  return parts;
}

/// The convex decomposition of a closed part, remembered by the part's exact vertices, triangles
/// and options: a scene with the same ring five times decomposes it once. At most 32 parts are
/// kept (a `sweep` loads many scenes in one process); the result depends only on the key.
std::vector<sim::ConvexPiece> decomposed(const MeshPart& part, const sim::ConvexDecompositionOptions& o) {
  std::string key(reinterpret_cast<const char*>(part.points.data()), part.points.size() * sizeof(sim::Vec3));
  key.append(reinterpret_cast<const char*>(part.triangles.data()), part.triangles.size() * sizeof(part.triangles[0]));
  key.append(reinterpret_cast<const char*>(&o.max_concavity), sizeof o.max_concavity);
  key.append(reinterpret_cast<const char*>(&o.max_convex_hulls), sizeof o.max_convex_hulls);
  static std::mutex mutex;
  static std::map<std::string, std::vector<sim::ConvexPiece>> memo;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (const auto it = memo.find(key); it != memo.end()) return it->second;
  }
  std::vector<sim::ConvexPiece> pieces = sim::convex_decomposition(part.points, part.triangles, o);
  const std::lock_guard<std::mutex> lock(mutex);
  if (memo.size() >= 32) memo.clear();
  memo.emplace(std::move(key), pieces);
  return pieces;
}

/// A mesh file relative to the scene's folder, scaled; reports at `key` and returns null on error.
std::shared_ptr<const assets::TriangleMesh> mesh_file(ObjectReader& r, const std::string& key) {
  const std::string name = r.string(key, "");
  if (name.empty()) {
    r.error_at(r.pointer(key), "expected a mesh file (OBJ, STL, PLY, glTF, ...), found \"\"");
    return nullptr;
  }
  const std::filesystem::path path = std::filesystem::path(r.file()).parent_path() / name;
  try {
    auto mesh = std::make_shared<assets::TriangleMesh>(assets::load_mesh(path));
    if (mesh_textures_readable(r, key, path, *mesh)) return mesh;
  } catch (const assets::AssetError& e) {
    r.error_at(r.pointer(key), e.what());
  }
  return nullptr;
}

/// A material's "texture": an image file named relative to the scene file, as its full path;
/// "" when the key is absent (or wrong: the error is recorded with its pointer).
std::string texture_file(ObjectReader& o) {
  if (!o.has("texture")) return {};
  const std::string tex = o.string("texture", "");
  const std::filesystem::path path = std::filesystem::path(o.file()).parent_path() / tex;
  const std::string why = tex.empty() ? std::string("\"\" is not a file") : texture_problem(path);
  if (!why.empty()) {
    o.error_at(o.pointer("texture"), "expected an image file (PNG, JPEG, ...), found \"" + tex + "\" (" + why + ")");
    return {};
  }
  return path.string();
}

/// One shape's keys (from a shapes[k] object, or inline in the body with `type_key` "shape"):
/// appended to body.shapes (several for a dynamic mesh: the hulls of its closed parts).
void shape(ObjectReader& r, const std::string& type_key, sim::BodyType body_type, double density,
           const sim::Material& material, const std::array<double, 4>& body_color, ColliderScene& c) {
  const std::string type = r.choice(type_key, "", kShapeTypes);
  if (!r.has(type_key)) {
    r.error_at(r.pointer(), "expected a \"" + type_key + "\": one of \"sphere\", \"box\", \"capsule\", \"cylinder\", "
                            "\"convex_hull\", \"mesh\"");
    return;
  }
  sim::Transform offset;
  if (type_key == "type") {  // a shapes[k] object: its pose in the body frame
    offset.translation = to_vec(r.vec3("position", {0, 0, 0}));
    offset.rotation = rotation_from_deg(r.vec3("rotation_deg", {0, 0, 0}));
  }
  sim::ShapeDef s;
  s.offset = offset;
  s.material = material;
  std::optional<std::array<float, 4>> own_color;
  std::string own_texture;
  if (type_key == "type") {
    // A shapes[k] object may have its own material (a rubber grip on a steel handle, a red
    // head on a wooden hammer): the body's, with the keys it gives replaced.
    if (const json* mj = object_member(r, "material")) {
      ObjectReader o(*mj, r.pointer("material"), r.file(), r.errors());
      s.material.restitution = o.number("restitution", material.restitution, ranges::kRestitution);
      s.material.friction = o.number("friction", material.friction, ranges::kFriction);
      if (o.has("static_friction")) s.material.static_friction = o.number("static_friction", 0.0, 0.0, kInf);
      if (o.has("color")) {
        const auto rgba = o.color("color", body_color);
        own_color = std::array<float, 4>{float(rgba[0]), float(rgba[1]), float(rgba[2]), float(rgba[3])};
      }
      own_texture = texture_file(o);
      o.finish();
    }
  }
  s.density = r.number("density", density, ranges::kBodyDensity);
  BodyShapeDraw draw;
  if (type == "sphere") {
    s.type = sim::ShapeType::sphere;
    s.radius = r.number("radius", 0.5, ranges::kColliderSize);
  } else if (type == "box") {
    s.type = sim::ShapeType::box;
    const auto he = r.numbers("half_extents", {0.5, 0.5, 0.5}, 3, ranges::kColliderSize);
    s.half_extents = {he[0], he[1], he[2]};
  } else if (type == "capsule" || type == "cylinder") {
    s.type = type == "capsule" ? sim::ShapeType::capsule : sim::ShapeType::cylinder;
    s.radius = r.number("radius", type == "capsule" ? 0.25 : 0.5, ranges::kColliderSize);
    s.half_height = r.number("half_height", 0.5, ranges::kColliderSize);
  } else if (type == "convex_hull" || type == "mesh") {
    const std::array<double, 3> scale = mesh_scale(r);
    std::shared_ptr<const assets::TriangleMesh> asset;
    std::vector<sim::Vec3> verts;
    if (type == "convex_hull" && r.has("points") && r.has("mesh")) {
      r.known("points");
      r.error_at(r.pointer("mesh"), "expected \"points\" or \"mesh\", found both");
    }
    sim::ConvexDecompositionOptions decomposition;  // a dynamic mesh's (read before the file, for the schema)
    if (type == "mesh" && body_type == sim::BodyType::dynamic) {
      decomposition.max_concavity = r.number("max_concavity", 0.0, 0.0, 1e6);
      decomposition.max_convex_hulls = int(r.integer("max_convex_hulls", 32, 1, 256));
    }
    if (type == "mesh" || r.has("mesh")) {
      if (!r.has("mesh")) {
        r.error_at(r.pointer(), "expected a \"mesh\": the mesh file (OBJ, STL, PLY, glTF, ...)");
        return;
      }
      asset = mesh_file(r, "mesh");
      if (!asset || !scale_keeps_mesh_finite(r, scale, asset->positions)) return;
      for (const auto& p : asset->positions) verts.emplace_back(p.x() * scale[0], p.y() * scale[1], p.z() * scale[2]);
    } else if (type == "convex_hull") {
      if (!r.has("points")) {
        r.error_at(r.pointer(), "expected \"points\": [[x, y, z], ...] (m) or a \"mesh\" file for a convex_hull");
        return;
      }
      verts = points(r);
      if (verts.empty()) return;
    }
    draw.scale = scale;
    if (type == "mesh" && body_type != sim::BodyType::dynamic) {
      s.type = sim::ShapeType::mesh;
      s.vertices = std::move(verts);
      s.triangles = asset->triangles;
      draw.asset = asset;
    } else if (type == "mesh") {
      // Dynamic: each closed part of the file becomes the convex pieces of its decomposition
      // (App. F), a convex part one hull of its vertices.
      const std::vector<MeshPart> parts = mesh_parts(verts, asset->triangles);
      for (std::size_t p = 0; p < parts.size(); ++p)
        if (!parts[p].closed) {
          r.error_at(r.pointer("mesh"), "expected a file of closed parts for a dynamic mesh (each becomes a convex "
                                        "hull; or use \"type\": \"static\"), found part " + std::to_string(p + 1) +
                                        " of " + std::to_string(parts.size()) + " open");
          return;
        }
      bool first = true;
      for (std::size_t p = 0; p < parts.size(); ++p) {
        std::vector<sim::ConvexPiece> pieces;
        try {
          pieces = decomposed(parts[p], decomposition);
        } catch (const std::invalid_argument& e) {
          r.error_at(r.pointer("mesh"), "expected closed, outward-wound parts for a dynamic mesh, found part " +
                                            std::to_string(p + 1) + ": " + e.what());
          return;
        }
        for (sim::ConvexPiece& piece : pieces) {
          sim::ShapeDef hull = s;
          hull.type = sim::ShapeType::convex_hull;
          hull.points = std::move(piece);
          c.body.shapes.push_back(std::move(hull));
          BodyShapeDraw d;  // the file is drawn once, with the first piece
          d.scale = scale;
          d.color = own_color;
          d.texture = own_texture;
          if (first) d.asset = asset;
          else d.skip = true;
          first = false;
          c.body_draw.push_back(d);
        }
      }
      return;
    } else {
      s.type = sim::ShapeType::convex_hull;
      s.points = std::move(verts);
      // Degenerate point sets here, with the pointer (the engine would say it without one).
      try {
        (void)sim::hull_mesh(s.points);
      } catch (const std::exception& e) {
        std::string m = e.what();
        if (m.rfind("convex_hull: ", 0) == 0) m = m.substr(13);
        r.error_at(r.pointer(r.has("points") ? "points" : "mesh"),
                   "expected points bounding a volume for a convex hull (at least 4, not all in one plane), found: " + m);
        return;
      }
    }
  }
  c.body.shapes.push_back(std::move(s));
  draw.color = own_color;
  draw.texture = own_texture;
  c.body_draw.push_back(draw);
}

}  // namespace

ColliderScene body(const json& j, const std::string& ptr, const std::string& file, std::vector<std::string>& errors,
                   std::size_t index, const sim::Vec3& gravity) {
  const std::size_t errors_before = errors.size();
  ColliderScene c;
  c.type = ColliderScene::Type::body;
  c.pointer = ptr;
  ObjectReader r(j, ptr, file, errors);
  c.name = r.string("name", "body" + std::to_string(index));
  const std::string type = r.choice("type", "dynamic", {"dynamic", "kinematic", "static"});
  sim::BodyDef& b = c.body;
  b.name = c.name;
  b.type = type == "static" ? sim::BodyType::static_body
           : type == "kinematic" ? sim::BodyType::kinematic
                                 : sim::BodyType::dynamic;
  b.pose.translation = to_vec(r.vec3("position", {0, 0, 0}));
  b.pose.rotation = rotation_from_deg(r.vec3("rotation_deg", {0, 0, 0}));
  b.path = keyframe_path(r, "path");
  if (type == "kinematic" && b.path.empty())
    r.error_at(r.has("path") ? r.pointer("path") : ptr, "expected a \"path\" to follow for a \"kinematic\" body, found none");
  if (type != "kinematic" && !b.path.empty())
    r.error_at(r.pointer("path"), "expected \"type\": \"kinematic\" for a body with a \"path\", found \"" + type + "\"");
  // Contact and drawing material.
  sim::Material m;
  std::array<double, 4> color{0.78, 0.36, 0.16, 1};
  if (const json* mj = object_member(r, "material")) {
    ObjectReader o(*mj, r.pointer("material"), file, errors);
    m.restitution = o.number("restitution", m.restitution, ranges::kRestitution);
    m.friction = o.number("friction", m.friction, ranges::kFriction);
    if (o.has("static_friction")) m.static_friction = o.number("static_friction", 0.0, 0.0, kInf);
    c.color_given = o.has("color");
    color = o.color("color", color);
    c.texture = texture_file(o);
    o.finish();
  }
  c.color = {float(color[0]), float(color[1]), float(color[2]), float(color[3])};
  // Dynamic keys.
  if (b.type == sim::BodyType::dynamic) {
    c.dynamic.enabled = true;
    if (r.has("density") && r.has("mass")) r.error_at(r.pointer("mass"), "expected \"density\" or \"mass\", found both");
    b.mass = r.has("mass") ? r.number("mass", 0.0, ranges::kBodyMass) : 0.0;
    b.linear_velocity = to_vec(r.vec3("velocity", {0, 0, 0}));
    b.angular_velocity = to_vec(r.vec3("angular_velocity_deg", {0, 0, 0})) * kDeg;
    b.linear_damping = r.number("linear_damping", 0.0, ranges::kBodyDamping);
    b.angular_damping = r.number("angular_damping", 0.0, ranges::kBodyDamping);
    b.drag_coefficient = r.number("drag_coefficient", b.drag_coefficient, ranges::kBodyDragCoefficient);
    b.drag_area = r.number("drag_area_m2", 0.0, ranges::kBodyDragArea);
    b.gravity = gravity;
  } else {
    for (const char* key : kDynamicKeys)
      if (r.has(key)) {
        r.known(key);
        r.error_at(r.pointer(key), std::string("expected \"type\": \"dynamic\" for \"") + key + "\", found a " + type + " body");
      }
  }
  const double density = b.type == sim::BodyType::dynamic ? r.number("density", 1000.0, ranges::kBodyDensity) : 1000.0;
  // Shapes: an array, or one shape inline.
  if (r.has("shapes") && r.has("shape")) {
    r.known("shape");
    r.error_at(r.pointer("shape"), "expected \"shapes\": [...] or one inline \"shape\", found both");
  }
  if (r.has("shapes")) {
    const json* a = r.get("shapes");
    if (!a->is_array() || a->empty()) r.error("shapes", "a non-empty array of shape objects", *a);
    object_array(r, "shapes", [&](const json& sj, const std::string& sp, std::size_t) {
      ObjectReader o(sj, sp, file, errors);
      shape(o, "type", b.type, density, m, color, c);
      o.finish();
    });
  } else if (!r.has("shape")) {
    r.error_at(ptr, "expected \"shapes\": [...] or an inline \"shape\": one of \"sphere\", \"box\", \"capsule\", "
                    "\"cylinder\", \"convex_hull\", \"mesh\"");
  } else {
    shape(r, "shape", b.type, density, m, color, c);
  }
  r.finish();
  // The engine's own checks (shape sizes, mass properties of closed hulls), with the pointer.
  if (!b.shapes.empty() && errors.size() == errors_before) {
    try {
      sim::World probe;
      (void)probe.add_body(b);
    } catch (const std::invalid_argument& e) {
      r.error_at(ptr, e.what());
    }
  }
  return c;
}

}  // namespace simreel::app::scene_read
