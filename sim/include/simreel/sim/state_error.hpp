#pragma once
/// @file state_error.hpp
/// The error of World::load_state: the bytes are not a state of this world (truncated, written
/// by another format or build, or for a scene with other objects). The message says what differs.

#include <stdexcept>

namespace simreel::sim {

class StateError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace simreel::sim
