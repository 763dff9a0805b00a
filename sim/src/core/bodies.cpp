// Bodies (Box2D v3's body apart from shape): World::add_body, the single-collider wrappers that
// build a one-shape body, the body's pose, its removal with all its shapes, and the kinematic
// motion of a body's shapes (body pose ∘ shape offset; Coutinho §3.7 moving bodies).
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/path_math.hpp"
#include "rigid/mass_properties.hpp"
#include "core/validate.hpp"
#include "core/world_impl.hpp"

namespace simreel::sim {

namespace detail {

void Body::move_to(double t, std::vector<Collider>& shapes) {
  pose = path.sample(t);
  velocity = path.velocity(t);
  angular_velocity = detail::angular_velocity(path, t);
  for (std::uint32_t k = first_shape; k < first_shape + shape_count; ++k)
    shapes[k].follow(pose, velocity, angular_velocity);
}

MovedObject Body::report_pose(const std::vector<Collider>& shapes) const {
  if (shape_count == 1 && shapes[first_shape].offset_identity) return shapes[first_shape].pose();
  MovedObject m;
  m.translation = pose.translation;
  m.rotation = pose.rotation.normalized().toRotationMatrix();
  return m;
}

namespace {

/// How messages name the fields: "BodyDef.pose", "BodyDef.shapes[i]", or the single-collider
/// definition the body was built from ("SphereDef.transform", "SphereDef").
struct Names {
  std::string pose, path, shape;
  bool indexed = true;  ///< shape names get "[i]"
};

void require_zero(const Vec3& v, BodyType type, const char* field) {
  if (v == Vec3::Zero()) return;
  std::ostringstream m;
  m << "BodyDef." << field << " must be zero for a "
    << (type == BodyType::static_body ? "static body" : "kinematic body (its velocity comes from its path)")
    << " (got (" << v.transpose() << "))";
  throw std::invalid_argument(m.str());
}

void validate_body(const BodyDef& def, const Names& names) {
  if (def.type != BodyType::static_body && def.type != BodyType::kinematic &&
      def.type != BodyType::dynamic)
    throw std::invalid_argument("BodyDef.type is not a body type");
  if (def.shapes.empty()) throw std::invalid_argument("BodyDef.shapes must hold at least one shape");
  const Transform& t = def.pose;
  if (!t.translation.allFinite() || !t.rotation.coeffs().allFinite() ||
      !(t.rotation.norm() > 1e-12))
    throw std::invalid_argument(names.pose +
                                " must be finite with a non-zero rotation quaternion");
  validate(def.path, names.path);
  if (def.type == BodyType::kinematic && def.path.empty())
    throw std::invalid_argument(names.path + " must not be empty for a kinematic body");
  if (def.type == BodyType::static_body && !def.path.empty())
    throw std::invalid_argument(names.path + " must be empty for a static body (make it kinematic)");
  if (def.type == BodyType::dynamic) {
    if (!def.path.empty())
      throw std::invalid_argument(names.path + " must be empty for a dynamic body (make it kinematic)");
    if (!def.linear_velocity.allFinite() || !def.angular_velocity.allFinite() ||
        !def.gravity.allFinite())
      throw std::invalid_argument("BodyDef.linear_velocity, angular_velocity and gravity must be finite");
    if (!(def.mass == 0.0 || ranges::kBodyMass.contains(def.mass))) {
      std::ostringstream m;
      m << "BodyDef.mass must be >= 0 and finite (0: from the densities) (got " << def.mass << ")";
      throw std::invalid_argument(m.str());
    }
  } else {
    require_zero(def.linear_velocity, def.type, "linear_velocity");
    require_zero(def.angular_velocity, def.type, "angular_velocity");
  }
  require_in(def.linear_damping, ranges::kBodyDamping, "BodyDef.linear_damping");
  require_in(def.angular_damping, ranges::kBodyDamping, "BodyDef.angular_damping");
  require_in(def.drag_coefficient, ranges::kBodyDragCoefficient, "BodyDef.drag_coefficient");
  require_in(def.drag_area, ranges::kBodyDragArea, "BodyDef.drag_area");
}

/// (m²) Mean projected area of a dynamic body's shapes: a quarter of the surface area (Cauchy's
/// formula, exact for a convex shape averaged over all directions), summed over the shapes.
double mean_projected_area(const BodyDef& def, const std::vector<Collider>& made) {
  constexpr double pi = 3.14159265358979323846;
  double surface = 0.0;
  for (std::size_t i = 0; i < def.shapes.size(); ++i) {
    const ShapeDef& s = def.shapes[i];
    if (made[i].hull) surface += made[i].hull->area;
    const double r = s.radius, hh = s.half_height;
    const Vec3& e = s.half_extents;
    switch (s.type) {
      case ShapeType::sphere: surface += 4.0 * pi * r * r; break;
      case ShapeType::box: surface += 8.0 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x()); break;
      case ShapeType::cylinder: surface += 2.0 * pi * r * r + 4.0 * pi * r * hh; break;
      case ShapeType::capsule: surface += 4.0 * pi * r * r + 4.0 * pi * r * hh; break;
      default: break;
    }
  }
  return 0.25 * surface;
}

/// Mass properties of a dynamic body in its body frame from its shapes (Coutinho §4.1, App. D):
/// each shape's closed form at its density, moved to its offset, combined by the parallel-axis
/// theorem; BodyDef::mass > 0 then rescales the total.
MassProperties body_mass(const BodyDef& def, const std::vector<Collider>& made,
                         const std::string& shape_name, bool indexed) {
  std::vector<MassPart> parts;
  for (std::size_t i = 0; i < def.shapes.size(); ++i) {
    const ShapeDef& s = def.shapes[i];
    const std::string what = indexed ? shape_name + "[" + std::to_string(i) + "]" : shape_name;
    if (!ranges::kBodyDensity.contains(s.density)) {
      std::ostringstream m;
      m << what << ".density must be > 0 and finite (kg/m³) (got " << s.density << ")";
      throw std::invalid_argument(m.str());
    }
    MassPart p;
    switch (s.type) {
      case ShapeType::sphere: p.props = sphere_mass(s.radius, s.density); break;
      case ShapeType::box: p.props = box_mass(s.half_extents, s.density); break;
      case ShapeType::cylinder: p.props = cylinder_mass(s.radius, s.half_height, s.density); break;
      case ShapeType::capsule: p.props = capsule_mass(s.radius, s.half_height, s.density); break;
      case ShapeType::convex_hull:  // from its boundary (App. D): the hull's closed triangles
        p.props = mesh_mass(made[i].hull->vertices, made[i].hull->triangles, s.density);
        break;
      default: throw std::invalid_argument(what + ": not a shape a dynamic body may have");
    }
    p.translation = s.offset.translation;
    p.rotation = s.offset.rotation.normalized().toRotationMatrix();
    parts.push_back(p);
  }
  MassProperties total = combine(parts);
  if (def.mass > 0.0) total = with_mass(total, def.mass);
  return total;
}

BodyHandle add(WorldState& w, const BodyDef& def, const Names& names) {
  validate_body(def, names);
  // Every shape is made (and checked) before the world changes: a throw leaves it as it was.
  std::vector<Collider> made;
  made.reserve(def.shapes.size());
  for (std::size_t i = 0; i < def.shapes.size(); ++i) {
    const std::string what = names.indexed ? names.shape + "[" + std::to_string(i) + "]" : names.shape;
    made.push_back(make_collider(def.shapes[i], what));
    if (made.back().shape == Collider::Shape::plane && def.type != BodyType::static_body)
      throw std::invalid_argument(what + ": a plane may only belong to a static body");
    if (made.back().shape == Collider::Shape::mesh && !made.back().hull &&
        def.type == BodyType::dynamic)
      throw std::invalid_argument(what + ": a mesh may not belong to a dynamic body yet (use "
                                         "sphere, box, capsule, cylinder or convex_hull shapes)");
  }
  MassProperties mass;
  if (def.type == BodyType::dynamic) mass = body_mass(def, made, names.shape, names.indexed);
  Body b;
  b.type = def.type;
  b.name = def.name;
  b.path = def.path;
  b.pose = def.pose;
  b.linear_damping = def.linear_damping;
  b.angular_damping = def.angular_damping;
  b.first_shape = std::uint32_t(w.shapes.size());
  b.shape_count = std::uint32_t(made.size());
  for (Collider& c : made) {
    c.moving = b.kinematic() || b.dynamic();  // particles see a dynamic body as a moving one
    w.shapes.push_back(std::move(c));
  }
  if (b.kinematic()) {
    b.move_to(w.time, w.shapes);
    b.rigid = std::uint32_t(add_body(w.dyn.rigid, RigidBodyDef{.position = b.pose.translation}));
  } else if (b.dynamic()) {
    b.local_com = mass.center_of_mass;
    b.gravity = def.gravity;
    b.drag_coefficient = def.drag_coefficient;
    b.drag_area = def.drag_area > 0.0 ? def.drag_area : mean_projected_area(def, made);
    const Quat q = def.pose.rotation.normalized();
    RigidBodyDef r;
    r.position = def.pose.translation + q * mass.center_of_mass;
    r.orientation = q;
    r.linear_velocity = def.linear_velocity + def.angular_velocity.cross(q * mass.center_of_mass);
    r.angular_velocity = def.angular_velocity;
    r.mass = mass.mass;
    r.inertia = mass.inertia;
    r.linear_drag = def.linear_damping * mass.mass;
    r.angular_drag = def.angular_damping * mass.inertia.trace() / 3.0;
    b.rigid = std::uint32_t(add_body(w.dyn.rigid, r));
    ++w.dyn.dynamic_count;
    // What World::velocity() reports before the first step (the stage sets it after each):
    // zero here made a state export's first row read 0 for a body launched at 1 m/s.
    b.velocity = def.linear_velocity;
    b.angular_velocity = def.angular_velocity;
    for (std::uint32_t k = b.first_shape; k < b.first_shape + b.shape_count; ++k)
      w.shapes[k].follow(b.pose, def.linear_velocity, def.angular_velocity);
  } else {
    for (std::uint32_t k = b.first_shape; k < b.first_shape + b.shape_count; ++k)
      w.shapes[k].follow(b.pose, Vec3::Zero(), Vec3::Zero());
  }
  for (std::uint32_t k = b.first_shape; k < b.first_shape + b.shape_count; ++k) {
    w.shapes[k].prev_center = w.shapes[k].center;
    w.shapes[k].prev_R = w.shapes[k].R;
    w.shapes[k].note_pose();
  }
  b.reported_translation = b.pose.translation;
  b.reported_rotation = b.pose.rotation.normalized();
  for (std::uint32_t k = b.first_shape; k < b.first_shape + b.shape_count; ++k)
    wake_particles_near(w, w.shapes[k]);  // it may overlap sleeping particles
  return BodyHandle{w.bodies.add(std::move(b))};
}

/// A one-shape body from a single-collider definition: static when its path is empty.
BodyDef one_shape(ShapeDef shape, const Transform& transform, const KeyframePath& path,
                  const Material& material) {
  BodyDef b;
  b.type = path.empty() ? BodyType::static_body : BodyType::kinematic;
  b.pose = transform;
  b.path = path;
  shape.material = material;
  b.shapes.push_back(std::move(shape));
  return b;
}

Names names_of(const std::string& def) {
  return Names{def + ".transform", def + ".path", def, false};
}

}  // namespace

void remove_rigid(WorldState& w, std::uint32_t i) {
  const std::uint32_t last = std::uint32_t(w.dyn.rigid.size() - 1);
  swap_remove(w.dyn.rigid, i);
  BodyDynamics& d = w.dyn;
  if (d.rest_time.size() == last + 1) {
    d.rest_time[i] = d.rest_time[last];
    d.rest_time.pop_back();
    d.island[i] = d.island[last];
    d.island.pop_back();
  }
  if (i == last) return;
  for (Body& b : w.bodies.dense())
    if (b.rigid == last) b.rigid = i;
}

void remove_body(WorldState& w, const Handle& h) {
  // Whatever rested on the body must be free to fall (and island ids name rigid indices, which
  // the swap-remove below changes).
  wake_all(w);
  const Body& gone = w.bodies[h];
  for (std::uint32_t k = gone.first_shape; k < gone.first_shape + gone.shape_count; ++k)
    wake_particles_near(w, w.shapes[k]);
  remove_joints_of(w, h);  // its joints go with it (their handles go stale)
  if (gone.dynamic()) --w.dyn.dynamic_count;
  if (gone.rigid != kNoRigid) remove_rigid(w, gone.rigid);
  w.bodies.remove(h);
  // The shapes follow the bodies' dense order again; the warm-start data that names shapes by
  // index follows them (for one-shape bodies this is the swap-remove of the shape array).
  std::vector<std::uint32_t> new_index(w.shapes.size(), ParticleCollider::kRemoved);
  std::vector<Collider> shapes;
  shapes.reserve(w.shapes.size());
  for (Body& b : w.bodies.dense()) {
    const std::uint32_t first = std::uint32_t(shapes.size());
    for (std::uint32_t k = b.first_shape; k < b.first_shape + b.shape_count; ++k) {
      new_index[k] = std::uint32_t(shapes.size());
      shapes.push_back(std::move(w.shapes[k]));
    }
    b.first_shape = first;
  }
  w.shapes = std::move(shapes);
  w.particle_collider.remap_colliders(new_index);
}

}  // namespace detail

BodyHandle World::add_body(const BodyDef& def) {
  return detail::add(*impl_, def, detail::Names{"BodyDef.pose", "BodyDef.path", "BodyDef.shapes"});
}

ColliderHandle World::add_plane(const PlaneDef& def) {
  BodyDef b;
  b.pose.translation = def.point;
  b.shapes.push_back(ShapeDef::plane(def.normal));
  b.shapes.back().material = def.material;
  return detail::add(*impl_, b, detail::Names{"PlaneDef.point", "PlaneDef.path", "PlaneDef", false});
}
ColliderHandle World::add_box(const BoxDef& def) {
  return detail::add(*impl_, detail::one_shape(ShapeDef::box(def.half_extents), def.transform,
                                               def.path, def.material),
                     detail::names_of("BoxDef"));
}
ColliderHandle World::add_sphere(const SphereDef& def) {
  return detail::add(*impl_, detail::one_shape(ShapeDef::sphere(def.radius), def.transform,
                                               def.path, def.material),
                     detail::names_of("SphereDef"));
}
ColliderHandle World::add_cylinder(const CylinderDef& def) {
  return detail::add(*impl_,
                     detail::one_shape(ShapeDef::cylinder(def.radius, def.half_height),
                                       def.transform, def.path, def.material),
                     detail::names_of("CylinderDef"));
}
ColliderHandle World::add_mesh(const MeshDef& def) {
  ShapeDef mesh;
  mesh.type = ShapeType::mesh;
  mesh.vertices = def.vertices;
  mesh.triangles = def.triangles;
  return detail::add(*impl_, detail::one_shape(std::move(mesh), def.transform, def.path, def.material),
                     detail::names_of("MeshDef"));
}

MovedObject World::pose(BodyHandle h) const {
  MovedObject m = impl_->bodies[h.id].report_pose(impl_->shapes);
  m.handle = h.id;
  return m;
}

bool World::is_awake(BodyHandle h) const {
  const detail::Body& b = impl_->bodies[h.id];
  return !b.dynamic() || !impl_->dyn.rigid.asleep[b.rigid];
}

void World::wake(BodyHandle h) {
  const detail::Body& b = impl_->bodies[h.id];
  if (b.dynamic()) detail::wake_island(*impl_, b.rigid);
}

std::pair<Vec3, Vec3> World::velocity(BodyHandle h) const {
  const detail::Body& b = impl_->bodies[h.id];
  return {b.velocity, b.angular_velocity};
}

BodyMotion World::motion(BodyHandle h) const {
  const detail::Body& b = impl_->bodies[h.id];
  if (!b.dynamic()) throw std::invalid_argument("World::motion: body '" + b.name + "' is not dynamic");
  const detail::RigidBodies& r = impl_->dyn.rigid;
  BodyMotion m;
  m.mass = r.mass[b.rigid];
  m.center_of_mass = r.position[b.rigid];
  m.linear_velocity = r.linear_velocity[b.rigid];
  m.angular_velocity = r.angular_velocity[b.rigid];
  m.linear_momentum = m.mass * m.linear_velocity;
  m.angular_momentum = r.angular_momentum[b.rigid];
  return m;
}

std::vector<BodyHandle> World::colliders() const {
  std::vector<BodyHandle> out;
  for (std::size_t i = 0; i < impl_->bodies.size(); ++i)
    out.push_back(BodyHandle{impl_->bodies.handle(i)});
  return out;
}

}  // namespace simreel::sim
