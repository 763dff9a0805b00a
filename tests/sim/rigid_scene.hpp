#pragma once
// A minimal rigid-body scene for the solver tests: bodies with one convex shape each, contacts
// from collide() (all pairs), box-on-box and box-on-ground faces as corner contacts, warm-start
// matching by (pair, feature) keys. A stand-in for the World's broad phase and manifolds.

#include <cstdint>
#include <utility>
#include <vector>

#include "collision/convex_contact.hpp"
#include "rigid/body_state.hpp"
#include "rigid/contact_solver.hpp"
#include "rigid/integrate.hpp"
#include "rigid/mass_properties.hpp"

namespace simreel::sim::test {

using detail::ContactPoint;
using detail::ConvexShape;
using detail::PosedShape;
using detail::RigidBodies;

struct RigidScene {
  RigidBodies bodies;
  std::vector<ConvexShape> shapes;  ///< one per body (static bodies included)
  std::vector<ContactPoint> contacts;
  std::vector<std::uint64_t> keys;  ///< per contact: pair and feature, for warm starting
  detail::ContactSolver solver;
  double restitution = 0.0;
  double friction = 0.5;
  Vec3 gravity{0.0, 0.0, -9.81};

  std::size_t add(const ConvexShape& shape, double density, const Vec3& position,
                  const Quat& q = Quat::Identity(), const Vec3& velocity = Vec3::Zero()) {
    detail::RigidBodyDef d;
    d.position = position;
    d.orientation = q;
    d.linear_velocity = velocity;
    if (density > 0.0) {
      const detail::MassProperties mp = shape.kind == detail::ConvexKind::sphere
                                            ? detail::sphere_mass(shape.radius, density)
                                            : detail::box_mass(shape.half_extents, density);
      d.mass = mp.mass;
      d.inertia = mp.inertia;
    }
    shapes.push_back(shape);
    return detail::add_body(bodies, d);
  }

  /// A static ground box whose top face is the plane through `top` with normal R·z.
  std::size_t add_ground(const Quat& q = Quat::Identity(), const Vec3& top = Vec3::Zero()) {
    const Vec3 half(50.0, 50.0, 1.0);
    return add(ConvexShape::box(half), 0.0, top - q * Vec3(0.0, 0.0, half.z()), q);
  }

  /// n boxes of `half` extents stacked on z = 0, box k of density density + k density_step,
  /// shifted along x by x_offset when k is odd.
  void add_box_stack(int n, const Vec3& half, double density, double density_step = 0.0,
                     double x_offset = 0.0) {
    for (int k = 0; k < n; ++k)
      add(ConvexShape::box(half), density + k * density_step,
          Vec3(x_offset * (k % 2), 0.0, half.z() * (2 * k + 1)));
  }

  [[nodiscard]] PosedShape posed(std::size_t i) const {
    return {shapes[i], bodies.orientation[i].toRotationMatrix(), bodies.position[i]};
  }

  /// Finds the contacts at the current positions; carries cached impulses over by key.
  void find_contacts() {
    std::vector<ContactPoint> old = std::move(contacts);
    std::vector<std::uint64_t> old_keys = std::move(keys);
    contacts.clear();
    keys.clear();
    for (std::size_t i = 0; i < bodies.size(); ++i)
      for (std::size_t j = i + 1; j < bodies.size(); ++j) {
        if (!bodies.is_dynamic(i) && !bodies.is_dynamic(j)) continue;
        const PosedShape A = posed(i), B = posed(j);
        const detail::ConvexContact cc = detail::collide(A, B, 0.0);
        if (!cc.touching) continue;
        const std::uint64_t pair = (std::uint64_t(i) << 40) | (std::uint64_t(j) << 8);
        const bool boxes = A.shape.kind == detail::ConvexKind::box &&
                           B.shape.kind == detail::ConvexKind::box;
        if (!boxes) {
          push(i, j, 0.5 * (cc.point_a + cc.point_b), cc.normal, cc.depth, pair);
          continue;
        }
        // Face contact: B's corners below the plane of A's face through point_a (the test's
        // stand-in for face clipping; right when B rests on a face of A that is larger).
        const double plane = cc.normal.dot(cc.point_a);
        for (int k = 0; k < 8; ++k) {
          const Vec3 local((k & 1) ? 1.0 : -1.0, (k & 2) ? 1.0 : -1.0, (k & 4) ? 1.0 : -1.0);
          const Vec3 corner = B.to_world(local.cwiseProduct(B.shape.half_extents));
          const double depth = plane - cc.normal.dot(corner);
          if (depth >= 0.0)
            push(i, j, corner + 0.5 * depth * cc.normal, cc.normal, depth, pair | (k + 1));
        }
      }
    for (std::size_t k = 0; k < contacts.size(); ++k)
      for (std::size_t m = 0; m < old.size(); ++m)
        if (old_keys[m] == keys[k]) {
          contacts[k].normal_impulse = old[m].normal_impulse;
          contacts[k].tangent_impulse[0] = old[m].tangent_impulse[0];
          contacts[k].tangent_impulse[1] = old[m].tangent_impulse[1];
        }
  }

  void step(double h) {
    find_contacts();
    detail::step_with_contacts(bodies, solver, contacts, h, gravity);
  }

  /// Largest penetration among the current contacts (m).
  [[nodiscard]] double max_depth() const {
    double d = 0.0;
    for (const ContactPoint& c : contacts) d = std::max(d, c.depth);
    return d;
  }

 private:
  void push(std::size_t a, std::size_t b, const Vec3& p, const Vec3& n, double depth,
            std::uint64_t key) {
    ContactPoint c;
    c.body_a = bodies.is_dynamic(a) ? std::uint32_t(a) : detail::kStaticBody;
    c.body_b = bodies.is_dynamic(b) ? std::uint32_t(b) : detail::kStaticBody;
    c.point = p;
    c.normal = n;
    c.depth = depth;
    c.restitution = restitution;
    c.friction = friction;
    contacts.push_back(c);
    keys.push_back(key);
  }
};

}  // namespace simreel::sim::test
