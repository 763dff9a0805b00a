#include "scene_list_builder.hpp"

#include <algorithm>

#include "simreel/render/camera_path.hpp"
#include "simreel/render/mesh.hpp"
#include "simreel/sim/hull_mesh.hpp"

namespace simreel::app {

namespace {

/// (s) The camera's exposure (render.shutter_deg / 360 / fps) that motion-blurs additive
/// particles: their trails grow by it, and with a shutter every additive particle streaks.
float particle_shutter_s(const Scene& scene) {
  return scene.fps > 0.0 ? float(double(scene.render.shutter_deg) / 360.0 / scene.fps) : 0.f;
}

/// Renderer material of a collider drawn in its scene colour.
render::Material collider_material(const ColliderScene& c) {
  render::Material m;
  m.base_color = c.color;
  m.checker_m = c.checker_m;
  return m;
}

render::MeshDesc body_desc(const ColliderScene& c);

/// A collider's drawable description (plane, box or mesh).
std::variant<render::PlaneDesc, render::BoxDesc, render::MeshDesc> collider_desc(const ColliderScene& c) {
  switch (c.type) {
    case ColliderScene::Type::plane: {
      render::PlaneDesc d;
      d.point = c.plane.point.cast<float>();
      d.normal = c.plane.normal.normalized().cast<float>();
      d.half_size = c.draw_half_size;
      d.color = c.color;
      d.checker_m = c.checker_m;
      return d;
    }
    case ColliderScene::Type::box: {
      render::BoxDesc d;
      d.half_extents = c.box.half_extents.cast<float>();
      d.color = c.color;
      return d;
    }
    case ColliderScene::Type::sphere: {
      render::MeshDesc d = render::make_sphere_mesh(float(c.sphere.radius), 48);
      d.material = collider_material(c);
      return d;
    }
    case ColliderScene::Type::cylinder: {
      render::MeshDesc d = render::make_cylinder_mesh(float(c.cylinder.radius), float(c.cylinder.half_height), 48);
      d.material = collider_material(c);
      return d;
    }
    case ColliderScene::Type::capsule: {
      render::MeshDesc d = render::make_capsule_mesh(float(c.capsule.radius), float(c.capsule.half_height), 32);
      d.material = collider_material(c);
      return d;
    }
    case ColliderScene::Type::mesh: break;
    case ColliderScene::Type::body: return body_desc(c);
  }
  return mesh_desc(c);
}

/// A polyhedron drawn flat: each planar face gets its own vertices with the face normal and
/// UVs in metres in the face's plane (u along its first edge).
void add_flat_faces(const std::vector<sim::Vec3>& v, const std::vector<std::vector<std::uint32_t>>& faces,
                    render::MeshDesc& d) {
  for (const auto& f : faces) {
    if (f.size() < 3) continue;
    const sim::Vec3 n = (v[f[1]] - v[f[0]]).cross(v[f[2]] - v[f[0]]).normalized();
    const sim::Vec3 u = (v[f[1]] - v[f[0]]).normalized(), w = n.cross(u);
    const auto base = std::uint32_t(d.positions.size() / 3);
    for (std::uint32_t k : f) {
      const sim::Vec3& p = v[k];
      d.positions.insert(d.positions.end(), {float(p.x()), float(p.y()), float(p.z())});
      d.normals.insert(d.normals.end(), {float(n.x()), float(n.y()), float(n.z())});
      d.uvs.insert(d.uvs.end(), {float((p - v[f[0]]).dot(u)), float((p - v[f[0]]).dot(w))});
    }
    for (std::uint32_t k = 1; k + 1 < f.size(); ++k)
      d.indices.insert(d.indices.end(), {base, base + k, base + k + 1});
  }
}

/// The box of half extents e as six flat faces.
void add_box(const sim::Vec3& e, render::MeshDesc& d) {
  std::vector<sim::Vec3> v;
  for (int i = 0; i < 8; ++i)
    v.emplace_back((i & 1) ? e.x() : -e.x(), (i & 2) ? e.y() : -e.y(), (i & 4) ? e.z() : -e.z());
  // Counter-clockwise seen from outside.
  add_flat_faces(v, {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}}, d);
}

/// Appends `m` to `d`, its vertices mapped by the shape's offset.
void append_at(const render::MeshDesc& m, const sim::Transform& offset, render::MeshDesc& d) {
  const Eigen::Matrix3f R = offset.rotation.normalized().toRotationMatrix().cast<float>();
  const Eigen::Vector3f t = offset.translation.cast<float>();
  const auto base = std::uint32_t(d.positions.size() / 3);
  const std::size_t n = m.positions.size() / 3;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f p = R * Eigen::Vector3f(m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]) + t;
    d.positions.insert(d.positions.end(), {p.x(), p.y(), p.z()});
    Eigen::Vector3f nn(0.f, 0.f, 1.f);
    if (m.normals.size() == m.positions.size())
      nn = R * Eigen::Vector3f(m.normals[3 * i], m.normals[3 * i + 1], m.normals[3 * i + 2]);
    d.normals.insert(d.normals.end(), {nn.x(), nn.y(), nn.z()});
    if (m.uvs.size() == 2 * n) d.uvs.insert(d.uvs.end(), {m.uvs[2 * i], m.uvs[2 * i + 1]});
    else d.uvs.insert(d.uvs.end(), {0.f, 0.f});
  }
  for (std::uint32_t k : m.indices) d.indices.push_back(base + k);
}

/// A bodies[i] body as one mesh in its body frame: every shape's mesh at its offset (primitives
/// tessellated, hulls as their flat faces, mesh files as imported). When a shape has its own
/// colour or texture, every shape's triangles are a part with its own material.
render::MeshDesc body_desc(const ColliderScene& c) {
  render::MeshDesc d;
  std::vector<render::MeshDesc> meshes(c.body.shapes.size());
  for (std::size_t i = 0; i < c.body.shapes.size(); ++i) {
    const sim::ShapeDef& s = c.body.shapes[i];
    const BodyShapeDraw& draw = c.body_draw[i];
    if (draw.skip) continue;
    render::MeshDesc& m = meshes[i];
    if (draw.asset) {
      ColliderScene as_mesh;
      as_mesh.mesh_asset = draw.asset;
      as_mesh.mesh_scale = draw.scale;
      as_mesh.color = c.color;
      as_mesh.color_given = c.color_given || draw.color.has_value();
      m = mesh_desc(as_mesh);
    } else {
      switch (s.type) {
        case sim::ShapeType::sphere: m = render::make_sphere_mesh(float(s.radius), 48); break;
        case sim::ShapeType::cylinder: m = render::make_cylinder_mesh(float(s.radius), float(s.half_height), 48); break;
        case sim::ShapeType::capsule: m = render::make_capsule_mesh(float(s.radius), float(s.half_height), 32); break;
        case sim::ShapeType::box: add_box(s.half_extents, m); break;
        case sim::ShapeType::convex_hull: {
          const sim::HullMesh h = sim::hull_mesh(s.points);
          add_flat_faces(h.vertices, h.faces, m);
          break;
        }
        default: break;
      }
    }
  }
  // One material for the body, unless a shape has its own colour or texture or a mesh file
  // brings several materials: then every shape's triangles are parts.
  const bool own = std::any_of(c.body_draw.begin(), c.body_draw.end(),
                               [](const BodyShapeDraw& b) { return b.color || !b.texture.empty(); }) ||
                   std::any_of(meshes.begin(), meshes.end(), [](const render::MeshDesc& m) { return !m.parts.empty(); });
  for (std::size_t i = 0; i < c.body.shapes.size(); ++i) {
    const BodyShapeDraw& draw = c.body_draw[i];
    const render::MeshDesc& m = meshes[i];
    if (draw.skip) continue;
    if (draw.asset && c.texture.empty() && !m.material.texture_path.empty() && !own)
      d.material.texture_path = m.material.texture_path;
    const auto first = std::uint32_t(d.indices.size() / 3);
    append_at(m, c.body.shapes[i].offset, d);
    if (!own || d.indices.size() / 3 == first) continue;
    if (!m.parts.empty()) {  // the file's own materials
      for (render::MeshPart part : m.parts) {
        part.first_triangle += first;
        part.material.double_sided = false;
        d.parts.push_back(std::move(part));
      }
      continue;
    }
    render::MeshPart& part = d.parts.emplace_back();
    part.first_triangle = first;
    part.triangle_count = std::uint32_t(d.indices.size() / 3) - first;
    part.material = collider_material(c);
    if (draw.color) part.material.base_color = render::Vec4f((*draw.color)[0], (*draw.color)[1], (*draw.color)[2], (*draw.color)[3]);
    // The shape's texture, else the body's, else the one its mesh file names.
    part.material.texture_path = !draw.texture.empty() ? draw.texture
                                 : !c.texture.empty()  ? c.texture
                                                       : m.material.texture_path;
  }
  const std::string file_texture = d.material.texture_path;
  d.material = collider_material(c);
  d.material.texture_path = c.texture.empty() ? file_texture : c.texture;
  return d;
}

/// A cloth as a dynamic two-sided mesh in the world frame; its vertices are replaced every frame.
render::MeshDesc cloth_desc(const ClothScene& cloth, const sim::ClothView& v) {
  render::MeshDesc d;
  d.positions.assign(v.positions, v.positions + 3 * v.vertex_count);
  d.normals.assign(v.normals, v.normals + 3 * v.vertex_count);
  // UVs in metres, so checker_m is a cell size on the cloth.
  d.uvs.resize(2 * v.vertex_count);
  for (std::size_t k = 0; k < v.vertex_count; ++k) {
    d.uvs[2 * k] = v.uvs[2 * k] * float(cloth.def.width);
    d.uvs[2 * k + 1] = v.uvs[2 * k + 1] * float(cloth.def.height);
  }
  d.indices.assign(v.triangles, v.triangles + 3 * v.triangle_count);
  d.material.base_color = cloth.color;
  d.material.checker_m = cloth.checker_m;
  d.material.double_sided = true;
  d.material.specular = 0.08f;
  d.dynamic = true;
  return d;
}

}  // namespace

render::MeshDesc mesh_desc(const ColliderScene& c) {
  render::MeshDesc d;
  const assets::TriangleMesh& m = *c.mesh_asset;
  // A file with several materials in use (OBJ usemtl groups, glTF primitives) is drawn in them
  // unless the scene gives a colour: its triangles grouped by material (stable), one part each
  // with the file's base colour and texture.
  std::vector<std::uint32_t> used;
  bool valid = m.triangle_material.size() == m.triangles.size();
  for (std::size_t t = 0; valid && t < m.triangle_material.size(); ++t) {
    const std::uint32_t k = m.triangle_material[t];
    valid = k < m.materials.size();
    if (valid && std::find(used.begin(), used.end(), k) == used.end()) used.push_back(k);
  }
  const bool by_material = valid && !c.color_given && used.size() > 1;
  d.positions.reserve(3 * m.positions.size());
  d.normals.reserve(3 * m.normals.size());
  for (const auto& p : m.positions)
    for (int k = 0; k < 3; ++k) d.positions.push_back(p[k] * float(c.mesh_scale[std::size_t(k)]));
  // Non-uniform scale: normals transform by the inverse scale (then renormalise).
  for (const auto& n0 : m.normals) {
    Eigen::Vector3f n(n0.x() / float(c.mesh_scale[0]), n0.y() / float(c.mesh_scale[1]),
                      n0.z() / float(c.mesh_scale[2]));
    n.normalize();
    d.normals.insert(d.normals.end(), {n.x(), n.y(), n.z()});
  }
  for (const auto& uv : m.uvs) d.uvs.insert(d.uvs.end(), {uv.x(), uv.y()});
  const auto file_texture = [](const assets::MeshMaterial& mm) {
    // (embedded textures, "*0", ..., are not read)
    return !mm.texture.empty() && mm.texture.string()[0] != '*' ? mm.texture.string() : std::string();
  };
  d.material = collider_material(c);
  // The texture of the one material the faces use (assimp lists its own default material first,
  // so the first is often not it), else of the first.
  if (valid && used.size() == 1) d.material.texture_path = file_texture(m.materials[used[0]]);
  else if (!m.materials.empty()) d.material.texture_path = file_texture(m.materials[0]);
  // Open meshes (a ramp's underside, stairs seen from behind) show their inside faces too.
  d.material.double_sided = true;
  if (!by_material) {
    for (const auto& t : m.triangles) d.indices.insert(d.indices.end(), t.begin(), t.end());
    return d;
  }
  std::sort(used.begin(), used.end());
  for (const std::uint32_t k : used) {
    render::MeshPart& part = d.parts.emplace_back();
    part.first_triangle = std::uint32_t(d.indices.size() / 3);
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
      if (m.triangle_material[t] == k) d.indices.insert(d.indices.end(), m.triangles[t].begin(), m.triangles[t].end());
    part.triangle_count = std::uint32_t(d.indices.size() / 3) - part.first_triangle;
    part.material = d.material;
    const auto& bc = m.materials[k].base_color;
    part.material.base_color = render::Vec4f(bc[0], bc[1], bc[2], bc[3]);
    part.material.texture_path = file_texture(m.materials[k]);
  }
  return d;
}

render::SceneList initial_scene_list(const Scene& scene, const SceneWorld& sw) {
  render::SceneList list;
  list.added.reserve(scene.colliders.size() + sw.cloths.size());
  for (std::size_t i = 0; i < scene.colliders.size(); ++i) {
    const ColliderScene& c = scene.colliders[i];
    render::SceneList::Added& a = list.added.emplace_back();
    a.key = sw.colliders[i].id.packed();
    a.desc = collider_desc(c);
    if (c.type == ColliderScene::Type::plane) {
      a.has_transform = false;  // a plane's drawable is already in the world frame
      continue;
    }
    const sim::MovedObject pose = sw.world.pose(sw.colliders[i]);
    a.translation = pose.translation.cast<float>();
    a.rotation = pose.rotation.cast<float>();
  }
  for (std::size_t i = 0; i < sw.cloths.size(); ++i) {
    render::SceneList::Added& a = list.added.emplace_back();
    a.key = sw.cloths[i].id.packed();
    a.desc = cloth_desc(scene.cloths[i], sw.world.cloth(sw.cloths[i]));
    a.has_transform = false;  // vertices are given in the world frame
  }
  return list;
}

void append_moved(std::span<const sim::MovedObject> moved, render::SceneList& out) {
  for (const sim::MovedObject& m : moved) {
    if (m.removed) {
      // Force fields and attractor springs are reported too but have no drawable.
      const sim::ObjectKind k = m.handle.kind;
      if (k == sim::ObjectKind::body || k == sim::ObjectKind::particle_system ||
          k == sim::ObjectKind::cloth)
        out.removed.push_back(m.handle.packed());
      continue;
    }
    out.moved.push_back({m.handle.packed(), m.translation.cast<float>(), m.rotation.cast<float>()});
  }
}

void append_frame(const Scene& scene, const SceneWorld& sw, double t, render::SceneList& out) {
  for (std::size_t i = 0; i < sw.systems.size(); ++i) {
    const sim::ParticleView v = sw.world.particles(sw.systems[i]);
    render::SceneList::Particles& p = out.particles.emplace_back();
    p.key = sw.systems[i].id.packed();
    p.batch.count = v.count;
    p.batch.position = v.position;
    p.batch.velocity = v.velocity;
    p.batch.color = v.color;
    p.batch.radius = v.radius;
    p.batch.style = scene.emitters[i].style;
    p.batch.streak_s = scene.emitters[i].streak_s;
    p.batch.age = v.age;
    p.batch.lifetime = v.lifetime;
    p.batch.id = v.id;
    // The particle part of the camera's shutter (render.shutter_deg) lengthens the trail by the
    // exposure, shutter_deg / 360 / fps; see particle_shutter_s.
    p.batch.trail_s = scene.emitters[i].trail_s + particle_shutter_s(scene);
    p.batch.emissive = scene.emitters[i].emissive;
    p.batch.strobe_hz = scene.emitters[i].strobe_hz;
    p.batch.strobe_duty = scene.emitters[i].strobe_duty;
    p.batch.texture = scene.emitters[i].texture;
  }
  for (const sim::ClothHandle& h : sw.cloths) {
    const sim::ClothView v = sw.world.cloth(h);
    out.meshes.push_back({h.id.packed(), {v.positions, 3 * v.vertex_count}, {v.normals, 3 * v.vertex_count}});
  }
  out.camera = render::camera_at(scene.camera_motion, t);
}

}  // namespace simreel::app
