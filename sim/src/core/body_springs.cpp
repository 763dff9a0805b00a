// Damped springs between bodies (World::add_body_spring; Coutinho §4.3.3, eqs. 4.21–4.22): the
// force on each side's point from the anchors' distance and closing speed, summed into the body
// accumulators before the velocity integration of the bodies stage.
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/world_impl.hpp"
#include "core/world_state.hpp"
#include "rigid/body_state.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace detail {
namespace {

[[noreturn]] void bad(const BodySpringDef& def, const std::string& field, const std::string& what) {
  throw std::invalid_argument("BodySpringDef." + field + (def.name.empty() ? "" : " (spring '" + def.name + "')") +
                              ": " + what);
}

/// World point and velocity of a side: rigid entry i (kStaticBody: the world point `local`).
void side_point(const RigidBodies& r, std::uint32_t i, const Vec3& local, Vec3& p, Vec3& v) {
  if (i == kStaticBody) {
    p = local;
    v.setZero();
    return;
  }
  p = r.position[i] + r.orientation[i] * local;
  v = point_velocity(r, i, p);
}

Vec3 force_on_a(const RigidBodies& r, const BodySpringEntry& e, JointBodies j, Vec3& pa, Vec3& pb) {
  Vec3 va, vb;
  side_point(r, j.a, e.local_a, pa, va);
  side_point(r, j.b, e.local_b, pb, vb);
  const Vec3 d = pb - pa;
  const double len = d.norm();
  if (!(len > 0.0)) return Vec3::Zero();  // coincident anchors: no direction to pull along
  const Vec3 u = d / len;
  return (e.def.stiffness * (len - e.rest) + e.def.damping * (vb - va).dot(u)) * u;
}

}  // namespace

void apply_body_springs(WorldState& w) {
  RigidBodies& r = w.dyn.rigid;
  const std::vector<BodySpringEntry>& springs = w.body_springs.dense();
  for (std::size_t k = 0; k < springs.size(); ++k) {
    const JointBodies j = w.dyn.spring_bodies[k];
    Vec3 pa, pb;
    const Vec3 F = force_on_a(r, springs[k], j, pa, pb);
    if (j.a != kStaticBody && r.is_dynamic(j.a)) apply_force_at(r, j.a, F, pa);
    if (j.b != kStaticBody && r.is_dynamic(j.b)) apply_force_at(r, j.b, -F, pb);
  }
}

}  // namespace detail

BodySpringHandle World::add_body_spring(const BodySpringDef& def) {
  detail::WorldState& w = *impl_;
  using detail::bad;
  if (!def.anchor_a.allFinite()) bad(def, "anchor_a", "must be finite");
  if (!def.anchor_b.allFinite()) bad(def, "anchor_b", "must be finite");
  if (!(def.stiffness >= 0.0) || !std::isfinite(def.stiffness)) bad(def, "stiffness", "must be finite and >= 0 (N/m)");
  if (!(def.damping >= 0.0) || !std::isfinite(def.damping)) bad(def, "damping", "must be finite and >= 0 (N s/m)");
  if (!std::isfinite(def.rest_length)) bad(def, "rest_length", "must be finite (negative: the current distance)");
  if (def.body_a.is_null() && def.body_b.is_null()) bad(def, "body_b", "a spring needs at least one body");
  if (def.body_a == def.body_b) bad(def, "body_b", "must differ from body_a");
  bool any_dynamic = false;
  for (const Handle& h : {def.body_a.id, def.body_b.id})
    if (!h.is_null() && w.bodies[h].dynamic()) any_dynamic = true;  // throws on a stale handle
  if (!any_dynamic) bad(def, "body_a", "neither body is dynamic: the spring would do nothing");
  detail::BodySpringEntry e;
  e.def = def;
  e.body_a = def.body_a.id;
  e.body_b = def.body_b.id;
  auto local = [&](const Handle& h, const Vec3& p) -> Vec3 {
    if (h.is_null()) return p;
    const detail::Body& b = w.bodies[h];
    if (b.rigid == detail::kNoRigid) return p;  // static: a world point
    const detail::RigidBodies& r = w.dyn.rigid;
    return r.orientation[b.rigid].conjugate() * (p - r.position[b.rigid]);
  };
  e.local_a = local(e.body_a, def.anchor_a);
  e.local_b = local(e.body_b, def.anchor_b);
  e.rest = def.rest_length >= 0.0 ? def.rest_length : (def.anchor_b - def.anchor_a).norm();
  for (const Handle& h : {e.body_a, e.body_b})
    if (!h.is_null() && w.bodies[h].dynamic()) detail::wake_island(w, w.bodies[h].rigid);
  return BodySpringHandle{w.body_springs.add(std::move(e))};
}

Vec3 World::body_spring_force(BodySpringHandle h) const {
  const detail::WorldState& w = *impl_;
  const detail::BodySpringEntry& e = w.body_springs[h.id];
  auto rigid = [&](const Handle& b) {
    if (b.is_null()) return detail::kStaticBody;
    const std::uint32_t i = w.bodies[b].rigid;
    return i == detail::kNoRigid ? detail::kStaticBody : i;
  };
  Vec3 pa, pb;
  return detail::force_on_a(w.dyn.rigid, e, {rigid(e.body_a), rigid(e.body_b)}, pa, pb);
}

void World::remove(BodySpringHandle h) {
  detail::WorldState& w = *impl_;
  const detail::BodySpringEntry& e = w.body_springs[h.id];
  for (const Handle& b : {e.body_a, e.body_b})
    if (!b.is_null() && w.bodies[b].dynamic()) detail::wake_island(w, w.bodies[b].rigid);
  w.body_springs.remove(h.id);
}

}  // namespace simreel::sim
