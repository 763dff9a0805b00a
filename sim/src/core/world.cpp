// The World: registration, the step loop and the moved list (Coutinho §1.4.1, §1.3: move ->
// check collisions -> respond -> report).
#include "simreel/sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <thread>
#include <sstream>
#include <stdexcept>

#include "cloth/cloth_particles.hpp"
#include "collision/collider_impl.hpp"
#include "particles/emitter.hpp"
#include "particles/forces.hpp"
#include "particles/integrators.hpp"
#include "collision/particle_collisions.hpp"
#include "particles/particle_store.hpp"
#include "particles/split.hpp"
#include "core/validate.hpp"

namespace simreel::sim {

namespace detail {

void validate(const WorldDef& def) {
  if (!(def.max_step > 0.0) || !std::isfinite(def.max_step)) {
    std::ostringstream m;
    m << "WorldDef.max_step must be > 0 and finite (got " << def.max_step << ")";
    throw std::invalid_argument(m.str());
  }
  if (!(def.contact_speed >= 0.0) || !std::isfinite(def.contact_speed)) {
    std::ostringstream m;
    m << "WorldDef.contact_speed must be >= 0 and finite (got " << def.contact_speed << ")";
    throw std::invalid_argument(m.str());
  }
}

/// One particle system's model (definition) and state (particles, emitter).
struct ParticleSystemState {
  ParticleSystemDef def;
  std::uint16_t generation = 1;
  ParticleStore store;
  EmitterState emitter;
  ColorGradient gradient;
  SizeCurve size_curve;  ///< size over lifetime (emitter.hpp)
  Rng split_rng;         ///< particle split draws (split.hpp), a stream apart from the emitter's
  ForceParams forces{};
  std::uint64_t next_id = 0;
  // Forces beyond gravity + drag and the general integrators (forces.hpp, integrators.hpp).
  std::vector<SpringDef> springs;  ///< by particle id, rest lengths resolved
  Rng charge_rng;
  IntegratorState integrator_state;
  IntegratorWorkspace workspace;
  Dynamics dynamics;
  // Collisions (issue 5): splash droplets, §3.4.2 removals.
  Rng splash_rng;
  std::vector<SpawnRequest> spawns;
  std::uint64_t removed_inside = 0;
};

}  // namespace detail

namespace {

/// Relative slack when splitting a sampling time into steps, so T/max_step = 2.0000000001 from
/// rounding takes 2 steps, not 3.
constexpr double kStepSlack = 1e-9;

}  // namespace

struct World::Impl {
  WorldDef def;
  double time = 0.0;
  std::uint64_t steps = 0;
  std::vector<detail::Collider> colliders;
  std::vector<detail::ParticleSystemState> systems;
  std::vector<MovedObject> moved;
  std::vector<std::unique_ptr<detail::FieldState>> fields;
  std::vector<std::unique_ptr<AttractorSpringDef>> attractors;
  int threads = 1;
  detail::ParticleCollider particle_collider;

  ColliderHandle add_collider(detail::Collider c) {
    colliders.push_back(std::move(c));
    return ColliderHandle{Handle{std::uint32_t(colliders.size() - 1), colliders.back().generation,
                                 ObjectKind::collider}};
  }
  /// Colliders of system `index` over particles [begin, end), then its splash droplets.
  void collide_system(std::size_t index, std::size_t begin, std::size_t end, double h);
  /// Particle–particle collisions of every opted-in system (internal and by group), with the
  /// resting contacts on colliders in the same solve; h (s) is the step.
  void collide_particles(double h);
  std::vector<Cloth> cloths;  // cloth: one generation per slot, never removed yet
  detail::ClothParticleScratch cloth_scratch;  // particles against cloth (issue 6)

  detail::Collider& collider(ColliderHandle h) {
    if (h.id.kind != ObjectKind::collider || h.id.index >= colliders.size() ||
        h.id.generation == 0 || colliders[h.id.index].generation != h.id.generation)
      throw std::out_of_range("simreel::sim::World: stale or invalid collider handle");
    return colliders[h.id.index];
  }
  detail::ParticleSystemState& system(ParticleSystemHandle h) {
    if (h.id.kind != ObjectKind::particle_system || h.id.index >= systems.size() ||
        h.id.generation == 0 || systems[h.id.index].generation != h.id.generation)
      throw std::out_of_range("simreel::sim::World: stale or invalid particle-system handle");
    return systems[h.id.index];
  }

  Cloth& cloth(ClothHandle h) {
    if (h.id.kind != ObjectKind::cloth || h.id.index >= cloths.size() || h.id.generation != 1)
      throw std::out_of_range("simreel::sim::World: stale or invalid cloth handle");
    return cloths[h.id.index];
  }

  void step(double t0, double t1);
  void step_system(std::size_t index, double t0, double t1);
  bool general(std::size_t index) const;
  void build_dynamics(std::size_t index, bool interactions);
  [[noreturn]] void non_finite(std::size_t index, std::size_t begin, std::size_t end,
                               double t1) const;
};

// ---------------------------------------------------------------------------------------------
// The step

void World::Impl::step(double t0, double t1) {
  // Kinematic colliders first: particles collide with them at their end-of-step pose (§3.4).
  for (detail::Collider& c : colliders)
    if (c.kinematic()) c.update(t1);
  for (std::size_t s = 0; s < systems.size(); ++s) step_system(s, t0, t1);
  collide_particles(t1 - t0);
  // Cloth (§3.9.2) after the particle systems.
  for (std::size_t c = 0; c < cloths.size(); ++c) {
    if (cloths[c].step(t0, t1, &colliders)) continue;
    std::ostringstream m;
    m.precision(9);
    m << "cloth '" << cloths[c].definition().name << "' (index " << c
      << "): non-finite vertex state at internal step " << steps + 1 << ", t = " << t1 << " s";
    throw NonFiniteState(m.str());
  }
  // --- Particles against cloth (issue 6): after the cloth step, both have moved over [t0, t1];
  // each contact's impulse is shared by the triangle's vertices (cloth_particles.hpp).
  for (Cloth& cloth : cloths) {
    if (!cloth.definition().collide_particles) continue;
    for (detail::ParticleSystemState& ps : systems)
      if (ps.def.collide) detail::collide_particles_with_cloth(ps.store, t1 - t0, cloth, cloth_scratch);
  }
  // --- end particles against cloth
  ++steps;
}

void World::Impl::step_system(std::size_t index, double t0, double t1) {
  detail::ParticleSystemState& ps = systems[index];
  detail::ParticleStore& st = ps.store;
  const double h = t1 - t0;
  const bool collide = ps.def.collide && !colliders.empty();

  // 1. Particles alive at t0: integrate, then collide along their step.
  const std::size_t n_old = st.count;
  const bool full = general(index);
  if (full) {
    build_dynamics(index, true);
    if (detail::integrate_system(st, 0, n_old, t0, h, ps.dynamics, ps.def.integrator,
                                 ps.def.tolerance, ps.integrator_state, ps.workspace))
      non_finite(index, 0, n_old, t1);
  } else {
    ++ps.integrator_state.substeps;
    if (detail::integrate(st, 0, n_old, h, ps.forces, ps.def.integrator, threads))
      non_finite(index, 0, n_old, t1);
  }
  if (collide) collide_system(index, 0, n_old, h);
  // Particle split (§3.9.1): parents whose condition is met create their children.
  detail::split_particles(ps.def.emitter, ps.split_rng, st, n_old, ps.next_id);
  st.compact(0);

  // 2. Particles born in (t0, t1]: each moves only for its own age (no banding in jets).
  const std::size_t first_new = detail::emit(ps.def.emitter, ps.emitter, st, t0, t1, ps.next_id);
  if (st.has_charge)
    for (std::size_t i = first_new; i < st.count; ++i)
      st.charge[i] = float(ps.charge_rng.normal(ps.def.charge.mean, ps.def.charge.deviation));
  bool bad = false;
  if (full && first_new < st.count) {
    // A newborn moves alone for its partial step: external forces only (gravity, drag, fields);
    // springs, pair forces and attractor springs act on it from the next step.
    build_dynamics(index, false);
    detail::IntegratorState scratch;
    for (std::size_t i = first_new; i < st.count; ++i)
      bad |= detail::integrate_system(st, i, i + 1, t1 - double(st.age[i]), double(st.age[i]),
                                      ps.dynamics, ps.def.integrator, ps.def.tolerance, scratch,
                                      ps.workspace, false);
  } else {
    for (std::size_t i = first_new; i < st.count; ++i)
      bad |= detail::integrate_one(st, i, st.age[i], ps.forces, ps.def.integrator);
  }
  if (bad) non_finite(index, first_new, st.count, t1);
  if (collide) collide_system(index, first_new, st.count, h);
  ps.gradient.apply(st, first_new, st.count);
  st.compact(first_new);  // lifetimes shorter than the part of the step they lived

  // 3. Colour over lifetime.
  if (!ps.gradient.constant()) ps.gradient.apply(st, 0, first_new);

  // 4. Emitter curves: brightness variation on freshly written colours, size over lifetime.
  if (ps.def.emitter.color_deviation > 0.0)
    detail::apply_tint(st, ps.gradient.constant() ? first_new : 0, st.count);
  if (!ps.size_curve.empty()) ps.size_curve.apply(st, 0, st.count);
}

bool World::Impl::general(std::size_t index) const {
  const detail::ParticleSystemState& ps = systems[index];
  const Integrator in = ps.def.integrator;
  if (in != Integrator::semi_implicit_euler && in != Integrator::rk4) return true;
  if (!ps.springs.empty() || ps.def.pair_forces.enabled()) return true;
  if (!ps.dynamics.fields.empty()) return true;
  for (const auto& a : attractors)
    if (a->system.id.index == index) return true;
  return false;
}

void World::Impl::build_dynamics(std::size_t index, bool interactions) {
  detail::ParticleSystemState& ps = systems[index];
  detail::ParticleStore& st = ps.store;
  detail::Dynamics& d = ps.dynamics;
  d.gravity = ps.def.gravity;
  d.drag = ps.def.drag;
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
  for (const auto& a : attractors) {
    if (a->system.id.index != index) continue;
    detail::Dynamics::Pull p{a.get(), {}, a->ids.empty()};
    for (std::uint64_t id : a->ids) {
      const std::size_t i = find(id);
      if (i < st.count) p.index.push_back(std::uint32_t(i));
    }
    d.pulls.push_back(std::move(p));
  }
}

// ---------------------------------------------------------------------------------------------
// Collisions (Coutinho Ch. 2–3)

void World::Impl::collide_system(std::size_t index, std::size_t begin, std::size_t end, double h) {
  detail::ParticleSystemState& ps = systems[index];
  detail::ParticleStore& st = ps.store;
  detail::CollisionContext ctx;
  ctx.contact_speed = def.contact_speed;
  ctx.rng = &ps.splash_rng;
  ctx.spawns = &ps.spawns;
  if (ps.def.on_hit) {
    ctx.on_hit = &*ps.def.on_hit;
    ctx.on_hit_split = &ps.def.on_hit_split;
  }
  ps.spawns.clear();
  detail::collide(st, begin, end, h, colliders, ctx, ps.forces);
  ps.removed_inside += ctx.removed_inside;
  // Splash droplets (HitAction::split) join the system now, at age 0: they move from the next
  // step on. Droplets past max_particles are dropped.
  for (const detail::SpawnRequest& q : ps.spawns) {
    if (st.count >= ps.def.emitter.max_particles) break;
    const std::size_t i = st.append(1);
    for (int k = 0; k < 3; ++k) {
      st.position[3 * i + std::size_t(k)] = float(q.position[k]);
      if (st.track_prev) st.prev_position[3 * i + std::size_t(k)] = float(q.position[k]);
      st.velocity[3 * i + std::size_t(k)] = float(q.velocity[k]);
    }
    st.mass[i] = float(q.mass);
    st.radius[i] = float(q.radius);
    st.base_radius[i] = float(q.radius);
    st.lifetime[i] = float(q.lifetime);
    st.age[i] = 0.0f;
    st.id[i] = ps.next_id++;
    ps.gradient.apply(st, i, i + 1);
  }
}

void World::Impl::collide_particles(double h) {
  // Groups in order of their first member; a system without a group is its own group.
  std::vector<bool> done(systems.size(), false);
  std::vector<detail::ParticleGroupMember> members;
  for (std::size_t s = 0; s < systems.size(); ++s) {
    if (done[s]) continue;
    const ParticleSystemDef& d = systems[s].def;
    if (!d.collide_particles && d.collision_group.empty()) continue;
    members.clear();
    for (std::size_t u = s; u < systems.size(); ++u) {
      const ParticleSystemDef& du = systems[u].def;
      const bool same = u == s || (!d.collision_group.empty() && du.collision_group == d.collision_group);
      if (!same || done[u]) continue;
      done[u] = true;
      members.push_back({&systems[u].store, du.particle_restitution, du.particle_friction,
                         du.collide, std::uint32_t(u)});
    }
    // A lone system without collide_particles has nobody to collide with.
    if (members.size() == 1 && !d.collide_particles) continue;
    particle_collider.run(members, def.contact_speed, h, &colliders);
    if (colliders.empty() || particle_collider.x_before.empty()) continue;
    // The overlap correction moved particles: sweep those moves against the colliders (§3.4).
    std::size_t k = 0;
    for (const detail::ParticleGroupMember& m : members) {
      for (std::size_t i = 0; i < m.store->count; ++i, ++k) {
        const Vec3& from = particle_collider.x_before[k];
        if (m.collide && from != particle_collider.x[k])
          detail::constrain_displacement(*m.store, i, from, colliders);
      }
    }
  }
}

void World::Impl::non_finite(std::size_t index, std::size_t begin, std::size_t end,
                             double t1) const {
  const detail::ParticleSystemState& ps = systems[index];
  const detail::ParticleStore& st = ps.store;
  std::size_t i = begin;
  for (; i < end; ++i) {
    bool ok = true;
    for (int k = 0; k < 3; ++k)
      ok = ok && std::isfinite(st.position[3 * i + std::size_t(k)]) &&
           std::isfinite(st.velocity[3 * i + std::size_t(k)]);
    if (!ok) break;
  }
  std::ostringstream m;
  m.precision(9);
  m << "particle system '" << ps.def.name << "' (index " << index
    << "): non-finite particle state";
  if (i < end) m << " (particle id " << st.id[i] << ")";
  m << " at internal step " << steps + 1 << ", t = " << t1 << " s";
  throw NonFiniteState(m.str());
}

// ---------------------------------------------------------------------------------------------
// World

World::World(const WorldDef& def) : impl_(std::make_unique<Impl>()) {
  detail::validate(def);
  if (def.threads < 0) throw std::invalid_argument("WorldDef.threads must be >= 0 (0 = hardware)");
  impl_->def = def;
  impl_->threads = def.threads > 0 ? def.threads
                                   : std::max(1, int(std::thread::hardware_concurrency()));
}

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

ColliderHandle World::add_plane(const PlaneDef& def) {
  return impl_->add_collider(detail::make_collider(def));
}
ColliderHandle World::add_box(const BoxDef& def) {
  return impl_->add_collider(detail::make_collider(def, impl_->time));
}
ColliderHandle World::add_sphere(const SphereDef& def) {
  return impl_->add_collider(detail::make_collider(def, impl_->time));
}
ColliderHandle World::add_cylinder(const CylinderDef& def) {
  return impl_->add_collider(detail::make_collider(def, impl_->time));
}
ColliderHandle World::add_mesh(const MeshDef& def) {
  return impl_->add_collider(detail::make_collider(def, impl_->time));
}

std::uint64_t World::removed_inside_count(ParticleSystemHandle h) const {
  return impl_->system(h).removed_inside;
}

ParticleSystemHandle World::add_particle_system(const ParticleSystemDef& def) {
  // The integrator and the force definitions are checked by validate_forces (forces.cpp), the
  // emitter by validate (emitter.cpp).
  detail::validate_forces(def);
  detail::validate(def);
  if (!(def.particle_restitution >= 0.0 && def.particle_restitution <= 1.0) ||
      !(def.particle_friction >= 0.0) || !std::isfinite(def.particle_friction)) {
    std::ostringstream m;
    m << "ParticleSystemDef '" << def.name << "': particle_restitution must be in [0, 1] and "
      << "particle_friction >= 0 and finite (got " << def.particle_restitution << ", "
      << def.particle_friction << ")";
    throw std::invalid_argument(m.str());
  }
  const std::size_t index = impl_->systems.size();
  detail::ParticleSystemState ps;
  ps.def = def;
  ps.store.track_prev = def.collide && def.integrator != Integrator::semi_implicit_euler;
  ps.store.has_charge = def.charge.mean != 0.0 || def.charge.deviation != 0.0;
  for (const InitialParticle& p : def.initial_particles) ps.store.has_charge |= p.charge != 0.0;
  ps.store.reserve(def.emitter.max_particles);
  ps.charge_rng = Rng(impl_->def.seed, 0x5eed0000u + index);
  ps.emitter.rng = Rng(impl_->def.seed, index);
  ps.splash_rng = Rng(impl_->def.seed, 0x5b1a5400000000ull + index);  // own stream: splashes
  ps.gradient = detail::ColorGradient(def.emitter.color_over_lifetime);
  ps.size_curve = detail::SizeCurve(def.emitter.size_over_lifetime);
  ps.split_rng = Rng(impl_->def.seed, (std::uint64_t{1} << 32) + index);
  for (int k = 0; k < 3; ++k) ps.forces.gravity[k] = float(def.gravity[k]);
  ps.forces.drag = float(def.drag);
  // Initial particles: ids 0..k-1, immortal; springs between them by index = id.
  for (const InitialParticle& p : def.initial_particles) {
    detail::ParticleStore& st = ps.store;
    const std::size_t i = st.append(1);
    for (int k = 0; k < 3; ++k) {
      st.position[3 * i + std::size_t(k)] = float(p.position[k]);
      if (st.track_prev) st.prev_position[3 * i + std::size_t(k)] = float(p.position[k]);
      st.velocity[3 * i + std::size_t(k)] = float(p.velocity[k]);
    }
    st.mass[i] = float(p.mass);
    st.radius[i] = float(p.radius);
    st.base_radius[i] = float(p.radius);
    st.lifetime[i] = std::numeric_limits<float>::infinity();
    st.age[i] = 0.0f;
    st.id[i] = ps.next_id++;
    if (st.has_charge) st.charge[i] = float(p.charge);
    ps.gradient.apply(st, i, i + 1);
  }
  for (SpringDef s : def.springs) {
    if (s.rest_length < 0.0)
      s.rest_length = (def.initial_particles[s.a].position - def.initial_particles[s.b].position).norm();
    ps.springs.push_back(s);
  }
  for (const auto& f : impl_->fields)
    if (f->def.systems.empty()) ps.dynamics.fields.push_back(f.get());
  impl_->systems.push_back(std::move(ps));
  return ParticleSystemHandle{
      Handle{std::uint32_t(index), impl_->systems.back().generation, ObjectKind::particle_system}};
}

std::uint64_t World::spawn_particle(ParticleSystemHandle h, const Vec3& position,
                                    const Vec3& velocity, double mass, double radius,
                                    double lifetime) {
  detail::ParticleSystemState& ps = impl_->system(h);
  if (!(mass > 0.0) || !(radius > 0.0) || !(lifetime >= 0.0)) {
    std::ostringstream m;
    m << "World::spawn_particle: mass and radius must be > 0 and lifetime >= 0 (got mass " << mass
      << ", radius " << radius << ", lifetime " << lifetime << ")";
    throw std::invalid_argument(m.str());
  }
  detail::ParticleStore& st = ps.store;
  if (st.count >= ps.def.emitter.max_particles)
    throw std::length_error("World::spawn_particle: particle system '" + ps.def.name +
                            "' already holds max_particles live particles");
  const std::size_t i = st.append(1);
  for (int k = 0; k < 3; ++k) {
    st.position[3 * i + std::size_t(k)] = float(position[k]);
    if (st.track_prev) st.prev_position[3 * i + std::size_t(k)] = float(position[k]);
    st.velocity[3 * i + std::size_t(k)] = float(velocity[k]);
  }
  st.mass[i] = float(mass);
  st.radius[i] = float(radius);
  st.base_radius[i] = float(radius);
  st.tint[i] = 1.0f;
  st.lifetime[i] = float(lifetime);
  st.age[i] = 0.0f;
  st.id[i] = ps.next_id++;
  ps.gradient.apply(st, i, i + 1);
  return st.id[i];
}

std::size_t World::add_force_field(const ForceFieldDef& def) {
  detail::validate(def);
  for (const ParticleSystemHandle& h : def.systems) (void)impl_->system(h);
  auto f = std::make_unique<detail::FieldState>();
  f->def = def;
  f->def.axis = def.axis.normalized();
  f->noise = detail::GradientNoise(impl_->def.seed ^ (0x9E3779B97F4A7C15ULL * (impl_->fields.size() + 1)));
  f->pose_at(impl_->time);
  for (std::size_t s = 0; s < impl_->systems.size(); ++s) {
    bool applies = def.systems.empty();
    for (const ParticleSystemHandle& h : def.systems) applies = applies || h.id.index == s;
    if (applies) impl_->systems[s].dynamics.fields.push_back(f.get());
  }
  impl_->fields.push_back(std::move(f));
  return impl_->fields.size() - 1;
}

std::size_t World::add_attractor_spring(const AttractorSpringDef& def) {
  (void)impl_->system(def.system);
  detail::validate(def);
  impl_->attractors.push_back(std::make_unique<AttractorSpringDef>(def));
  return impl_->attractors.size() - 1;
}

void World::add_spring(ParticleSystemHandle h, const SpringDef& spring) {
  detail::ParticleSystemState& ps = impl_->system(h);
  const detail::ParticleStore& st = ps.store;
  const auto find = [&](std::uint64_t id) -> std::size_t {
    const auto* b = st.id.data();
    const auto* e = b + st.count;
    const auto* it = std::lower_bound(b, e, id);
    return it != e && *it == id ? std::size_t(it - b) : st.count;
  };
  const std::size_t i = find(spring.a), j = find(spring.b);
  if (i == st.count || j == st.count || spring.a == spring.b)
    throw std::invalid_argument("World::add_spring: ids a and b must name two different live "
                                "particles of the system");
  if (!(spring.stiffness >= 0.0) || !(spring.damping >= 0.0) || !std::isfinite(spring.stiffness) ||
      !std::isfinite(spring.damping))
    throw std::invalid_argument("World::add_spring: stiffness and damping must be >= 0 and finite");
  SpringDef s = spring;
  if (s.rest_length < 0.0) {
    Vec3 d;
    for (int k = 0; k < 3; ++k)
      d[k] = double(st.position[3 * i + std::size_t(k)]) - double(st.position[3 * j + std::size_t(k)]);
    s.rest_length = d.norm();
  }
  ps.springs.push_back(s);
}

std::uint64_t World::integrator_steps(ParticleSystemHandle h) const {
  return impl_->system(h).integrator_state.substeps;
}
std::uint64_t World::rejected_steps(ParticleSystemHandle h) const {
  return impl_->system(h).integrator_state.rejected;
}

const std::vector<MovedObject>& World::advance(double sampling_time) {
  Impl& w = *impl_;
  if (!(sampling_time > 0.0) || !std::isfinite(sampling_time)) {
    std::ostringstream m;
    m << "World::advance: sampling_time must be > 0 and finite (got " << sampling_time << ")";
    throw std::invalid_argument(m.str());
  }
  const double ratio = sampling_time / w.def.max_step;
  const std::uint64_t n = std::max<std::uint64_t>(
      1, std::uint64_t(std::ceil(ratio - kStepSlack * std::max(1.0, ratio))));
  const double h = sampling_time / double(n);
  const double start = w.time;
  for (std::uint64_t i = 0; i < n; ++i) {
    const double t0 = start + double(i) * h;
    const double t1 = i + 1 == n ? start + sampling_time : start + double(i + 1) * h;
    w.step(t0, t1);
    w.time = t1;
  }

  w.moved.clear();
  for (std::size_t i = 0; i < w.colliders.size(); ++i) {
    detail::Collider& c = w.colliders[i];
    if (!c.kinematic()) continue;
    if (c.center == c.reported_translation && c.rotation.coeffs() == c.reported_rotation.coeffs())
      continue;
    c.reported_translation = c.center;
    c.reported_rotation = c.rotation;
    MovedObject m = c.pose();
    m.handle = Handle{std::uint32_t(i), c.generation, ObjectKind::collider};
    w.moved.push_back(m);
  }
  return w.moved;
}

MovedObject World::pose(ColliderHandle h) const {
  MovedObject m = impl_->collider(h).pose();
  m.handle = h.id;
  return m;
}

ParticleView World::particles(ParticleSystemHandle h) const { return impl_->system(h).store.view(); }

const ParticleSystemDef& World::definition(ParticleSystemHandle h) const {
  return impl_->system(h).def;
}

double World::time() const { return impl_->time; }
std::uint64_t World::step_count() const { return impl_->steps; }

std::uint64_t World::emitted_count(ParticleSystemHandle h) const {
  return impl_->system(h).next_id;
}

std::vector<ParticleSystemHandle> World::particle_systems() const {
  std::vector<ParticleSystemHandle> out;
  for (std::size_t i = 0; i < impl_->systems.size(); ++i)
    out.push_back(ParticleSystemHandle{
        Handle{std::uint32_t(i), impl_->systems[i].generation, ObjectKind::particle_system}});
  return out;
}

std::vector<ColliderHandle> World::colliders() const {
  std::vector<ColliderHandle> out;
  for (std::size_t i = 0; i < impl_->colliders.size(); ++i)
    out.push_back(
        ColliderHandle{Handle{std::uint32_t(i), impl_->colliders[i].generation, ObjectKind::collider}});
  return out;
}

// ---------------------------------------------------------------------------------------------
// Cloth

ClothHandle World::add_cloth(const ClothDef& def) {
  const std::size_t index = impl_->cloths.size();
  impl_->cloths.emplace_back(def, impl_->def.seed, index);
  return ClothHandle{Handle{std::uint32_t(index), 1, ObjectKind::cloth}};
}

ClothView World::cloth(ClothHandle h) const { return impl_->cloth(h).view(); }
ClothStats World::cloth_stats(ClothHandle h) const { return impl_->cloth(h).stats(); }
const ClothDef& World::definition(ClothHandle h) const { return impl_->cloth(h).definition(); }

std::vector<ClothHandle> World::cloths() const {
  std::vector<ClothHandle> out;
  for (std::size_t i = 0; i < impl_->cloths.size(); ++i)
    out.push_back(ClothHandle{Handle{std::uint32_t(i), 1, ObjectKind::cloth}});
  return out;
}

}  // namespace simreel::sim
