#pragma once
// Private: finding ffmpeg and asking it what it can encode (the video sink and the tests' skips).

#include <filesystem>
#include <string>

namespace simreel::render::detail {

/// Searches PATH the way execvp does; empty when `program` is not found.
std::filesystem::path find_on_path(const std::string& program);

}  // namespace simreel::render::detail
