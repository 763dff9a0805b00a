// Joints in the World (Coutinho Ch. 5): registration, readings, removal and the per-step
// gathering the bodies stage hands to rigid/joint_solver.hpp.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/world_impl.hpp"
#include "simreel/sim/ranges.hpp"
#include "core/world_state.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace detail {
namespace {

constexpr double kPi = 3.141592653589793;

[[noreturn]] void bad(const JointDef& def, const std::string& field, const std::string& what) {
  throw std::invalid_argument("JointDef." + field + (def.name.empty() ? "" : " (joint '" + def.name + "')") +
                              ": " + what);
}

bool finite(const Vec3& v) { return v.allFinite(); }

void validate_joint(const JointDef& def) {
  if (!finite(def.anchor)) bad(def, "anchor", "must be finite");
  if (!finite(def.axis) || def.axis.norm() < 1e-12) bad(def, "axis", "must be a finite, non-zero vector");
  if (def.limit_enabled) {
    if (def.type == JointType::hinge) {
      if (!std::isfinite(def.lower_angle) || !std::isfinite(def.upper_angle) || def.lower_angle > 0.0 ||
          def.upper_angle < 0.0)
        bad(def, "lower_angle", "hinge limits must be finite with lower_angle <= 0 <= upper_angle (rad), got [" +
                                    format_number(def.lower_angle) + ", " + format_number(def.upper_angle) + "]");
    } else if (def.type == JointType::spherical) {
      if (!(def.cone_angle > 0.0 && def.cone_angle < kPi))
        bad(def, "cone_angle", "must be in (0, pi) rad with limits on a spherical joint, got " +
                                   format_number(def.cone_angle));
      if (!(def.twist_lower <= 0.0 && def.twist_upper >= 0.0 && def.twist_lower >= -kPi && def.twist_upper <= kPi))
        bad(def, "twist_lower", "twist limits must satisfy -pi <= twist_lower <= 0 <= twist_upper <= pi (rad)");
    }
  }
  if (!(def.damping >= 0.0) || !std::isfinite(def.damping)) bad(def, "damping", "must be finite and >= 0");
  if (!(def.max_motor_torque >= 0.0) || !std::isfinite(def.max_motor_torque))
    bad(def, "max_motor_torque", "must be finite and >= 0");
  if (!std::isfinite(def.motor_speed)) bad(def, "motor_speed", "must be finite");
  if (!(def.break_force >= 0.0)) bad(def, "break_force", "must be >= 0 (infinity: unbreakable)");
}

/// The frame a side's geometry is stored in: its rigid entry's (position, orientation), or the
/// world for a null or static body.
struct SideFrame {
  std::uint32_t rigid = kStaticBody;
  Vec3 x = Vec3::Zero();
  Quat q = Quat::Identity();
};

SideFrame side(const WorldState& w, const Handle& h) {
  SideFrame f;
  if (h.is_null()) return f;
  const Body& b = w.bodies[h];
  if (b.rigid == kNoRigid) return f;
  f.rigid = b.rigid;
  f.x = w.dyn.rigid.position[b.rigid];
  f.q = w.dyn.rigid.orientation[b.rigid];
  return f;
}

std::uint32_t rigid_of(const WorldState& w, const Handle& h) {
  if (h.is_null()) return kStaticBody;
  const std::uint32_t r = w.bodies[h].rigid;
  return r == kNoRigid ? kStaticBody : r;
}

}  // namespace

void gather_joints(WorldState& w) {
  BodyDynamics& d = w.dyn;
  d.joint_models.clear();
  d.joint_bodies.clear();
  d.joint_entry.clear();
  d.joint_force_n.clear();
  d.no_collide.clear();
  for (std::uint32_t i = 0; i < w.joints.size(); ++i) {
    JointEntry& e = w.joints.at(i);
    if (e.broken) {  // a broken joint carries nothing from the step after it broke
      e.reading.force.setZero();
      e.reading.torque.setZero();
      continue;
    }
    d.joint_models.push_back(e.model);
    d.joint_bodies.push_back({rigid_of(w, e.body_a), rigid_of(w, e.body_b)});
    d.joint_entry.push_back(i);
    d.joint_force_n.push_back(e.reading.force.norm());
    if (!e.def.collide_connected && !e.body_a.is_null() && !e.body_b.is_null()) {
      const std::uint32_t a = std::uint32_t(w.bodies.index(e.body_a));
      const std::uint32_t b = std::uint32_t(w.bodies.index(e.body_b));
      d.no_collide.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  std::sort(d.no_collide.begin(), d.no_collide.end());
  d.spring_bodies.clear();
  for (const BodySpringEntry& e : w.body_springs.dense())
    d.spring_bodies.push_back({rigid_of(w, e.body_a), rigid_of(w, e.body_b)});
}

bool no_collide(const BodyDynamics& d, std::uint32_t i, std::uint32_t j) {
  if (d.no_collide.empty()) return false;
  return std::binary_search(d.no_collide.begin(), d.no_collide.end(),
                            std::pair{std::min(i, j), std::max(i, j)});
}

void finish_joints(WorldState& w, double h) {
  BodyDynamics& d = w.dyn;
  const auto impulses = d.joint_solver.impulses();
  std::vector<JointEntry>& joints = w.joints.dense();
  for (std::size_t k = 0; k < d.joint_entry.size(); ++k) {
    const JointBodies j = d.joint_bodies[k];
    const bool active = (j.a != kStaticBody && d.rigid.is_dynamic(j.a)) ||
                        (j.b != kStaticBody && d.rigid.is_dynamic(j.b));
    if (!active) continue;  // asleep: keeps the reading it fell asleep with
    JointEntry& e = joints[d.joint_entry[k]];
    e.reading.force = impulses[k].linear / h;
    e.reading.torque = impulses[k].angular / h;
    if (e.reading.force.norm() > e.def.break_force) {
      e.broken = true;
      e.reading.broken = true;
    }
  }
}

void remove_joints_of(WorldState& w, const Handle& body) {
  for (std::size_t i = w.joints.size(); i-- > 0;) {
    const JointEntry& e = w.joints.at(i);
    if (e.body_a == body || e.body_b == body) w.joints.remove(w.joints.handle(i));
  }
  for (std::size_t i = w.body_springs.size(); i-- > 0;) {
    const BodySpringEntry& e = w.body_springs.at(i);
    if (e.body_a == body || e.body_b == body) w.body_springs.remove(w.body_springs.handle(i));
  }
}

}  // namespace detail

JointHandle World::add_joint(const JointDef& def) {
  detail::WorldState& w = *impl_;
  detail::validate_joint(def);
  if (def.body_a.is_null() && def.body_b.is_null()) detail::bad(def, "body_b", "a joint needs at least one body");
  if (def.body_a == def.body_b) detail::bad(def, "body_b", "must differ from body_a");
  const Handle ha = def.body_a.id, hb = def.body_b.id;
  bool any_dynamic = false;
  for (const Handle& h : {ha, hb})
    if (!h.is_null() && w.bodies[h].dynamic()) any_dynamic = true;  // throws on a stale handle
  if (!any_dynamic) detail::bad(def, "body_a", "neither body is dynamic: the joint would do nothing");
  detail::JointEntry e;
  e.def = def;
  e.def.axis = def.axis.normalized();
  e.body_a = ha;
  e.body_b = hb;
  const detail::SideFrame fa = detail::side(w, ha), fb = detail::side(w, hb);
  Vec3 ref, unused;
  detail::tangent_basis(e.def.axis, ref, unused);
  detail::JointModel& m = e.model;
  m.type = def.type;
  m.local_anchor_a = fa.q.conjugate() * (def.anchor - fa.x);
  m.local_anchor_b = fb.q.conjugate() * (def.anchor - fb.x);
  m.local_axis_a = fa.q.conjugate() * e.def.axis;
  m.local_axis_b = fb.q.conjugate() * e.def.axis;
  m.local_ref_a = fa.q.conjugate() * ref;
  m.local_ref_b = fb.q.conjugate() * ref;
  m.rel0 = fa.q.conjugate() * fb.q;
  m.limit_enabled = def.limit_enabled;
  m.lower_angle = def.lower_angle;
  m.upper_angle = def.upper_angle;
  m.cone_angle = def.cone_angle;
  m.twist_lower = def.twist_lower;
  m.twist_upper = def.twist_upper;
  m.damping = def.damping;
  m.motor_enabled = def.motor_enabled;
  m.motor_speed = def.motor_speed;
  m.max_motor_torque = def.max_motor_torque;
  // Bodies asleep on either side wake: the joint may pull them.
  for (const Handle& h : {ha, hb})
    if (!h.is_null() && w.bodies[h].dynamic()) detail::wake_island(w, w.bodies[h].rigid);
  return JointHandle{w.joints.add(std::move(e))};
}

void World::remove(JointHandle h) {
  detail::WorldState& w = *impl_;
  const detail::JointEntry& e = w.joints[h.id];
  for (const Handle& b : {e.body_a, e.body_b})
    if (!b.is_null() && w.bodies[b].dynamic()) detail::wake_island(w, w.bodies[b].rigid);
  w.joints.remove(h.id);
}

JointReading World::joint_state(JointHandle h) const {
  const detail::WorldState& w = *impl_;
  const detail::JointEntry& e = w.joints[h.id];
  JointReading r = e.reading;
  const detail::JointBodies j{detail::rigid_of(w, e.body_a), detail::rigid_of(w, e.body_b)};
  const detail::JointFrame f = detail::joint_frame(w.dyn.rigid, e.model, j);
  const detail::JointAngles a = detail::joint_angles(e.model, f);
  r.anchor = f.pa;
  r.anchor_error = (f.pb - f.pa).norm();
  r.angle = e.def.type == JointType::hinge ? a.hinge : e.def.type == JointType::spherical ? a.swing : 0.0;
  r.twist = e.def.type == JointType::spherical ? a.twist : 0.0;
  r.broken = e.broken;
  return r;
}

const JointDef& World::definition(JointHandle h) const { return impl_->joints[h.id].def; }

std::vector<JointHandle> World::joints() const {
  std::vector<JointHandle> out;
  out.reserve(impl_->joints.size());
  for (std::size_t i = 0; i < impl_->joints.size(); ++i) out.push_back(JointHandle{impl_->joints.handle(i)});
  return out;
}

}  // namespace simreel::sim
