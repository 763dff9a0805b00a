// Two-way coupling of dynamic bodies with particles, cloth and force fields (the rigid-body
// issue's coupling part).
//
// Impulses (Coutinho §3.7). Particles and cloth vertices are responded to with the body held
// fixed at its pose (the body taken as immovable: the exchange is right when a particle is much
// lighter than the body); each velocity change Δv of a particle of mass m against a dynamic
// body's shape logs the impulse -m Δv on the body at the contact point (BodyImpulses). "For each
// simulation time step ... sum all collision impulses acting on rigid body B ... and apply the
// resultant impulse at the beginning of the next simulation time step": the bodies stage, which
// follows the particle and cloth stages, sums the log of its step per body in log order (the
// particles' order, the same at any thread count) and applies it as the constant force J/h and
// torque Σ (p - x) × J / h over its step, which changes the momenta by exactly J and
// Σ (p - x) × J before the contact solve sees them (a box on the floor pressed by rain is held
// by the floor's contacts in the same solve).
//
// Force fields on bodies, at the centre of mass x (velocity v, mass M, drag coefficient C_d and
// area A of the body; w the field's drop-off weight at x):
//   uniform:             F = w R (M a + f) + w ½ ρ_air C_d A |u - v| (u - v),  u = R wind
//   attractor, vortex:   F = M a(x, v): the particle acceleration field, times the mass
//   curl_noise:          F = w ½ ρ_air C_d A |u - v| (u - v),  u = the noise flow at x
//   blast:               J = w Π A / (4π max(d, √(A/π))²) d̂ once, in the step holding `time`
// The air drag is the quadratic (Newtonian) law of a bluff body, ρ_air = 1.225 kg/m³ (sea level,
// 15 °C), evaluated with the velocity at the start of the step. The blast is the explosion's
// momentum Π spreading evenly over the sphere of radius d: a body intercepts the fraction
// A / (4π d²) of it (d is not taken below the radius √(A/π) of the disc of area A, so a body at
// the centre takes at most Π/4). Fields act on bodies only when ForceFieldDef::bodies is set;
// they are summed in registration order, bodies in dense order (serial: deterministic).
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "core/stages.hpp"

namespace simreel::sim::detail {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kAirDensity = 1.225;  ///< (kg/m³) ρ_air at sea level, 15 °C

/// (N) Quadratic air drag ½ ρ C_d A |u - v| (u - v) of a body moving at v in air moving at u.
Vec3 air_drag(const Body& b, const Vec3& u, const Vec3& v) {
  const Vec3 rel = u - v;
  return (0.5 * kAirDensity * b.drag_coefficient * b.drag_area * rel.norm()) * rel;
}

/// (N) The force of field f on dynamic body b over the step [t0, t1] (see the file comment).
Vec3 field_force(const FieldState& f, const Body& b, const RigidBodies& r, double t0, double t1) {
  const std::uint32_t i = b.rigid;
  const Vec3& x = r.position[i];
  const Vec3& v = r.linear_velocity[i];
  const double m = r.mass[i];
  const double w = f.weight(x);
  if (w == 0.0) return Vec3::Zero();
  const ForceFieldDef& d = f.def;
  switch (d.kind) {
    case FieldKind::uniform: {
      Vec3 F = w * (f.rotation * (m * d.acceleration + d.force));
      if (d.wind != Vec3::Zero()) F += w * air_drag(b, f.air_velocity(x, t0), v);
      return F;
    }
    case FieldKind::attractor:
    case FieldKind::vortex:
      return m * f.acceleration(x, v, m, t0);
    case FieldKind::curl_noise:
      return w * air_drag(b, f.air_velocity(x, t0), v);
    case FieldKind::blast: {
      if (!(t0 <= d.time && d.time < t1)) return Vec3::Zero();
      const Vec3 off = x - f.centre;
      const double dist = off.norm();
      if (!(dist > 0.0)) return Vec3::Zero();  // no outward direction
      const double reach = std::max(dist, std::sqrt(b.drag_area / kPi));
      const double J = w * d.impulse * b.drag_area / (4.0 * kPi * reach * reach);
      return (J / (t1 - t0) / dist) * off;
    }
  }
  return Vec3::Zero();
}

}  // namespace

void prepare_coupling(WorldState& w) {
  BodyImpulses& c = w.dyn.coupling;
  c.entries.clear();
  c.shapes = w.shapes.data();
  if (w.dyn.dynamic_count == 0) {
    c.rigid.clear();
    return;
  }
  c.rigid.assign(w.shapes.size(), BodyImpulses::kNone);
  for (const Body& b : w.bodies.dense())
    if (b.dynamic())
      for (std::uint32_t k = b.first_shape; k < b.first_shape + b.shape_count; ++k) c.rigid[k] = b.rigid;
  const RigidBodies& r = w.dyn.rigid;
  c.motion.resize(r.size());
  for (std::size_t i = 0; i < r.size(); ++i)
    c.motion[i] = {r.position[i], r.linear_velocity[i], r.angular_velocity[i], Vec3::Zero(),
                   r.inv_mass[i], r.inv_inertia_world[i]};
  for (const Body& b : w.bodies.dense()) {
    if (!b.dynamic()) continue;
    BodyImpulses::Motion& m = c.motion[b.rigid];
    m.gravity = b.gravity;
    // A sleeping body answers an impulse as the awake body it becomes (the impulse wakes it):
    // a pinned sheet keeps holding a body asleep in it, which then never sleeps there, instead
    // of the sheet's tension throwing it when it wakes.
    if (r.asleep[b.rigid] && r.mass[b.rigid] > 0.0) {
      const Mat3 R = r.orientation[b.rigid].toRotationMatrix();
      m.inv_mass = 1.0 / r.mass[b.rigid];
      m.inv_inertia = R * r.inv_inertia_body[b.rigid] * R.transpose();
    }
  }
}

BodyImpulses* coupling_log(WorldState& w) {
  return w.dyn.dynamic_count > 0 ? &w.dyn.coupling : nullptr;
}

void wake_coupled(WorldState& w, double t0, double t1) {
  BodyDynamics& d = w.dyn;
  const RigidBodies& r = d.rigid;
  for (const BodyImpulses::Entry& e : d.coupling.entries) {
    const std::uint32_t i = d.coupling.rigid[e.shape];
    if (r.asleep[i] && !e.impulse.isZero(0.0)) wake_island(w, i);
  }
  if (w.fields.size() == 0) return;
  for (std::size_t f = 0; f < w.fields.size(); ++f) {
    FieldState& field = *w.fields.at(f).state;
    if (!field.def.bodies) continue;
    field.pose_at(t0);
    for (const Body& b : w.bodies.dense())
      if (b.dynamic() && r.asleep[b.rigid] && !field_force(field, b, r, t0, t1).isZero(0.0))
        wake_island(w, b.rigid);
  }
}

void apply_coupling(WorldState& w, double t0, double t1) {
  BodyDynamics& d = w.dyn;
  RigidBodies& r = d.rigid;
  const double h = t1 - t0;
  BodyImpulses& log = d.coupling;
  if (!log.entries.empty()) {
    // Per body: ΣJ and Σ (p - x) × J = Σ (p - c) × J + (c - x) × J, c the shape's origin.
    std::vector<Vec3>& impulse = d.coupling_impulse;
    std::vector<Vec3>& moment = d.coupling_moment;
    std::vector<std::uint8_t>& touched = d.coupling_touched;
    impulse.assign(r.size(), Vec3::Zero());
    moment.assign(r.size(), Vec3::Zero());
    touched.assign(r.size(), 0);
    for (const BodyImpulses::Entry& e : log.entries) {
      const std::uint32_t i = log.rigid[e.shape];
      impulse[i] += e.impulse;
      moment[i] += e.moment + (w.shapes[e.shape].center - r.position[i]).cross(e.impulse);
      touched[i] = 1;
    }
    for (std::size_t i = 0; i < r.size(); ++i) {
      if (touched[i] == 0 || !r.is_dynamic(i)) continue;
      apply_force(r, i, impulse[i] / h);
      apply_torque(r, i, moment[i] / h);
    }
    log.entries.clear();
  }
  if (w.fields.size() == 0) return;
  // Fields in registration order (their serials), as the particle systems sum them.
  std::vector<std::pair<std::uint64_t, FieldState*>> fields;
  for (std::size_t f = 0; f < w.fields.size(); ++f)
    if (w.fields.at(f).state->def.bodies)
      fields.emplace_back(w.fields.serial(f), w.fields.at(f).state.get());
  std::sort(fields.begin(), fields.end());
  for (const auto& [serial, f] : fields) {
    f->pose_at(t0);
    for (const Body& b : w.bodies.dense())
      if (b.dynamic() && r.is_dynamic(b.rigid)) apply_force(r, b.rigid, field_force(*f, b, r, t0, t1));
  }
}

}  // namespace simreel::sim::detail
