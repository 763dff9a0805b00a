#include "scene_player.hpp"

#include "scene_list_builder.hpp"

namespace simreel::app {

ScenePlayer::ScenePlayer(const Scene& scene)
    : scene_(scene),
      sw_(build_world(scene)),
      context_(render::create_context(scene.backend)),
      renderer_(*context_, scene.render) {
  // Camera and light before the drawables, as the renderer has always received them.
  renderer_.set_camera(scene.camera);
  renderer_.set_light(scene.light);
  renderer_.apply(initial_scene_list(scene_, sw_));
}

void ScenePlayer::advance_to(int frame) {
  const double dt = 1.0 / scene_.fps;
  for (; frame_ < frame; ++frame_) {
    list_.clear();
    append_moved(sw_.world.advance(dt), list_);
    renderer_.apply(list_);
  }
}

void ScenePlayer::restore(int frame, std::string_view state) {
  sw_.world.load_state(state);
  list_.clear();
  // Every moving body's pose: the renderer may still show another frame's (set_transform
  // replaces, so this is exactly the state a straight run leaves). Static bodies never move.
  append_moved(sw_.world.poses(), list_);
  renderer_.apply(list_);
  frame_ = frame;
}

render::Image ScenePlayer::render() {
  list_.clear();
  append_frame(scene_, sw_, double(frame_) / scene_.fps, list_);
  renderer_.apply(list_);
  return renderer_.render();
}

}  // namespace simreel::app
