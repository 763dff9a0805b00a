#pragma once
// Momentum handed from particles and cloth vertices to the dynamic bodies they touch (private).
// Coutinho §3.7: a particle colliding with (or resting on) a rigid body is responded to with the
// body held fixed; "for each simulation time step, we need to sum all collision impulses acting
// on the rigid body owing to one or more particle-rigid body collisions, and apply the resultant
// impulse at the beginning of the next simulation time step". (An impact of the swept particle
// pass departs from the fixed body: its velocity change is shared by the two inverse masses,
// inverse_mass_at(), so a particle as heavy as the body does not throw it.) The passes that change a particle's
// or a vertex's velocity against a shape (collision/particle_response.cpp, the particle-particle
// stage's collider contacts, cloth/cloth_collide.cpp) append the equal and opposite impulse here;
// the bodies stage sums the log per body, in log order, and applies it (core/body_coupling.cpp).
//
// Determinism: the log is a sequence, not a sum, so the result does not depend on how a pass is
// split over threads as long as the chunks' logs are concatenated in particle order (a pass split
// over threads gives each chunk its own BodyImpulses and appends their entries in chunk order).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "collision/collider_impl.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim::detail {

struct BodyImpulses {
  /// One exchange: the impulse on the body and its moment about the shape frame's origin.
  struct Entry {
    std::uint32_t shape;  ///< index into WorldState::shapes
    Vec3 impulse;         ///< (N s) on the body, world frame
    Vec3 moment;          ///< (N m s) (p - c) × impulse, p the contact point, c Collider::center
  };
  static constexpr std::uint32_t kNone = 0xffffffffu;
  /// WorldState::shapes.data() and, per shape, the rigid index of its body when that body is
  /// dynamic, else kNone (set by prepare_coupling each step; only those shapes log anything).
  const Collider* shapes = nullptr;
  std::vector<std::uint32_t> rigid;
  std::vector<Entry> entries;
  /// A dynamic body's motion at the start of the step, for passes that must know how the body
  /// answers an impulse (the cloth's hold on a body, cloth_collide.hpp).
  struct Motion {
    Vec3 centre = Vec3::Zero();            ///< x (m), centre of mass, world
    Vec3 velocity = Vec3::Zero();          ///< v (m/s), world
    Vec3 angular_velocity = Vec3::Zero();  ///< ω (rad/s), world
    Vec3 gravity = Vec3::Zero();           ///< (m/s²) the body's own gravity, world
    double inv_mass = 0.0;                 ///< 1/m (1/kg); 0 while asleep (immovable)
    Mat3 inv_inertia = Mat3::Zero();       ///< I_w⁻¹ (1/(kg m²)), world; 0 while asleep
  };
  /// Per rigid index (the values of `rigid`), set by prepare_coupling each step.
  std::vector<Motion> motion;
  /// While set, add() logs nothing (logs() still answers): a pass that repeats a contact
  /// resolution whose reaction another pass accounts for (cloth.cpp).
  bool muted = false;

  /// Does add() log anything for collider c (a shape of a dynamic body)?
  [[nodiscard]] bool logs(const Collider& c) const {
    const std::size_t k = std::size_t(&c - shapes);
    return k < rigid.size() && rigid[k] != kNone;
  }
  /// The inverse effective mass (1/kg) of collider c's body at world point p along the unit
  /// normal n: 1/M + (r × n)·I⁻¹(r × n), r = p - x its centre of mass, from the start-of-step
  /// motion; 0 when c's body is not dynamic or is asleep (immovable) and while muted (the body
  /// takes nothing). A particle's impact is shared by this and 1/m_p (particle_response.cpp).
  [[nodiscard]] double inverse_mass_at(const Collider& c, const Vec3& p, const Vec3& n) const {
    if (muted || !logs(c)) return 0.0;
    const Motion& m = motion[rigid[std::size_t(&c - shapes)]];
    const Vec3 rn = (p - m.centre).cross(n);
    return m.inv_mass + rn.dot(m.inv_inertia * rn);
  }
  /// Logs the impulse J (N s, world) on collider c (an element of the `shapes` array) at world
  /// point p, if c belongs to a dynamic body.
  void add(const Collider& c, const Vec3& J, const Vec3& p) {
    if (muted) return;
    const std::size_t k = std::size_t(&c - shapes);
    if (k >= rigid.size() || rigid[k] == kNone) return;
    entries.push_back(Entry{std::uint32_t(k), J, (p - c.center).cross(J)});
  }
};

}  // namespace simreel::sim::detail
