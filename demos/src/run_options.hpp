#pragma once
/// @file run_options.hpp
/// The command-line options shared by the commands that load and run a scene (RunOptions in
/// commands.hpp): --frames parsing and the overrides of scene values, checked as usage errors.

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>
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

/// Bytes of memory a scene needs, estimated up front (particles, cloth vertices, framebuffers
/// when rendering), and what each item is, naming its keys.
struct MemoryEstimate {
  std::uint64_t bytes = 0;
  std::vector<std::pair<std::string, std::uint64_t>> items;  ///< "/emitters/0/max_particles", bytes
};
MemoryEstimate estimate_memory(const Scene& scene, bool renders);

/// The budget: `option` (--memory-limit), else $SIMREEL_MEMORY_LIMIT, else half the physical
/// memory. "2G", "512M", "1500000000". @throws SceneError naming the source of a bad value.
std::uint64_t memory_limit(const std::optional<std::string>& option);

/// @throws SceneError naming the largest items' keys when the estimate exceeds the budget.
void check_memory(const Scene& scene, const RunOptions& o);

/// One output a command will write: the option that names it ("-o", "--hash"), the path, and
/// whether it is a folder (PNG frames, a report) rather than a file.
struct OutputPath {
  std::string option;
  std::string path;
  bool folder = false;
};

/// Usage check of a command's outputs before anything runs: a file must be a name the atomic
/// write can replace (render::unreplaceable_output: not a directory, device, FIFO or socket), a
/// folder must not be a file or device, and no two outputs may name the same path (two writers
/// racing to rename over one name). Empty paths are skipped.
/// @throws SceneError (exit 2) naming the option and the path.
void check_outputs(const std::vector<OutputPath>& outputs);

/// Loads the scene with its --set overrides, then applies --frames, --fps, --seed, --size and
/// --backend. `first` receives the first frame to output (frames before it are simulated only).
/// @throws SceneError (exit 2) naming the option or the scene key.
Scene prepare_scene(const RunOptions& o, int* first = nullptr);

}  // namespace simreel::app
