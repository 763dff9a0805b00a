// Stage "births and deaths" (stages.hpp): sub-emitters fired by the step's deaths, splits
// (§3.9.1), removal of the dead, the step's newborns (each moves and collides only for its own age, so jets show no banding), colours and
// sizes over lifetime (§3.8).
#include <algorithm>

#include "core/stages.hpp"
#include "particles/split.hpp"

namespace simreel::sim::detail {

namespace {

/// Sub-emitters (SubEmitterDef): every system's deaths of this step, found before anything is
/// removed, handed to the target systems as SubBirths (consumed below in the same stage, so a
/// target earlier in the list gets them in the same step as one later). Nothing is done, and
/// nothing drawn, in a world without sub-emitters.
void collect_sub_births(WorldState& w, double h) {
  bool any = false;
  for (ParticleSystemState& ps : w.systems.dense()) {
    ps.sub_births.clear();
    any |= !ps.sub_emitters.empty();
  }
  if (!any) return;
  for (ParticleSystemState& ps : w.systems.dense()) {
    const ParticleStore& st = ps.store;
    for (const SubEmitterDef& se : ps.sub_emitters) {
      if (!w.systems.contains(se.system.id)) continue;  // its target was removed
      ParticleSystemState& target = w.systems[se.system.id];
      for (std::size_t i = 0; i < ps.n_old; ++i) {
        if (st.age[i] < st.lifetime[i]) continue;  // alive
        if (!se.split_children && st.from_split[i] != 0) continue;
        if (se.probability < 1.0 && !(target.emitter.rng.uniform() < se.probability)) continue;
        // It died o seconds before the end of the step, at x1 - v1 o.
        const double o = std::clamp(double(st.age[i]) - double(st.lifetime[i]), 0.0, h);
        SubBirth b;
        for (int k = 0; k < 3; ++k) {
          const double v = st.velocity[3 * i + std::size_t(k)];
          b.position[k] = double(st.position[3 * i + std::size_t(k)]) - v * o;
          b.velocity[k] = se.inherit_velocity * v;
        }
        b.age = o;
        b.count = se.count;
        target.sub_births.push_back(b);
      }
    }
  }
}

}  // namespace

void stage_births_and_deaths(WorldState& w, double t0, double t1) {
  const double h = t1 - t0;
  const bool any_collider = !w.shapes.empty();
  collect_sub_births(w, h);
  // A system of sleeping particles that lost some (lifetime, a kill, a split) wakes with its
  // collision group: a sleeper may have rested on one that is gone.
  std::vector<bool> lost(w.systems.size(), false);
  bool any_lost = false;
  for (std::size_t index = 0; index < w.systems.size(); ++index) {
    ParticleSystemState& ps = w.systems.at(index);
    ParticleStore& st = ps.store;
    // Particle split (§3.9.1): parents whose condition is met create their children.
    split_particles(ps.def.emitter, ps.split_rng, st, ps.n_old, ps.next_id);
    if (st.compact(0) > 0 && st.track_rest) any_lost = lost[index] = true;

    // Particles born in (t0, t1].
    const std::size_t first_new = emit(ps.def.emitter, ps.emitter, st, t0, t1, ps.next_id);
    // Sub-emitter births follow the emitter's own: newborns alike from here on.
    if (!ps.sub_births.empty()) emit_sub(ps.def.emitter, ps.emitter, st, ps.sub_births, ps.next_id);
    if (st.has_charge)
      for (std::size_t i = first_new; i < st.count; ++i)
        st.charge[i] = float(ps.charge_rng.normal(ps.def.charge.mean, ps.def.charge.deviation));
    bool bad = false;
    if (ps.general && first_new < st.count) {
      // A newborn moves alone for its partial step: external forces only (gravity, drag,
      // fields); springs, pair forces and attractor springs act on it from the next step.
      w.build_dynamics(index, false);
      IntegratorState scratch;
      for (std::size_t i = first_new; i < st.count; ++i)
        bad |= integrate_system(st, i, i + 1, t1 - double(st.age[i]), double(st.age[i]),
                                ps.dynamics, ps.def.integrator, ps.def.tolerance, scratch,
                                ps.workspace, false);
    } else {
      for (std::size_t i = first_new; i < st.count; ++i)
        bad |= integrate_one(st, i, st.age[i], ps.forces, ps.def.integrator);
    }
    if (bad) w.non_finite(index, first_new, st.count, t1);
    if (ps.def.collide && any_collider) w.collide_system(index, first_new, st.count, h);
    ps.gradient.apply(st, first_new, st.count);
    st.compact(first_new);  // lifetimes shorter than the part of the step they lived

    // Colour over lifetime.
    if (!ps.gradient.constant()) ps.gradient.apply(st, 0, first_new);

    // Emitter curves: brightness variation on freshly written colours, size over lifetime.
    if (ps.def.emitter.color_deviation > 0.0)
      apply_tint(st, ps.gradient.constant() ? first_new : 0, st.count);
    if (!ps.size_curve.empty()) ps.size_curve.apply(st, 0, st.count);
  }
  if (any_lost) wake_systems(w, lost);
}

}  // namespace simreel::sim::detail
