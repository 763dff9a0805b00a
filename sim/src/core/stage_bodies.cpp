// Stage "bodies" (stages.hpp): where dynamic bodies will be simulated (forces, broad and narrow
// phase, contact and joint solve, integration; sim/src/rigid/README.md). World::add_body rejects
// dynamic bodies until then, so there is nothing to do.
#include "core/stages.hpp"

namespace simreel::sim::detail {

void stage_bodies(WorldState& /*w*/, double /*t0*/, double /*t1*/) {}

}  // namespace simreel::sim::detail
