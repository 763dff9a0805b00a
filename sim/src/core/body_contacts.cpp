// Broad and narrow phase of the bodies stage (body_dynamics.hpp; Coutinho §4.4–4.7).
//
// Broad phase: every solid shape's world AABB (Collider::aabb_*, fattened by kPad), sort and
// sweep along x; a pair is kept when at least one side is dynamic and the shapes belong to
// different bodies. Planes (static, unbounded) are tested against every dynamic shape directly.
// Narrow phase, per pair, A before B:
//   plane–convex: collide_plane (plane_manifold.hpp);
//   convex–convex: collide_manifold (box–box SAT, face clipping, GJK/EPA; contact_manifold.hpp);
//   (a convex hull is convex here: its vertices and planar faces, Collider::hull)
//   mesh–convex: the mesh's AABB tree queried with the convex's box in the mesh frame; a
//     triangle whose plane keeps the convex beyond the margin is skipped (TrianglePlaneCull),
//     every other one found is a 3-point hull for collide() (GJK/EPA); when its normal is the
//     triangle's, the convex's features over that triangle give up to 4 points (a face
//     contact), otherwise collide()'s one point (edge and vertex contacts).
// Each manifold takes last step's impulses by key (shape pair, triangle) through warm_start().
// Order: planes first (plane shape, then dynamic shape, by index), then pairs sorted by shape
// index; the manifolds are finally sorted by key for the next step's lookup (binary search).
#include <algorithm>
#include <array>
#include <cmath>

#include "collision/contact_manifold.hpp"
#include "collision/persistent_manifold.hpp"
#include "collision/plane_manifold.hpp"
#include "core/world_state.hpp"

namespace simreel::sim::detail {
namespace {

/// (m) AABB fattening: pairs a little apart still reach the narrow phase, which decides.
constexpr double kPad = 0.005;

}  // namespace

TrianglePlaneCull::TrianglePlaneCull(const Collider& mesh, const Collider& shape)
    : shape_(convex_of(shape)),
      to_shape_(shape.R.transpose() * mesh.R),
      origin_(mesh.R.transpose() * (shape.center - mesh.center)),
      slack_(1e-9 * (1.0 + origin_.cwiseAbs().maxCoeff())) {}

bool TrianglePlaneCull::apart(const Triangle& tri, double gap) const {
  const double above = tri.normal.dot(origin_ - tri.a);  // (m) shape origin over the plane
  // The shape's reach from its origin along the normal and against it: its support values.
  const Vec3 d = to_shape_ * tri.normal;
  const double up = shape_.support(d).dot(d), down = -shape_.support(-d).dot(d);
  return above - down > gap + slack_ || -above - up > gap + slack_;
}

ConvexShape convex_of(const Collider& c) {
  switch (c.shape) {
    case Collider::Shape::sphere: return ConvexShape::sphere(c.radius);
    case Collider::Shape::box: return ConvexShape::box(c.half_extents);
    case Collider::Shape::capsule: return ConvexShape::capsule(c.half_height, c.radius);
    case Collider::Shape::cylinder: return ConvexShape::cylinder(c.radius, c.half_height);
    case Collider::Shape::mesh:  // a convex hull (a plain mesh never reaches here)
      if (c.hull) return ConvexShape::hull(c.hull->vertices);
      return {};
    default: return {};
  }
}

namespace {

/// (m) The radius of a sphere or capsule (its surface turns about its centre or segment), else 0.
double round_radius(const Collider& c) {
  return c.shape == Collider::Shape::sphere || c.shape == Collider::Shape::capsule ? c.radius : 0.0;
}

/// A cylinder's axis (unit, world) and the offset of world point p from it, perpendicular to
/// it (ContactPoint::axis_a); both zero for other shapes.
void spin_axis(const Collider& c, const Vec3& p, Vec3& axis, Vec3& radial) {
  if (c.shape != Collider::Shape::cylinder) return;
  axis = c.R.col(2);
  const Vec3 rel = p - c.center;
  radial = rel - rel.dot(axis) * axis;
}

PosedShape posed(const Collider& c) { return {convex_of(c), c.R, c.center}; }

/// Where each shape belongs: its body's dense index and its index within the body.
struct Owner {
  std::uint32_t body, local;
};

class Builder {
 public:
  explicit Builder(WorldState& w) : w_(w), d_(w.dyn), bodies_(w.bodies.dense()) {
    owner_.resize(w.shapes.size());
    for (std::uint32_t i = 0; i < bodies_.size(); ++i)
      for (std::uint32_t k = 0; k < bodies_[i].shape_count; ++k)
        owner_[bodies_[i].first_shape + k] = {i, k};
  }

  void run() {
    d_.manifolds.clear();
    d_.points.clear();
    planes();
    broad_phase();
    for (const auto& [i, j] : d_.pairs) pair(i, j);
    carry_sleeping();
    std::sort(d_.manifolds.begin(), d_.manifolds.end(),
              [](const BodyManifold& a, const BodyManifold& b) { return a.key < b.key; });
  }

 private:
  [[nodiscard]] const Body& body_of(std::uint32_t shape) const { return bodies_[owner_[shape].body]; }
  [[nodiscard]] bool dynamic(std::uint32_t shape) const { return body_of(shape).dynamic(); }
  /// Can start a contact: an awake dynamic body, or a kinematic body with a velocity.
  [[nodiscard]] bool active(std::uint32_t shape) const {
    const Body& b = body_of(shape);
    if (b.dynamic()) return !d_.rigid.asleep[b.rigid];
    return b.kinematic() && (!b.velocity.isZero(0.0) || !b.angular_velocity.isZero(0.0));
  }
  /// A pair with a fast body (begin_continuous) takes the speculative margin.
  [[nodiscard]] double margin(std::uint32_t a, std::uint32_t b) const {
    const auto fast = [&](std::uint32_t s) {
      const Body& o = body_of(s);
      return o.dynamic() && o.rigid < d_.fast.size() && d_.fast[o.rigid] != 0;
    };
    return fast(a) || fast(b) ? kSpeculativeMargin : kBodyContactMargin;
  }
  /// Last step's manifold of pair key k, or nullptr (one binary search: the margin and the warm
  /// start both read it).
  [[nodiscard]] const BodyManifold* previous(const PairKey& k) const {
    const auto it = std::lower_bound(d_.previous.begin(), d_.previous.end(), k,
                                     [](const BodyManifold& x, const PairKey& y) { return x.key < y; });
    return it != d_.previous.end() && it->key == k ? &*it : nullptr;
  }
  /// The margin of shapes a, b whose last manifold is `last`: a pair that carried load in the
  /// previous step keeps its points up to kKeptContactMargin (body_dynamics.hpp).
  [[nodiscard]] double margin(std::uint32_t a, std::uint32_t b, const BodyManifold* last) const {
    const double m = margin(a, b);
    return m < kKeptContactMargin && carried_load(last) ? kKeptContactMargin : m;
  }
  [[nodiscard]] static bool carried_load(const BodyManifold* last) {
    if (last == nullptr) return false;
    // Only a pair that carried load: pairs that merely came within the margin (Newton's
    // cradle's hanging balls after a collision passed) would otherwise keep speculative points
    // for as long as they stay that close, and the next impact would be solved through the
    // whole chain at once instead of ball by ball.
    for (int i = 0; i < last->manifold.count; ++i)
      if (last->manifold.points[i].normal_impulse > 0.0) return true;
    return false;
  }
  [[nodiscard]] bool frozen(std::uint32_t rigid) const {
    return rigid == kStaticBody || d_.rigid.asleep[rigid] ||
           (!d_.rigid.is_dynamic(rigid) && d_.rigid.linear_velocity[rigid].isZero(0.0) &&
            d_.rigid.angular_velocity[rigid].isZero(0.0));
  }

  /// Last step's manifolds between two bodies that cannot move now (a sleeping island's
  /// contacts): not recomputed, kept for the warm start when the island wakes.
  void carry_sleeping() {
    for (const BodyManifold& m : d_.previous) {
      if (m.rigid_a != kStaticBody && m.rigid_a >= d_.rigid.size()) continue;
      if (m.rigid_b != kStaticBody && m.rigid_b >= d_.rigid.size()) continue;
      const bool sleeping = (m.rigid_a != kStaticBody && d_.rigid.asleep[m.rigid_a]) ||
                            (m.rigid_b != kStaticBody && d_.rigid.asleep[m.rigid_b]);
      if (!sleeping || !frozen(m.rigid_a) || !frozen(m.rigid_b)) continue;
      BodyManifold c = m;
      c.first_point = kCarriedManifold;
      d_.manifolds.push_back(c);
    }
  }
  [[nodiscard]] std::uint32_t rigid(std::uint32_t shape) const {
    const Body& b = body_of(shape);
    return b.rigid == kNoRigid ? kStaticBody : b.rigid;
  }
  [[nodiscard]] PairKey key(std::uint32_t a, std::uint32_t b, std::uint32_t sub) const {
    return {w_.bodies.handle(owner_[a].body).packed(), owner_[a].local,
            w_.bodies.handle(owner_[b].body).packed(), owner_[b].local, sub};
  }

  void planes() {
    for (std::uint32_t p = 0; p < w_.shapes.size(); ++p) {
      const Collider& plane = w_.shapes[p];
      if (plane.shape != Collider::Shape::plane) continue;
      for (std::uint32_t s = 0; s < w_.shapes.size(); ++s) {
        if (!dynamic(s) || !active(s) || no_collide(d_, owner_[p].body, owner_[s].body)) continue;
        const PairKey k = key(p, s, 0);
        const BodyManifold* last = previous(k);
        add(k, last, collide_plane(plane.point, plane.normal, posed(w_.shapes[s]), margin(p, s, last)),
            p, s);
      }
    }
  }

  void broad_phase() {
    d_.proxies.clear();
    d_.pairs.clear();
    for (std::uint32_t s = 0; s < w_.shapes.size(); ++s) {
      const Collider& c = w_.shapes[s];
      if (c.shape == Collider::Shape::plane) continue;
      const Vec3 half = c.aabb_half + Vec3::Constant(kPad);
      d_.proxies.push_back(
          {c.aabb_center - half, c.aabb_center + half, s, owner_[s].body, dynamic(s), active(s)});
    }
    std::sort(d_.proxies.begin(), d_.proxies.end(), [](const Proxy& a, const Proxy& b) {
      return a.lo.x() < b.lo.x() || (a.lo.x() == b.lo.x() && a.shape < b.shape);
    });
    const std::size_t n = d_.proxies.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Proxy& a = d_.proxies[i];
      for (std::size_t j = i + 1; j < n && d_.proxies[j].lo.x() <= a.hi.x(); ++j) {
        const Proxy& b = d_.proxies[j];
        // A dynamic side, and a side that can move (two sleeping or resting sides: carried).
        if (!(a.dynamic || b.dynamic) || !(a.active || b.active) || a.body == b.body) continue;
        if (a.lo.y() > b.hi.y() || b.lo.y() > a.hi.y() || a.lo.z() > b.hi.z() || b.lo.z() > a.hi.z())
          continue;
        // After the cheap overlap test: a binary search over the joined pairs.
        if (no_collide(d_, a.body, b.body)) continue;  // joined (JointDef::collide_connected)
        d_.pairs.emplace_back(std::min(a.shape, b.shape), std::max(a.shape, b.shape));
      }
    }
    std::sort(d_.pairs.begin(), d_.pairs.end());
  }

  void pair(std::uint32_t a, std::uint32_t b) {
    const Collider& A = w_.shapes[a];
    const Collider& B = w_.shapes[b];
    if (A.shape == Collider::Shape::mesh && !A.hull) return mesh(a, b);
    if (B.shape == Collider::Shape::mesh && !B.hull) return mesh(b, a);
    ManifoldOptions options;
    const PairKey k = key(a, b, 0);
    const BodyManifold* last = previous(k);
    options.margin = margin(a, b, last);
    add(k, last,
        collide_manifold(posed(A), posed(B), options, A.hull ? &A.hull->faces : nullptr,
                         B.hull ? &B.hull->faces : nullptr),
        a, b);
  }

  void mesh(std::uint32_t m, std::uint32_t s) {
    const Collider& M = w_.shapes[m];
    const Collider& S = w_.shapes[s];
    const PosedShape body = posed(S);
    // The convex's box in the mesh frame (a box around the rotated box).
    const Mat3 Rt = M.R.transpose();
    const Vec3 c = Rt * (S.aabb_center - M.center);
    const Vec3 half = Rt.cwiseAbs() * (S.aabb_half + Vec3::Constant(kPad));
    // Most triangles the tree returns (80 % in the terrain benchmark) do not touch the body,
    // and their plane says so in a few products where GJK takes two or three support rounds.
    // Only pairs GJK would report apart are skipped: the contacts are the same bits.
    const TrianglePlaneCull cull(M, S);
    M.mesh->bvh.query(c - half, c + half, [&](std::uint32_t t) {
      const Triangle& tri = M.mesh->triangles[t];
      const PairKey k = key(m, s, t + 1);
      const BodyManifold* last = previous(k);
      const double gap = margin(m, s, last);
      if (cull.apart(tri, gap)) return;
      const std::array<Vec3, 3> local{tri.a, tri.b, tri.c};
      const PosedShape T(ConvexShape::hull(local), M.R, M.center);
      const ConvexContact cc = collide(T, body, gap);
      if (!cc.touching) return;
      const Vec3 n = M.R * tri.normal;
      const double along = cc.normal.dot(n);
      // A gap to a triangle's edge or corner is a speculative point only when it faces the
      // triangle: a fast body sliding over a tessellated floor sees the next triangle's edge a
      // few mm ahead, and a point with that edge's normal would stop it (a ghost collision).
      if (cc.depth < 0.0 && std::abs(along) <= 0.9) return;
      Manifold man;
      if (std::abs(along) > 0.9) {
        // A face contact: the triangle's plane, turned towards the body (two-sided mesh).
        std::array<Vec3, 3> wv{T.to_world(tri.a), T.to_world(tri.b), T.to_world(tri.c)};
        if (along < 0.0) std::swap(wv[1], wv[2]);
        man = collide_plane(wv[0], along > 0.0 ? n : Vec3(-n), body, gap, wv.data());
      }
      if (man.count == 0) man = manifold_from_contact(cc);
      add(k, last, man, m, s);
    });
  }

  /// Appends manifold `m` of shapes a (A) and b (B): warm-started from `last` (the pair's manifold
  /// of the previous step, or nullptr), its points handed to the solver.
  void add(const PairKey& k, const BodyManifold* last, Manifold m, std::uint32_t a, std::uint32_t b) {
    if (m.count == 0) return;
    if (last != nullptr) warm_start(last->manifold, m);
    const Material& ma = w_.shapes[a].material;
    const Material& mb = w_.shapes[b].material;
    // Box2D's mixing: the bouncier side wins, friction is the geometric mean (static friction
    // too, each side's μ_s defaulting to its μ).
    const double e = std::max(ma.restitution, mb.restitution);
    const double mu = std::sqrt(ma.friction * mb.friction);
    const double mu_s = std::sqrt(ma.static_mu() * mb.static_mu());
    BodyManifold bm{k, m, rigid(a), rigid(b), std::uint32_t(d_.points.size())};
    Vec3 t1, t2;
    tangent_basis(m.normal, t1, t2);
    for (int i = 0; i < m.count; ++i) {
      const ManifoldPoint& p = m.points[i];
      ContactPoint c;
      c.body_a = bm.rigid_a;
      c.body_b = bm.rigid_b;
      c.point = 0.5 * (p.point_a + p.point_b);
      c.normal = m.normal;
      c.depth = -p.separation;
      c.restitution = e;
      c.friction = mu;
      c.static_friction = mu_s;
      c.round_a = round_radius(w_.shapes[a]);
      c.round_b = round_radius(w_.shapes[b]);
      spin_axis(w_.shapes[a], p.point_a, c.axis_a, c.radial_a);
      spin_axis(w_.shapes[b], p.point_b, c.axis_b, c.radial_b);
      c.normal_impulse = p.normal_impulse;
      c.tangent_impulse[0] = p.tangent_impulse.dot(t1);
      c.tangent_impulse[1] = p.tangent_impulse.dot(t2);
      d_.points.push_back(c);
    }
    d_.manifolds.push_back(bm);
  }

  WorldState& w_;
  BodyDynamics& d_;
  std::vector<Body>& bodies_;
  std::vector<Owner> owner_;  // per step: small; the shapes' owners change only on add/remove
};

}  // namespace

void find_body_contacts(WorldState& w) { Builder(w).run(); }

}  // namespace simreel::sim::detail
