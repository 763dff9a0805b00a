#pragma once
/// @file scene_list_builder.hpp
/// The sim -> render glue without GL (DESIGN.md "The handle/transform interface", Coutinho
/// §1.4.1): turns a Scene, its SceneWorld and what World::advance() returns into plain-data
/// render::SceneLists. ScenePlayer (scene_player.hpp) applies them to a renderer; tests read
/// them with no context at all.
///
/// Keys are the engine handles' `packed()` values: a collider's drawable, a particle system's
/// batch and a cloth's mesh all carry the key of the object they show.
///
/// Order matters for byte-identical frames: the renderer must receive its calls in the order it
/// always did. The lists keep scene order (colliders, then cloths; systems in emitter order) and
/// Renderer::apply() replays them in its fixed order (added, moved, removed, particles, meshes,
/// camera).

#include <span>

#include "scene.hpp"
#include "simreel/render/scene_list.hpp"

namespace simreel::app {

/// The renderer's mesh for a mesh collider: the imported file scaled to the collider's local
/// frame (positions (n x 3) m, normals (n x 3) renormalised after the inverse scale, UVs
/// (n x 2)), drawn double-sided in the collider's colour; the file's first texture if any.
/// Precondition: `c.type == mesh` and `c.mesh_asset` set (the loader guarantees both).
render::MeshDesc mesh_desc(const ColliderScene& c);

/// The list that builds the scene in an empty renderer: one `added` per collider (scene order;
/// plane, box or mesh desc; the pose World::pose() reports, except planes, which are given in
/// the world frame and have `has_transform == false`), then one per cloth (a dynamic
/// double-sided mesh in the world frame, UVs in metres, `has_transform == false`).
/// The camera and the light are not in it: ScenePlayer sets them before applying it, as the
/// renderer always received them. Reads `sw` once; nothing in the list points into the world.
render::SceneList initial_scene_list(const Scene& scene, const SceneWorld& sw);

/// Appends what one World::advance() reported: each entry becomes a `moved` pose (float copy
/// of translation (m, world frame) and rotation (local-to-world)), in the engine's order; an
/// entry with `removed` set becomes a `removed` key (bodies, particle systems and cloths: the
/// renderer drops the drawable; removed force fields and springs have none and are skipped).
void append_moved(std::span<const sim::MovedObject> moved, render::SceneList& out);

/// Appends the state drawn at time `t` (s): one particle batch per system in emitter order
/// (views into the world's current particle arrays with the emitter's render style and streak
/// length), one vertex update per cloth (spans of 3 x vertex_count floats: positions (m) and
/// normals, world frame) and the camera at `t` (render::camera_at on the scene's motion).
/// The views are valid until the world advances again.
void append_frame(const Scene& scene, const SceneWorld& sw, double t, render::SceneList& out);

}  // namespace simreel::app
