#pragma once
/// @file moved_object.hpp
/// MovedObject: one entry of the list World::advance() returns (Coutinho §1.4.1, the interface
/// with the rendering engine). Its own header so the engine's lower layers need not include
/// world.hpp.

#include "simreel/sim/handle.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim {

/// One entry of the moved list: the object's pose at the end of advance(), or its removal.
struct MovedObject {
  Handle handle;
  Vec3 translation = Vec3::Zero();      ///< (m), world frame
  Mat3 rotation = Mat3::Identity();     ///< local-to-world rotation
  /// True: the handle's object was removed (World::remove) since the last advance(); the handle
  /// is stale and translation/rotation are meaningless. Reported once, after the moved entries.
  bool removed = false;
};

}  // namespace simreel::sim
