#pragma once
/// @file commands.hpp
/// The subcommands of the `simreel` program. Each returns the process exit code:
/// 0 ok, 1 runtime failure, 2 bad input or usage. Exceptions are mapped in main.cpp.

#include <optional>
#include <string>
#include <vector>

namespace simreel::app {

/// Options shared by commands that load and run a scene.
struct RunOptions {
  std::string scene;
  std::vector<std::string> overrides;  ///< --set POINTER=VALUE, applied in order
  std::optional<int> frames;
  std::optional<double> fps;
  std::optional<std::string> size;     ///< "WxH"
  std::optional<long long> seed;
  std::optional<std::string> backend;  ///< "osmesa" | "egl"
};

struct RenderOptions : RunOptions {
  std::vector<std::string> outputs;  ///< directories (PNG) or .mp4/.gif files; default out/<stem>/ + out/<stem>.mp4
  int png_compression = 4;
  int crf = 18;
  bool quiet = false;
};

int render_command(const RenderOptions& options);
int simulate_command(const RunOptions& options, const std::string& export_csv);
int validate_command(const std::string& scene, const std::vector<std::string>& overrides);
int hash_command(const std::vector<std::string>& images, const std::string& algorithm);

}  // namespace simreel::app
