// Stage "kinematic poses" (stages.hpp).
#include "core/stages.hpp"

namespace simreel::sim::detail {

void stage_kinematic_poses(WorldState& w, double /*t0*/, double t1) {
  for (Body& b : w.bodies.dense())
    if (b.kinematic()) b.move_to(t1, w.shapes);
}

}  // namespace simreel::sim::detail
