// The World: registration, removal and the accessors (Coutinho §1.4.1). Bodies are registered in
// bodies.cpp, the step is in step.cpp and its stages (stages.hpp); removal in remove.cpp.
#include "simreel/sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <thread>
#include <stdexcept>

#include "core/validate.hpp"
#include "core/world_impl.hpp"

namespace simreel::sim {

namespace detail {

void validate(const WorldDef& def) {
  require_in(def.max_step, ranges::kWorldMaxStep, "WorldDef.max_step");
  require_in(double(def.body_substeps), ranges::kWorldBodySubsteps, "WorldDef.body_substeps");
  require_in(def.contact_speed, ranges::kWorldContactSpeed, "WorldDef.contact_speed");
  require_in(def.max_speed, ranges::kWorldMaxSpeed, "WorldDef.max_speed");
  require_in(def.max_distance, ranges::kWorldMaxDistance, "WorldDef.max_distance");
}

}  // namespace detail

// ---------------------------------------------------------------------------------------------
// World

World::World(const WorldDef& def) : impl_(std::make_unique<Impl>()) {
  detail::validate(def);
  if (def.threads < 0) throw std::invalid_argument("WorldDef.threads must be >= 0 (0 = hardware)");
  impl_->def = def;
  impl_->dyn.allow_sleeping = def.allow_sleeping;
  impl_->dyn.continuous = def.continuous_collision;
  impl_->threads = def.threads > 0 ? def.threads
                                   : std::max(1, int(std::thread::hardware_concurrency()));
}

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

std::uint64_t World::removed_inside_count(ParticleSystemHandle h) const {
  return impl_->systems[h.id].removed_inside;
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
  // Random streams are keyed by the registration serial: the index in a world without removals.
  const std::uint64_t index = impl_->systems.next_serial();
  detail::ParticleSystemState ps;
  ps.def = def;
  ps.store.track_prev = def.collide && def.integrator != Integrator::semi_implicit_euler;
  ps.store.has_charge = def.charge.mean != 0.0 || def.charge.deviation != 0.0;
  ps.store.track_rest = def.collide_particles || !def.collision_group.empty();
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
  ps.forces.drag_quadratic = float(def.drag_quadratic);
  ps.forces.max_speed = float(impl_->def.max_speed);
  ps.forces.max_distance = float(impl_->def.max_distance);
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
  // Fields for every system, in registration order (the order their forces are summed in).
  std::vector<std::pair<std::uint64_t, detail::FieldState*>> all;
  for (std::size_t f = 0; f < impl_->fields.size(); ++f)
    if (impl_->fields.at(f).all_systems && impl_->fields.at(f).state->def.particles &&
        impl_->fields.at(f).state->def.kind != FieldKind::blast)
      all.emplace_back(impl_->fields.serial(f), impl_->fields.at(f).state.get());
  std::sort(all.begin(), all.end());
  for (const auto& [serial, f] : all) ps.dynamics.fields.push_back(f);
  return ParticleSystemHandle{impl_->systems.add(std::move(ps))};
}

std::uint64_t World::spawn_particle(ParticleSystemHandle h, const Vec3& position,
                                    const Vec3& velocity, double mass, double radius,
                                    double lifetime) {
  detail::ParticleSystemState& ps = impl_->systems[h.id];
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

ForceFieldHandle World::add_force_field(const ForceFieldDef& def) {
  detail::validate(def);
  for (const ParticleSystemHandle& h : def.systems) (void)impl_->systems[h.id];
  auto f = std::make_unique<detail::FieldState>();
  f->def = def;
  f->def.axis = def.axis.normalized();
  // Noise keyed by the registration serial (+ 1): the field count in a world without removals.
  f->noise = detail::GradientNoise(impl_->def.seed ^
                                   (0x9E3779B97F4A7C15ULL * (impl_->fields.next_serial() + 1)));
  f->pose_at(impl_->time);
  for (std::size_t s = 0; s < impl_->systems.size(); ++s) {
    // A blast is not an acceleration: it is applied once, as an impulse, by the integration
    // stage (stage_integrate.cpp), which finds it in the field table.
    const bool accelerates = def.particles && def.kind != FieldKind::blast;
    bool applies = def.systems.empty() && accelerates;
    for (const ParticleSystemHandle& h : def.systems)
      applies = applies || (h.id == impl_->systems.handle(s) && accelerates);
    if (applies) impl_->systems.at(s).dynamics.fields.push_back(f.get());
  }
  detail::FieldEntry e;
  e.state = std::move(f);
  e.all_systems = def.systems.empty();
  return ForceFieldHandle{impl_->fields.add(std::move(e))};
}

AttractorSpringHandle World::add_attractor_spring(const AttractorSpringDef& def) {
  detail::ParticleSystemState& ps = impl_->systems[def.system.id];
  detail::validate(def);
  auto a = std::make_unique<AttractorSpringDef>(def);
  ps.attractors.push_back(a.get());
  return AttractorSpringHandle{impl_->attractors.add(std::move(a))};
}

void World::add_spring(ParticleSystemHandle h, const SpringDef& spring) {
  detail::ParticleSystemState& ps = impl_->systems[h.id];
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

void World::add_sub_emitter(ParticleSystemHandle parent, const SubEmitterDef& def) {
  detail::ParticleSystemState& ps = impl_->systems[parent.id];
  (void)impl_->systems[def.system.id];  // throws std::out_of_range on a stale target
  if (def.count < 1 || def.count > 1'000'000 || !(def.probability >= 0.0 && def.probability <= 1.0) ||
      !(def.inherit_velocity >= 0.0 && def.inherit_velocity <= 1.0)) {
    std::ostringstream m;
    m << "World::add_sub_emitter: count must be in [1, 10^6], probability and inherit_velocity in "
      << "[0, 1] (got " << def.count << ", " << def.probability << ", " << def.inherit_velocity << ")";
    throw std::invalid_argument(m.str());
  }
  ps.sub_emitters.push_back(def);
}

std::uint64_t World::integrator_steps(ParticleSystemHandle h) const {
  return impl_->systems[h.id].integrator_state.substeps;
}
std::uint64_t World::rejected_steps(ParticleSystemHandle h) const {
  return impl_->systems[h.id].integrator_state.rejected;
}

ParticleView World::particles(ParticleSystemHandle h) const { return impl_->systems[h.id].store.view(); }

const ParticleSystemDef& World::definition(ParticleSystemHandle h) const {
  return impl_->systems[h.id].def;
}

double World::time() const { return impl_->time; }
std::uint64_t World::step_count() const { return impl_->steps; }

std::uint64_t World::emitted_count(ParticleSystemHandle h) const {
  return impl_->systems[h.id].next_id;
}

std::vector<ParticleSystemHandle> World::particle_systems() const {
  std::vector<ParticleSystemHandle> out;
  for (std::size_t i = 0; i < impl_->systems.size(); ++i)
    out.push_back(ParticleSystemHandle{impl_->systems.handle(i)});
  return out;
}

// ---------------------------------------------------------------------------------------------
// Cloth

ClothHandle World::add_cloth(const ClothDef& def) {
  // Gust noise keyed by the registration serial: the cloth index in a world without removals.
  return ClothHandle{impl_->cloths.add(Cloth(def, impl_->def.seed, impl_->cloths.next_serial()))};
}

ClothView World::cloth(ClothHandle h) const { return impl_->cloths[h.id].view(); }
ClothStats World::cloth_stats(ClothHandle h) const { return impl_->cloths[h.id].stats(); }
const ClothDef& World::definition(ClothHandle h) const { return impl_->cloths[h.id].definition(); }

std::vector<ClothHandle> World::cloths() const {
  std::vector<ClothHandle> out;
  for (std::size_t i = 0; i < impl_->cloths.size(); ++i)
    out.push_back(ClothHandle{impl_->cloths.handle(i)});
  return out;
}

}  // namespace simreel::sim
