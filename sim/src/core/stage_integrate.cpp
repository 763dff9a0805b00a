// Stage "particle forces and integration" (stages.hpp): every system's particles alive at t0
// move over the step, by the fast gravity + drag path or the general integrators (forces.hpp,
// integrators.hpp; Coutinho §3.3, Appendix B).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/stages.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim::detail {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kAirDensity = 1.225;  ///< (kg/m³) ρ_air at sea level, 15 °C (body_coupling.cpp)

/// Blast fields whose pulse passes in [t0, t1) push the particles of system `index` alive at t0
/// and born before the pulse (forces.hpp FieldKind::blast): Δv = J / (m + ½ ρ_air V) outward,
/// J = w Π π r² / (4π max(d, r)²), with x at t0. Fields in table order, particles in array
/// order: serial and deterministic; a blast happens once, so it needs no threads.
void apply_blasts(WorldState& w, std::size_t index, double t0, double t1) {
  ParticleSystemState& ps = w.systems.at(index);
  ParticleStore& st = ps.store;
  const ParticleSystemHandle self{w.systems.handle(index)};
  for (FieldEntry& e : w.fields.dense()) {
    FieldState& f = *e.state;
    const ForceFieldDef& d = f.def;
    if (d.kind != FieldKind::blast || !d.particles || !(t0 <= d.time && d.time < t1)) continue;
    if (!e.all_systems && std::find(d.systems.begin(), d.systems.end(), self) == d.systems.end())
      continue;
    f.pose_at(t0);
    // Born at or after the pulse (to within float ages): the blast's own products.
    const double born_before = d.time - 1e-6;
    for (std::size_t i = 0; i < ps.n_old; ++i) {
      if (!(t0 - double(st.age[i]) < born_before)) continue;
      const Vec3 x(st.position[3 * i], st.position[3 * i + 1], st.position[3 * i + 2]);
      const double weight = f.weight(x);
      if (weight == 0.0) continue;
      const Vec3 off = x - f.centre;
      const double dist = off.norm();
      if (!(dist > 0.0)) continue;  // no outward direction
      const double r = st.radius[i];
      const double reach = std::max(dist, r);
      const double J = weight * d.impulse * r * r / (4.0 * reach * reach);  // Π π r² / (4π reach²)
      const double m_eff = double(st.mass[i]) + 0.5 * kAirDensity * (4.0 / 3.0) * kPi * r * r * r;
      const Vec3 dv = (J / m_eff / dist) * off;
      for (int k = 0; k < 3; ++k)
        st.velocity[3 * i + std::size_t(k)] = float(double(st.velocity[3 * i + std::size_t(k)]) + dv[k]);
    }
  }
}

}  // namespace

void stage_particle_integration(WorldState& w, double t0, double t1) {
  const double h = t1 - t0;
  for (std::size_t index = 0; index < w.systems.size(); ++index) {
    ParticleSystemState& ps = w.systems.at(index);
    ParticleStore& st = ps.store;
    ps.n_old = st.count;
    if (ps.n_old > 0 && w.fields.size() > 0) apply_blasts(w, index, t0, t1);
    ps.general = w.general(index);
    if (ps.general) {
      w.build_dynamics(index, true);
      if (integrate_system(st, 0, ps.n_old, t0, h, ps.dynamics, ps.def.integrator,
                           ps.def.tolerance, ps.integrator_state, ps.workspace))
        w.non_finite(index, 0, ps.n_old, t1);
    } else {
      ++ps.integrator_state.substeps;
      if (integrate(st, 0, ps.n_old, h, ps.forces, ps.def.integrator, w.threads))
        w.non_finite(index, 0, ps.n_old, t1);
    }
  }
}

bool WorldState::sleep_allowed(std::size_t index) const {
  const ParticleSystemState& ps = systems.at(index);
  if (!ps.store.track_rest || general(index) || !cloths.dense().empty() || dyn.dynamic_count > 0)
    return false;
  for (const Collider& c : shapes)
    if (c.moving) return false;
  return true;
}

bool WorldState::general(std::size_t index) const {
  const ParticleSystemState& ps = systems.at(index);
  const Integrator in = ps.def.integrator;
  if (in != Integrator::semi_implicit_euler && in != Integrator::rk4) return true;
  if (!ps.springs.empty() || ps.def.pair_forces.enabled()) return true;
  if (!ps.dynamics.fields.empty()) return true;
  return !ps.attractors.empty();
}

void WorldState::build_dynamics(std::size_t index, bool interactions) {
  ParticleSystemState& ps = systems.at(index);
  ParticleStore& st = ps.store;
  Dynamics& d = ps.dynamics;
  d.gravity = ps.def.gravity;
  d.drag = ps.def.drag;
  d.drag_quadratic = ps.def.drag_quadratic;
  d.max_speed = ps.forces.max_speed;
  d.max_distance = ps.forces.max_distance;
  d.threads = threads;
  d.pair = ps.def.pair_forces;
  if (!interactions) d.pair.gravitational_G = d.pair.coulomb_K = 0.0;
  d.springs.clear();
  d.pulls.clear();
  if (!interactions) return;
  // Ids increase along the arrays (emission order, survivors keep theirs): binary search.
  const auto find = [&](std::uint64_t id) -> std::size_t {
    const auto* b = st.id.data();
    const auto* e = b + st.count;
    const auto* it = std::lower_bound(b, e, id);
    return it != e && *it == id ? std::size_t(it - b) : st.count;
  };
  std::size_t keep = 0;
  for (const SpringDef& s : ps.springs) {
    const std::size_t i = find(s.a), j = find(s.b);
    if (i == st.count || j == st.count) continue;  // an end died: the spring goes with it
    ps.springs[keep++] = s;
    d.springs.push_back({std::uint32_t(i), std::uint32_t(j), s.stiffness, s.damping, s.rest_length});
  }
  ps.springs.resize(keep);
  for (const AttractorSpringDef* a : ps.attractors) {
    Dynamics::Pull p{a, {}, a->ids.empty()};
    for (std::uint64_t id : a->ids) {
      const std::size_t i = find(id);
      if (i < st.count) p.index.push_back(std::uint32_t(i));
    }
    d.pulls.push_back(std::move(p));
  }
}

void WorldState::non_finite(std::size_t index, std::size_t begin, std::size_t end,
                            double t1) const {
  const ParticleSystemState& ps = systems.at(index);
  const ParticleStore& st = ps.store;
  const float vmax = ps.forces.max_speed, xmax = ps.forces.max_distance;
  std::size_t i = begin;
  bool finite = true;
  for (; i < end; ++i) {
    bool fin = true, bounded = true;
    for (int k = 0; k < 3; ++k) {
      const float x = st.position[3 * i + std::size_t(k)], v = st.velocity[3 * i + std::size_t(k)];
      fin = fin && std::isfinite(x) && std::isfinite(v);
      bounded = bounded && std::abs(x) <= xmax && std::abs(v) <= vmax;
    }
    if (!fin || !bounded) {
      finite = fin;
      break;
    }
  }
  std::ostringstream m;
  m.precision(9);
  m << "particle system '" << ps.def.name << "' (index " << index << "): ";
  if (i < end && finite) {
    const Vec3 x(st.position[3 * i], st.position[3 * i + 1], st.position[3 * i + 2]);
    const Vec3 v(st.velocity[3 * i], st.velocity[3 * i + 1], st.velocity[3 * i + 2]);
    m << "diverged (particle id " << st.id[i] << " at |x| = " << x.norm() << " m, |v| = "
      << v.norm() << " m/s; bounds simulation.max_distance = " << xmax
      << " m, simulation.max_speed = " << vmax << " m/s per component)";
  } else {
    m << "non-finite particle state";
    if (i < end) m << " (particle id " << st.id[i] << ")";
  }
  m << " at internal step " << steps + 1 << ", t = " << t1 << " s";
  throw NonFiniteState(m.str());
}

}  // namespace simreel::sim::detail
