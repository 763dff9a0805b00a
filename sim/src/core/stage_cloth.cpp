// Stage "cloth" (stages.hpp): every cloth steps (Coutinho §3.9.2) against the colliders at their
// end-of-step pose; then particles collide with the cloths (issue 6), both having moved over
// [t0, t1], each contact's impulse shared by the triangle's vertices (cloth_particles.hpp).
#include <sstream>

#include "core/stages.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim::detail {

/// The first vertex of `cloth` with a coordinate beyond def.max_distance or a velocity component
/// beyond def.max_speed, or its vertex count. The particles' divergence bounds: a cloth torn
/// kilometres apart by a blow-up is finite, but its triangles' swept boxes then all overlap and
/// the contact rounds below test every pair of them, minutes a step (a state with one vertex
/// moved 6 km ran past 10 minutes for two frames), instead of stopping the run.
static std::size_t beyond_bounds(const Cloth& cloth, const WorldDef& def) {
  const std::vector<Vec3>& x = cloth.positions();
  const std::vector<Vec3>& v = cloth.velocities();
  for (std::size_t i = 0; i < x.size(); ++i)
    if (!(x[i].cwiseAbs().maxCoeff() <= def.max_distance && v[i].cwiseAbs().maxCoeff() <= def.max_speed))
      return i;
  return x.size();
}

void stage_cloth(WorldState& w, double t0, double t1) {
  std::vector<Cloth>& cloths = w.cloths.dense();
  for (std::size_t c = 0; c < cloths.size(); ++c) {
    const bool finite = cloths[c].step(t0, t1, &w.shapes, coupling_log(w), w.threads);
    const std::size_t far = finite ? beyond_bounds(cloths[c], w.def) : 0;
    if (finite && far == cloths[c].positions().size()) continue;
    std::ostringstream m;
    m.precision(9);
    m << "cloth '" << cloths[c].definition().name << "' (index " << c << "): ";
    if (finite) {
      const Vec3& x = cloths[c].positions()[far];
      const Vec3& v = cloths[c].velocities()[far];
      m << "diverged (vertex " << far << " at |x| = " << x.norm() << " m, |v| = " << v.norm()
        << " m/s; bounds simulation.max_distance = " << w.def.max_distance
        << " m, simulation.max_speed = " << w.def.max_speed << " m/s per component)";
    } else {
      m << "non-finite vertex state";
    }
    m << " at internal step " << w.steps + 1 << ", t = " << t1 << " s";
    throw NonFiniteState(m.str());
  }
  // Self-collision and cloth–cloth contacts once every cloth has moved (issue 16).
  if (!cloths.empty())
    collide_cloths(cloths, w.shapes, t1 - t0, w.cloth_contact_scratch, coupling_log(w));
  for (Cloth& cloth : cloths) {
    if (!cloth.definition().collide_particles) continue;
    for (ParticleSystemState& ps : w.systems.dense())
      if (ps.def.collide) collide_particles_with_cloth(ps.store, t1 - t0, cloth, w.cloth_scratch);
  }
}

}  // namespace simreel::sim::detail
