#pragma once
// Validation of definitions before registration (private). Each function throws
// std::invalid_argument with a message naming the field, the value found and what is expected.

#include <string>

#include "simreel/sim/types.hpp"
#include "simreel/sim/keyframes.hpp"
#include "simreel/sim/particle_system.hpp"
#include "simreel/sim/ranges.hpp"
#include "simreel/sim/world_def.hpp"

namespace simreel::sim::detail {

void validate(const WorldDef& def);
void validate(const ParticleSystemDef& def);
/// `what` names the path in messages, e.g. "BoxDef.path".
void validate(const KeyframePath& path, const std::string& what);
void validate(const Material& m, const std::string& what);

}  // namespace simreel::sim::detail
