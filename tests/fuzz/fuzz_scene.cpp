/// @file fuzz_scene.cpp
/// Fuzz target for the scene loader: the input bytes are parsed as JSON text and built into a
/// Scene. The loader's own errors (SceneError for bad scenes, AssetError for mesh files) are the
/// expected outcome of bad input; anything else escaping (a std::invalid_argument from the sim
/// layer means a range the loader did not check), or any sanitizer report, is a bug.
///
/// Built two ways (tests/fuzz/CMakeLists.txt): with clang and -DSIMREEL_FUZZ=ON as a libFuzzer
/// binary; with any compiler as a replay driver (SIMREEL_FUZZ_REPLAY) whose main() runs every
/// file or directory named on the command line through the same function, once.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "json_reader.hpp"
#include "scene.hpp"
#include "simreel/assets/mesh.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto doc = simreel::app::parse_json_text(text, "fuzz.json");
    (void)simreel::app::scene_from_json(doc, "fuzz.json");
  } catch (const simreel::app::SceneError&) {
  } catch (const simreel::assets::AssetError&) {
  }
  return 0;
}

#ifdef SIMREEL_FUZZ_REPLAY
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

int main(int argc, char** argv) {
  std::vector<std::filesystem::path> files;
  for (int i = 1; i < argc; ++i) {
    const std::filesystem::path arg(argv[i]);
    if (std::filesystem::is_directory(arg)) {
      for (const auto& e : std::filesystem::directory_iterator(arg))
        if (e.is_regular_file()) files.push_back(e.path());
    } else {
      files.push_back(arg);
    }
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  }
  std::printf("fuzz_scene_replay: %zu inputs, no crash\n", files.size());
  return 0;
}
#endif
