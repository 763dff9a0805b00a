// Stage "cloth" (stages.hpp): every cloth steps (Coutinho §3.9.2) against the colliders at their
// end-of-step pose; then particles collide with the cloths (issue 6), both having moved over
// [t0, t1], each contact's impulse shared by the triangle's vertices (cloth_particles.hpp).
#include <sstream>

#include "core/stages.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim::detail {

void stage_cloth(WorldState& w, double t0, double t1) {
  std::vector<Cloth>& cloths = w.cloths.dense();
  for (std::size_t c = 0; c < cloths.size(); ++c) {
    if (cloths[c].step(t0, t1, &w.shapes, coupling_log(w), w.threads)) continue;
    std::ostringstream m;
    m.precision(9);
    m << "cloth '" << cloths[c].definition().name << "' (index " << c
      << "): non-finite vertex state at internal step " << w.steps + 1 << ", t = " << t1 << " s";
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
