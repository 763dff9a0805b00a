#pragma once
// World::Impl is the world's state (world_state.hpp); only core/ sees it.

#include "core/world_state.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {

struct World::Impl : detail::WorldState {};

}  // namespace simreel::sim
