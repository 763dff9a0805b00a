#pragma once
/// @file run_options.hpp
/// The command-line options shared by the commands that load and run a scene (RunOptions in
/// commands.hpp): --frames parsing and the overrides of scene values, checked as usage errors.

#include <utility>
#include <string>

#include "commands.hpp"
#include "json_reader.hpp"
#include "scene.hpp"

// The build defines it (CMake: the project version); the fallback keeps a bare compile working.
#ifndef SIMREEL_VERSION
#define SIMREEL_VERSION "unknown"
#endif

namespace simreel::app {

/// --frames "N" or "A:B" -> [first, end). @throws SceneError.
std::pair<int, int> parse_frames(const std::string& text);

/// Loads the scene with its --set overrides, then applies --frames, --fps, --seed, --size and
/// --backend. `first` receives the first frame to output (frames before it are simulated only).
/// @throws SceneError (exit 2) naming the option or the scene key.
Scene prepare_scene(const RunOptions& o, int* first = nullptr);

}  // namespace simreel::app
