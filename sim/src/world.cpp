// The World: registration, the step loop and the moved list (Coutinho §1.4.1, §1.3: move ->
// check collisions -> respond -> report).
#include "simreel/sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "collider_impl.hpp"
#include "emitter.hpp"
#include "particle_store.hpp"
#include "validate.hpp"

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
  ForceParams forces{};
  std::uint64_t next_id = 0;
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
  std::vector<Cloth> cloths;  // cloth: one generation per slot, never removed yet

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
  // Cloth (§3.9.2) after the particle systems.
  for (std::size_t c = 0; c < cloths.size(); ++c) {
    if (cloths[c].step(t0, t1, &colliders)) continue;
    std::ostringstream m;
    m.precision(9);
    m << "cloth '" << cloths[c].definition().name << "' (index " << c
      << "): non-finite vertex state at internal step " << steps + 1 << ", t = " << t1 << " s";
    throw NonFiniteState(m.str());
  }
  ++steps;
}

void World::Impl::step_system(std::size_t index, double t0, double t1) {
  detail::ParticleSystemState& ps = systems[index];
  detail::ParticleStore& st = ps.store;
  const double h = t1 - t0;
  const bool collide = ps.def.collide && !colliders.empty();

  // 1. Particles alive at t0: integrate, then collide along their step.
  const std::size_t n_old = st.count;
  if (detail::integrate(st, 0, n_old, h, ps.forces, ps.def.integrator))
    non_finite(index, 0, n_old, t1);
  if (collide) detail::collide(st, 0, n_old, h, colliders, def.contact_speed, ps.forces);
  st.compact(0);

  // 2. Particles born in (t0, t1]: each moves only for its own age (no banding in jets).
  const std::size_t first_new = detail::emit(ps.def.emitter, ps.emitter, st, t0, t1, ps.next_id);
  bool bad = false;
  for (std::size_t i = first_new; i < st.count; ++i)
    bad |= detail::integrate_one(st, i, st.age[i], ps.forces, ps.def.integrator);
  if (bad) non_finite(index, first_new, st.count, t1);
  if (collide) detail::collide(st, first_new, st.count, h, colliders, def.contact_speed, ps.forces);
  ps.gradient.apply(st, first_new, st.count);
  st.compact(first_new);  // lifetimes shorter than the part of the step they lived

  // 3. Colour over lifetime.
  if (!ps.gradient.constant()) ps.gradient.apply(st, 0, first_new);
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
  impl_->def = def;
}

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

ColliderHandle World::add_plane(const PlaneDef& def) {
  impl_->colliders.push_back(detail::make_collider(def));
  return ColliderHandle{Handle{std::uint32_t(impl_->colliders.size() - 1),
                               impl_->colliders.back().generation, ObjectKind::collider}};
}

ColliderHandle World::add_box(const BoxDef& def) {
  impl_->colliders.push_back(detail::make_collider(def, impl_->time));
  return ColliderHandle{Handle{std::uint32_t(impl_->colliders.size() - 1),
                               impl_->colliders.back().generation, ObjectKind::collider}};
}

ParticleSystemHandle World::add_particle_system(const ParticleSystemDef& def) {
  detail::validate(def);
  const std::size_t index = impl_->systems.size();
  detail::ParticleSystemState ps;
  ps.def = def;
  ps.store.track_prev = def.collide && def.integrator == Integrator::rk4;
  ps.store.reserve(def.emitter.max_particles);
  ps.emitter.rng = Rng(impl_->def.seed, index);
  ps.gradient = detail::ColorGradient(def.emitter.color_over_lifetime);
  for (int k = 0; k < 3; ++k) ps.forces.gravity[k] = float(def.gravity[k]);
  ps.forces.drag = float(def.drag);
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
  st.lifetime[i] = float(lifetime);
  st.age[i] = 0.0f;
  st.id[i] = ps.next_id++;
  ps.gradient.apply(st, i, i + 1);
  return st.id[i];
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
