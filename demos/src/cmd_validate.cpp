// `simreel validate`: load and check a scene (the loader, then the engine's own checks).
#include <iostream>

#include "commands.hpp"
#include "scene.hpp"

namespace simreel::app {

int validate_command(const std::string& scene_path, const std::vector<std::string>& overrides) {
  const Scene scene = load_scene(scene_path, overrides);
  (void)build_world(scene);
  std::cout << "ok\n";
  return 0;
}

}  // namespace simreel::app
