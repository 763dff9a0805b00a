// cloths[i] (Coutinho §3.9.2; README "cloths[i]").
#include <algorithm>
#include <array>
#include <filesystem>
#include <map>

#include "simreel/assets/mesh.hpp"
#include "scene_read.hpp"

namespace simreel::app::scene_read {

namespace {

sim::SpringParams spring_params(ObjectReader& r, const std::string& key, sim::SpringParams fallback) {
  const json* v = object_member(r, key);
  if (!v) return fallback;
  ObjectReader o(*v, r.pointer(key), r.file(), r.errors());
  fallback.stiffness = o.number("stiffness", fallback.stiffness, ranges::kClothStiffness);
  fallback.damping = o.number("damping", fallback.damping, ranges::kClothSpringDamping);
  o.finish();
  return fallback;
}

/// "mesh": a triangle mesh file (relative to the scene file) as the cloth (issue 16). Vertices at
/// the same place are welded (a file's UV or normal seams would otherwise cut the cloth); "scale"
/// (one number or [sx, sy, sz]) multiplies them. Returns the mesh area (m²) for "areal_density";
/// `file` and `scale` get the mesh file and the scale (for pins by group).
double cloth_mesh(ObjectReader& r, sim::ClothMesh& mesh, std::filesystem::path& file,
                  std::array<double, 3>& scale) {
  scale = mesh_scale(r);
  const std::string name = r.string("mesh", "");
  if (name.empty()) {
    r.error_at(r.pointer("mesh"), "expected a mesh file name (OBJ, PLY, glTF, ...)");
    return 0.0;
  }
  const std::filesystem::path path = std::filesystem::path(r.file()).parent_path() / name;
  file = path;
  assets::TriangleMesh m;
  try {
    m = assets::load_mesh(path);
  } catch (const assets::AssetError& e) {
    r.error_at(r.pointer("mesh"), e.what());
    return 0.0;
  }
  if (!scale_keeps_mesh_finite(r, scale, m.positions)) return 0.0;
  std::map<std::array<float, 3>, std::uint32_t> weld;
  std::vector<std::uint32_t> index(m.positions.size());
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    const auto& p = m.positions[i];
    const auto [it, fresh] = weld.try_emplace({p.x(), p.y(), p.z()}, std::uint32_t(mesh.vertices.size()));
    index[i] = it->second;
    if (!fresh) continue;
    mesh.vertices.emplace_back(double(p.x()) * scale[0], double(p.y()) * scale[1], double(p.z()) * scale[2]);
    mesh.uvs.insert(mesh.uvs.end(), {m.uvs[i].x(), 1.0f - m.uvs[i].y()});
  }
  bool any_uv = false;
  for (const auto& uv : m.uvs) any_uv = any_uv || uv.x() != 0.0f || uv.y() != 0.0f;
  if (!any_uv) mesh.uvs.clear();  // planar from the local x, y (ClothTopology)
  double area = 0.0;
  for (const auto& t : m.triangles) {
    mesh.triangles.insert(mesh.triangles.end(), {index[t[0]], index[t[1]], index[t[2]]});
    const sim::Vec3 &a = mesh.vertices[index[t[0]]], &b = mesh.vertices[index[t[1]]],
                    &c = mesh.vertices[index[t[2]]];
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  // The engine's own checks (ClothTopology), reported here with the file and the pointer.
  try {
    (void)sim::ClothTopology(mesh);
  } catch (const std::invalid_argument& e) {
    r.error_at(r.pointer("mesh"), path.string() + ": " + e.what());
    mesh = {};
  }
  return area;
}

/// Pins of a mesh cloth: {"vertex": i}, {"box_min": [x, y, z], "box_max": [x, y, z]} (every
/// vertex inside the box, mesh coordinates after "scale") or {"group": name} (every vertex of the
/// faces of a named part of the file: an OBJ "g"/"o", a glTF node or mesh; assets::MeshGroup),
/// each with an optional "path".
void mesh_pins(ObjectReader& r, const json& pins, sim::ClothDef& d, const std::filesystem::path& file,
               const std::array<double, 3>& scale) {
  const std::size_t n = d.mesh.vertices.size();
  std::vector<assets::MeshGroup> groups;
  bool groups_read = false;
  for (std::size_t i = 0; i < pins.size(); ++i) {
    const std::string pp = r.pointer("pins") + "/" + std::to_string(i);
    if (!pins[i].is_object()) {
      r.error_at(pp, "expected an object {\"vertex\"}, {\"group\"} or {\"box_min\", \"box_max\"}, found " + describe(pins[i]));
      continue;
    }
    ObjectReader pr(pins[i], pp, r.file(), r.errors());
    sim::KeyframePath path = keyframe_path(pr, "path");
    if (pr.has("vertex")) {
      pr.record("vertex", {{"type", "integer"}, {"minimum", 0}});
      const auto v = std::size_t(pr.integer("vertex", 0, 0, std::max<long long>(0, (long long)n - 1)));
      d.pins.push_back({0, v, path});
    } else if (pr.has("box_min") && pr.has("box_max")) {
      const auto lo = pr.vec3("box_min", {0, 0, 0}), hi = pr.vec3("box_max", {0, 0, 0});
      std::size_t found = 0;
      for (std::size_t v = 0; v < n; ++v) {
        const sim::Vec3& p = d.mesh.vertices[v];
        if (p.x() < lo[0] || p.y() < lo[1] || p.z() < lo[2] || p.x() > hi[0] || p.y() > hi[1] || p.z() > hi[2])
          continue;
        d.pins.push_back({0, v, path});
        ++found;
      }
      if (found == 0 && n > 0) pr.error_at(pp, "expected the box to hold some vertex of the mesh, found none");
    } else if (pr.has("group")) {
      const std::string name = pr.string("group", "");
      if (!groups_read) {
        groups_read = true;
        try {
          groups = assets::load_mesh_groups(file);
        } catch (const assets::AssetError& e) {
          pr.error_at(pr.pointer("group"), e.what());
        }
      }
      const auto g = std::find_if(groups.begin(), groups.end(), [&](const auto& x) { return x.name == name; });
      if (g == groups.end()) {
        std::string names;
        for (const auto& x : groups) names += (names.empty() ? "\"" : ", \"") + x.name + "\"";
        pr.error_at(pr.pointer("group"), "expected a group of " + file.filename().string() + " (" +
                                             (names.empty() ? std::string("it has none") : "it has " + names) +
                                             "), found \"" + name + "\"");
      } else {
        // The cloth's vertices are the file's welded by position, scaled (cloth_mesh): the same
        // arithmetic on a group's positions finds them exactly.
        std::map<std::array<double, 3>, std::size_t> at;
        for (std::size_t v = 0; v < n; ++v)
          at.emplace(std::array<double, 3>{d.mesh.vertices[v].x(), d.mesh.vertices[v].y(), d.mesh.vertices[v].z()}, v);
        std::vector<std::uint8_t> taken(n, 0);
        for (const auto& p : g->positions) {
          const auto it = at.find({double(p.x()) * scale[0], double(p.y()) * scale[1], double(p.z()) * scale[2]});
          if (it == at.end() || taken[it->second]) continue;
          taken[it->second] = 1;
          d.pins.push_back({0, it->second, path});
        }
      }
    } else {
      pr.error_at(pp, "expected \"vertex\", \"group\" or both \"box_min\" and \"box_max\"");
    }
    pr.finish();
  }
}

}  // namespace

ClothScene cloth(const json& j, const std::string& ptr, const std::string& file,
                 std::vector<std::string>& errors, std::size_t index, const sim::Vec3& gravity) {
  ClothScene c;
  sim::ClothDef& d = c.def;
  ObjectReader r(j, ptr, file, errors);
  d.name = r.string("name", "cloth" + std::to_string(index));
  double mesh_area = 0.0;
  std::filesystem::path mesh_file;
  std::array<double, 3> scale{1, 1, 1};
  if (r.has("mesh")) {
    for (const char* key : {"rows", "columns", "size_m"})
      if (r.has(key)) r.error_at(r.pointer(key), std::string("expected either \"mesh\" or \"") + key + "\", not both");
    mesh_area = cloth_mesh(r, d.mesh, mesh_file, scale);
  }
  if (r.has("mesh")) {  // one row of vertices (sim::ClothDef::mesh)
    d.rows = 1;
    d.columns = std::max<std::size_t>(d.mesh.vertices.size(), 1);
  } else {
    d.rows = std::size_t(r.integer("rows", 16, ranges::kClothGrid));
    d.columns = std::size_t(r.integer("columns", 16, ranges::kClothGrid));
    if (d.rows * d.columns < 2) r.error_at(r.pointer("rows"), "expected rows * columns >= 2");
    const auto size = r.numbers("size_m", {1.0, 1.0}, 2, ranges::kClothSize);
    d.width = size[0];
    d.height = size[1];
  }
  if (r.has("mass") && r.has("areal_density"))
    r.error_at(r.pointer("areal_density"), "expected either \"mass\" or \"areal_density\", not both");
  if (r.has("areal_density"))
    d.mass = r.has("mesh") ? r.number("areal_density", 0.2, 0.0, kInf, true) * mesh_area
                           : r.number("areal_density", 0.2, 0.0, kInf, true) * d.width * d.height;
  else
    d.mass = r.number("mass", 0.2, ranges::kClothMass);
  d.transform.translation = to_vec(r.vec3("position", {0, 0, 1}));
  d.transform.rotation = rotation_from_deg(r.vec3("rotation_deg", {0, 0, 0}));
  if (const json* pins = r.get("pins"); pins && r.has("mesh")) {
    if (pins->is_array()) mesh_pins(r, *pins, d, mesh_file, scale);
    else if (!(pins->is_string() && pins->get<std::string>() == "none"))
      r.error("pins", "for a mesh cloth an array of {\"vertex\"}, {\"group\"} or {\"box_min\", \"box_max\"} or \"none\"", *pins);
  } else if (pins) {
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
        // Their upper bound depends on the cloth: the schema (KeyLog) records them without one.
        for (const char* key : {"row", "column"}) pr.record(key, {{"type", "integer"}, {"minimum", 0}});
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
  d.max_strain = r.number("max_strain", d.max_strain, ranges::kClothMaxStrain);
  const std::string integ = r.choice("integrator", "implicit_euler",
                                     {"implicit_euler", "semi_implicit_euler", "explicit_euler"});
  d.integrator = integ == "semi_implicit_euler" ? sim::ClothIntegrator::semi_implicit_euler
                 : integ == "explicit_euler"    ? sim::ClothIntegrator::explicit_euler
                                                : sim::ClothIntegrator::implicit_euler;
  d.damping = r.number("damping", d.damping, ranges::kClothDamping);
  if (const json* w = object_member(r, "wind")) {
    ObjectReader o(*w, r.pointer("wind"), file, errors);
    d.wind.velocity = to_vec(o.vec3("velocity", {0, 0, 0}));
    d.wind.gust_amplitude = o.number("gust_amplitude", d.wind.gust_amplitude, ranges::kClothGustAmplitude);
    d.wind.gust_frequency = o.number("gust_frequency", d.wind.gust_frequency, ranges::kClothGustFrequency);
    o.finish();
  }
  if (const json* a = object_member(r, "aero")) {
    ObjectReader o(*a, r.pointer("aero"), file, errors);
    d.aero.drag_coefficient = o.number("drag_coefficient", d.aero.drag_coefficient, ranges::kClothAero);
    d.aero.lift_coefficient = o.number("lift_coefficient", d.aero.lift_coefficient, ranges::kClothAero);
    d.aero.air_density = o.number("air_density", d.aero.air_density, ranges::kClothAero);
    o.finish();
  }
  d.thickness = r.number("thickness", d.thickness, ranges::kClothThickness);
  d.friction = r.number("friction", d.friction, ranges::kClothFriction);
  d.collide = r.boolean("collide", d.collide);
  d.collide_particles = r.boolean("collide_particles", d.collide_particles);
  d.self_collision = r.boolean("self_collision", d.self_collision);
  d.collide_cloths = r.boolean("collide_cloths", d.collide_cloths);
  d.restitution = r.number("restitution", d.restitution, ranges::kClothRestitution);
  d.gravity = gravity;
  const auto color = r.color("color", {0.75, 0.12, 0.12, 1});
  c.color = {float(color[0]), float(color[1]), float(color[2]), float(color[3])};
  c.checker_m = float(r.number("checker_m", 0.0, 0.0, kInf));
  r.finish();
  return c;
}

}  // namespace simreel::app::scene_read
