// Loads a scene, steps it to a frame and renders that frame to a PNG, through the installed
// simreel package (find_package(simreel), target simreel::scene).
// Usage: first_frame SCENE.json FRAME OUT.png
#include <cstdlib>
#include <iostream>
#include <string>

#include <simreel/render/image.hpp>
#include <simreel/scene/json_reader.hpp>  // SceneError
#include <simreel/scene/scene.hpp>
#include <simreel/scene/scene_player.hpp>

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: first_frame SCENE.json FRAME OUT.png\n";
    return 2;
  }
  try {
    simreel::app::Scene scene = simreel::app::load_scene(argv[1], {"/render/width=160", "/render/height=90"});
    simreel::app::ScenePlayer player(scene);
    player.advance_to(std::atoi(argv[2]));
    const simreel::render::Image image = player.render();
    simreel::render::write_png(argv[3], image);
    std::cout << "wrote " << argv[3] << " (" << image.width << "x" << image.height << ", "
              << player.context().renderer_string() << ")\n";
  } catch (const simreel::app::SceneError& e) {
    std::cerr << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}
