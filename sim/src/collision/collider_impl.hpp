#pragma once
// Colliders at run time and the particle collision pass (private).
// Coutinho §2.1–2.2 (local-frame queries, AABB tree), §3.4 (swept spheres, collider fixed at its
// end-of-step pose), §3.4.2 (particles inside a body are removed), §3.6.1 (impulse with
// restitution and Coulomb friction, critical friction), §3.6.3 (resting contact).

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "collision/bvh.hpp"
#include "collision/mesh_grid.hpp"
#include "collision/narrow_phase.hpp"
#include "collision/polytope_faces.hpp"
#include "particles/particle_store.hpp"
#include "simreel/sim/body.hpp"
#include "simreel/sim/random.hpp"
#include "simreel/sim/moved_object.hpp"

namespace simreel::sim::detail {

/// A mesh collider's geometry in its local frame, shared and immutable after registration.
struct MeshShape {
  std::vector<Triangle> triangles;
  Bvh bvh;
  MeshGrid grid;  ///< the small queries of swept particles (sweep.cpp)
  bool closed = false;  ///< every edge shared by exactly two triangles
  /// Convex edges sharper than ~20 degrees and open edges (indices into sharp_vertices), and
  /// their end points, local frame: the features cloth triangles and edges collide with.
  std::vector<std::array<std::uint32_t, 2>> sharp_edges;
  std::vector<Vec3> sharp_vertices;
  std::vector<Vec3> sharp_edge_out, sharp_vertex_out;  ///< outward (sum of face normals; 0 if open)
  Vec3 local_center = Vec3::Zero();  ///< of the local AABB
  Vec3 local_half = Vec3::Zero();
  /// Parity of crossings of a fixed, slightly oblique ray from p (local frame): inside a closed mesh.
  [[nodiscard]] bool contains(const Vec3& p) const;
  /// Is p (local frame) within `tol` (m) of some triangle? (§3.4.2: a point on the surface, within
  /// float rounding, is not inside.)
  [[nodiscard]] bool near_surface(const Vec3& p, double tol) const;
};

/// A convex hull shape's geometry in its local frame (ShapeType::convex_hull), built once at
/// registration by quickhull (rigid/convex_hull.hpp) and shared, immutable: the hull's vertices
/// (GJK/EPA support, plane contacts), its merged planar faces (manifold clipping) and its
/// outward-wound triangles (mass properties, App. D; the particle and cloth mesh).
struct HullShape {
  std::vector<Vec3> vertices;                            ///< (m) local frame
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< CCW from outside, into vertices
  HullFaces faces;
  double area = 0.0;  ///< (m²) surface area
};

/// One shape of a body at run time, posed in the world: geometry in the shape frame, material,
/// and the pose and velocities of the shape frame at the end of the current step. The world
/// keeps every body's shapes in one dense array (the collision passes loop over it).
struct Collider {
  enum class Shape : std::uint8_t { plane, box, sphere, cylinder, capsule, mesh };
  Shape shape = Shape::plane;
  Material material;

  // plane
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();  ///< unit
  Vec3 local_normal = Vec3::UnitZ();  ///< unit, shape frame

  // solids: definition
  Vec3 half_extents = Vec3::Zero();  ///< box
  double radius = 0.0;               ///< sphere, cylinder, capsule
  double half_height = 0.0;          ///< cylinder, capsule (half the segment)
  std::shared_ptr<const MeshShape> mesh;
  /// Convex hulls: their hull data; the collider is then a closed `Shape::mesh` of the hull's
  /// triangles for particles and cloth, and a convex polytope for bodies (body_contacts.cpp).
  std::shared_ptr<const HullShape> hull;
  /// Pose of the shape frame in its body's frame; identity (the body's only shape, as the
  /// single-collider wrappers build it) takes the body pose unchanged, bit for bit.
  Transform offset;
  bool offset_identity = true;
  bool moving = false;  ///< belongs to a kinematic body
  // solids: pose at the end of the current step (Coutinho §3.4: the body is taken as fixed there)
  Vec3 center = Vec3::Zero();  ///< origin of the local frame, world
  Quat rotation = Quat::Identity();
  Mat3 R = Mat3::Identity();     ///< local -> world
  Vec3 velocity = Vec3::Zero();  ///< (m/s) of the centre, from the path
  Vec3 angular_velocity = Vec3::Zero();  ///< (rad/s), world frame
  /// Pose at the start of the current step (kinematic solids; equal to the pose when static):
  /// the first sweep of a step runs in the body's frame from the particle's start point in the
  /// start pose to its end point in the end pose, i.e. along the relative motion (§2.1, §3.7).
  Vec3 prev_center = Vec3::Zero();
  Mat3 prev_R = Mat3::Identity();
  /// The shape frame is the world frame now and at the start of the step (centre zero, R the
  /// identity; a static terrain as most scenes place it): the sweeps skip the transforms, which
  /// would change nothing but the sign of a zero. Kept by note_pose().
  bool unposed = true;
  Vec3 aabb_center = Vec3::Zero();  ///< world AABB of the solid (unexpanded)
  Vec3 aabb_half = Vec3::Zero();

  [[nodiscard]] bool kinematic() const { return moving; }
  /// Sets the shape frame's world pose (a plane: its point and normal; its centre stays zero).
  void set_pose(const Transform& t);
  /// Places the shape on its body: the body frame's world pose and velocities (m/s of the body
  /// origin, rad/s, world). The previous pose becomes the start-of-step pose.
  void follow(const Transform& body_pose, const Vec3& v, const Vec3& w);
  /// Updates `unposed` after the pose or the start-of-step pose changed.
  void note_pose() {
    unposed = center == Vec3::Zero() && prev_center == Vec3::Zero() && R == Mat3::Identity() &&
              prev_R == Mat3::Identity();
  }
  /// Velocity (m/s) of the collider's material point at world position p.
  [[nodiscard]] Vec3 point_velocity(const Vec3& p) const {
    return shape == Shape::plane ? Vec3::Zero() : Vec3(velocity + angular_velocity.cross(p - center));
  }
  [[nodiscard]] MovedObject pose() const;
};

/// The shape's geometry and material (not yet posed: see Collider::follow), with a mesh's AABB
/// tree built once in its frame (§2.2). @throws std::invalid_argument naming `what` + the field
/// (e.g. "BodyDef.shapes[1].radius") on bad parameters.
Collider make_collider(const ShapeDef& def, const std::string& what);

struct BodyImpulses;  // collision/body_impulses.hpp
class CollideMemo;   // collision/collide_memo.hpp

/// A droplet requested by HitAction::split, appended to the system after the pass.
struct SpawnRequest {
  Vec3 position, velocity;
  double radius, mass, lifetime;
};

/// Per-system inputs and outputs of a collision pass.
struct CollisionContext {
  double contact_speed = 0.05;
  Rng* rng = nullptr;                      ///< splash directions
  std::vector<SpawnRequest>* spawns = nullptr;
  std::uint64_t removed_inside = 0;        ///< §3.4.2 removals this pass
  /// The system's own hit action (ParticleSystemDef::on_hit), replacing the collider's.
  const HitAction* on_hit = nullptr;
  const SplitOnHit* on_hit_split = nullptr;
  /// When set (a dynamic body exists): every velocity change of a particle against a dynamic
  /// body's shape logs the equal and opposite impulse m (v_before - v_after) here (Coutinho §3.7).
  BodyImpulses* impulses = nullptr;
  /// OpenMP threads for a large pass whose particles share nothing (WorldDef::threads; the
  /// results do not depend on it).
  int threads = 1;
  /// The system's particles may sleep (ParticleStore::rest): the pass leaves sleeping ones alone.
  bool sleep = false;
  /// Set by collide(): no box, plane or solid with an inside (sphere, cylinder, capsule, closed
  /// mesh) among the colliders, so a particle whose first sweep hits nothing keeps its state
  /// exactly and its slow path can end there.
  bool bare_misses = false;
  /// When set: the system's memo of responses (collide_memo.hpp), used where particles share
  /// nothing and the start of the step is not stored (then a response is a function of the
  /// particle's end state alone).
  CollideMemo* memo = nullptr;
};

/// Collides particles [begin, end) of one system with every collider, after integration. Each
/// particle's motion over the step is the segment from its start-of-step position to its
/// position, travelled in min(age, h) seconds (a newborn moves only for its age).
void collide(ParticleStore& s, std::size_t begin, std::size_t end, double h,
             const std::vector<Collider>& colliders, CollisionContext& ctx, const ForceParams& f);

/// Moves particle i from `from` to its stored position as a swept sphere against the colliders
/// and stops it at the first contact (its velocity is kept): displacements made outside the
/// integrator (particle–particle overlap correction) cannot carry it through a surface.
void constrain_displacement(ParticleStore& s, std::size_t i, const Vec3& from,
                            const std::vector<Collider>& colliders);

/// First contact of a sphere of radius r moving a -> b (world) with one collider (Coutinho §3.4):
/// the same closed forms and AABB-tree query the particle pass uses. `first`: the segment starts
/// in the body's start-of-step pose (relative motion of a kinematic body, §2.1). On a contact
/// earlier than hit.s, sets hit.s (fraction of the segment), hit.normal (unit, surface to the
/// sphere) and hit.point (the centre there, exactly r from the surface) and returns true. A start
/// point inside the solid itself is no contact (the caller decides: removal or push-out).
bool sweep_collider(const Collider& c, const Vec3& a, const Vec3& b, double r, bool first,
                    SweepHit& hit);

/// A sphere's contact with a collider's surface at the end of a step: the closest feature
/// (face, edge or vertex), for the resting-contact constraints of the particle solve (§3.6.3).
struct SurfaceContact {
  Vec3 normal = Vec3::Zero();  ///< unit, world frame, from the surface towards the centre
  double gap = 0.0;            ///< (m) surface to sphere distance; negative: overlap
};

/// Closest features of collider c to the sphere (centre p, radius r, world frame) with
/// gap < margin, nearest first, at most max_out with normals apart by more than ~2.5 degrees (a
/// particle in a mesh crease touches one facet per side; the facets sharing an edge or vertex
/// give one contact). A centre inside a sphere, cylinder, capsule or closed mesh gives none (§3.4.2
/// removes it); one inside a box gives the face it is least deep behind. Returns the count.
int surface_contacts(const Collider& c, const Vec3& p, double r, double margin,
                     SurfaceContact* out, int max_out);

/// Is a contact with relative normal velocity vn (m/s, < 0 approaching) resting (§3.6.3): slower
/// than contact_speed plus the inward part of one step's kick (kick_n, m/s, the normal component
/// of the velocity the forces add over a step)?
bool is_resting(double vn, double kick_n, double contact_speed);

/// Impulse response of a particle against an immovable collider, see particle_response.cpp.
/// `force_resting`: treat the contact as resting whatever its speed. Exposed for the tests of the
/// critical-friction case.
Vec3 respond(const Vec3& v, const Vec3& vc, const Vec3& n, const Material& m, double contact_speed,
             const Vec3& kick, bool force_resting = false);

}  // namespace simreel::sim::detail
