// Stage "kinematic poses" (stages.hpp).
#include "core/stages.hpp"

namespace simreel::sim::detail {

void stage_kinematic_poses(WorldState& w, double /*t0*/, double t1) {
  for (Collider& c : w.colliders.dense())
    if (c.kinematic()) c.update(t1);
}

}  // namespace simreel::sim::detail
