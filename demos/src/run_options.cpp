#include "run_options.hpp"

#include <cstdio>
#include <stdexcept>

namespace simreel::app {

std::pair<int, int> parse_frames(const std::string& text) {
  int a = 0, b = 0;
  char colon = 0, extra = 0;
  const int n = std::sscanf(text.c_str(), "%d%c%d%c", &a, &colon, &b, &extra);
  if (n == 1 && a >= 1 && text.find_first_not_of("0123456789") == std::string::npos) return {0, a};
  if (n == 3 && colon == ':' && a >= 0 && b > a && text.find_first_not_of("0123456789:") == std::string::npos)
    return {a, b};
  throw SceneError("--frames " + text + ": expected a count N >= 1 or a range A:B with 0 <= A < B");
}

Scene prepare_scene(const RunOptions& o, int* first) {
  Scene scene = load_scene(o.scene, o.overrides);
  if (first != nullptr) *first = 0;
  if (o.frames) {
    const auto [a, b] = parse_frames(*o.frames);
    if (first != nullptr) *first = a;
    scene.frames = b;
  }
  if (o.fps) {
    if (!(*o.fps > 0.0 && *o.fps <= 1000.0))
      throw SceneError("--fps " + std::to_string(*o.fps) + ": expected a number in (0, 1000]");
    scene.fps = *o.fps;
  }
  if (o.seed) {
    if (*o.seed < 0) throw SceneError("--seed " + std::to_string(*o.seed) + ": expected an integer >= 0");
    scene.seed = std::uint64_t(*o.seed);
  }
  if (o.size) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(o.size->c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') || w < 16 ||
        h < 16 || w > 8192 || h > 8192)
      throw SceneError("--size " + *o.size + ": expected WIDTHxHEIGHT with each in [16, 8192], e.g. 1280x720");
    scene.render.width = w;
    scene.render.height = h;
  }
  if (o.backend) {
    try {
      scene.backend = render::parse_backend(*o.backend);
    } catch (const std::invalid_argument&) {
      throw SceneError("--backend " + *o.backend + ": expected osmesa or egl");
    }
  }
  return scene;
}

}  // namespace simreel::app
