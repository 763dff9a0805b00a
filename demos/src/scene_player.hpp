#pragma once
/// @file scene_player.hpp
/// The simulation and the renderer of one scene, stepped frame by frame in order. It owns the GL
/// context and the renderer; everything it tells the renderer goes through a render::SceneList
/// built by scene_list_builder.hpp (the GL-free half, tested without a context).

#include <memory>
#include <string_view>

#include "scene.hpp"
#include "simreel/render/context.hpp"
#include "simreel/render/renderer.hpp"
#include "simreel/render/scene_list.hpp"

namespace simreel::app {

class ScenePlayer {
 public:
  /// Builds the world, creates the scene's context (backend) and renderer, and adds every
  /// collider and cloth. `scene` must outlive the player.
  /// @throws SceneError (engine rejects a definition), render::ContextError (no context).
  explicit ScenePlayer(const Scene& scene);

  /// Steps the simulation until it shows frame `frame` (t = frame / fps); frame 0 is the
  /// initial state. Moved colliders reach the renderer at every step, drawn or not.
  /// A frame at or before the current one does nothing (the player only goes forward).
  void advance_to(int frame);

  /// Jumps to frame `frame` by loading its engine state (World::save_state bytes of the same
  /// scene, e.g. from a `simreel bake` cache) instead of simulating, and gives the renderer every
  /// moving body's pose: the next render() draws exactly what a player advanced to `frame` would.
  /// Frames may be restored in any order. @throws sim::StateError when the state does not fit.
  void restore(int frame, std::string_view state);

  /// Draws the current frame: particles, cloth vertices and the camera at the frame's time.
  render::Image render();

  [[nodiscard]] const render::Context& context() const { return *context_; }

 private:
  const Scene& scene_;
  SceneWorld sw_;
  std::unique_ptr<render::Context> context_;
  render::Renderer renderer_;
  render::SceneList list_;  ///< reused for every list so a run does not allocate per frame
  int frame_ = 0;
};

}  // namespace simreel::app
