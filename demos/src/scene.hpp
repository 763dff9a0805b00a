#pragma once
/// @file scene.hpp
/// Scene files: JSON -> checked definitions -> a sim::World and the renderer's drawables.
/// The format is documented key by key in README.md ("Scene format").

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <memory>
#include <nlohmann/json.hpp>

#include "simreel/assets/mesh.hpp"
#include "simreel/render/camera_path.hpp"
#include "simreel/render/context.hpp"
#include "simreel/render/renderer.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::app {

/// A dynamic collider's keys (colliders[i] "motion": "dynamic"; README "Rigid bodies").
struct DynamicScene {
  bool enabled = false;
  double density = 1000.0;  ///< (kg/m³)
  double mass = 0.0;        ///< (kg) > 0 overrides the density's mass; 0 = from the density
  sim::Vec3 velocity = sim::Vec3::Zero();          ///< (m/s) world
  sim::Vec3 angular_velocity = sim::Vec3::Zero();  ///< (rad/s) world (JSON in deg/s)
  double linear_damping = 0.0;                     ///< (1/s)
  double angular_damping = 0.0;                    ///< (1/s)
  double drag_coefficient = 1.0;                   ///< C_d of the air drag (BodyDef)
  double drag_area = 0.0;                          ///< (m²) 0: a quarter of the surface area
  sim::Vec3 gravity{0.0, 0.0, -9.81};              ///< (m/s²) the scene's "simulation"/"gravity"
};

struct ColliderScene {
  std::string name;
  enum class Type { plane, box, sphere, cylinder, mesh } type = Type::plane;
  sim::PlaneDef plane;
  sim::BoxDef box;
  sim::SphereDef sphere;
  sim::CylinderDef cylinder;
  sim::MeshDef mesh;  ///< vertices already scaled, in the mesh's local frame
  /// The imported file (positions unscaled, normals, UVs, materials) for drawing; `scale`
  /// below maps it to the collider's local frame.
  std::shared_ptr<const assets::TriangleMesh> mesh_asset;
  std::array<double, 3> mesh_scale{1, 1, 1};
  render::Vec4f color{0.6f, 0.6f, 0.62f, 1.f};
  float checker_m = 0.f;        ///< (m) plane checker cell; 0 = plain
  float draw_half_size = 20.f;  ///< (m) drawn extent of an infinite plane
  DynamicScene dynamic;         ///< "motion": "dynamic" (box, sphere, cylinder)
};

struct EmitterScene {
  sim::ParticleSystemDef system;
  render::ParticleStyle style = render::ParticleStyle::soft;
  float streak_s = 0.02f;  ///< (s) streak length per unit speed (render_style "streak")
};

/// A force field with the names of the systems (emitters) it acts on (empty = all).
struct ForceFieldScene {
  sim::ForceFieldDef def;
  std::vector<std::string> systems;
};

/// An attractor spring pulling particles of the named system.
struct AttractorSpringScene {
  sim::AttractorSpringDef def;
  std::string system;
};

/// A cloth (Coutinho §3.9.2) and how it is drawn. README "cloths[i]".
struct ClothScene {
  sim::ClothDef def;
  render::Vec4f color{0.75f, 0.12f, 0.12f, 1.f};
  float checker_m = 0.f;  ///< (m) checker cell on the cloth's UVs; 0 = plain
};

/// A loaded, checked scene. Every value is in engine units (SI, radians) except where named.
struct Scene {
  std::string file;  ///< path as given, used in messages
  std::uint64_t seed = 0;
  double fps = 30.0;  ///< frames per second; the sampling time is 1/fps
  int frames = 120;
  sim::WorldDef world;
  render::Backend backend = render::Backend::osmesa;
  render::RenderSettings render;
  render::Camera camera;
  render::CameraMotion camera_motion;  ///< camera.path / camera.orbit; base == camera
  render::Light light;
  std::vector<ColliderScene> colliders;
  std::vector<EmitterScene> emitters;
  std::vector<ForceFieldScene> force_fields;
  std::vector<AttractorSpringScene> attractor_springs;
  std::vector<ClothScene> cloths;
};

/// Turns a parsed document into a Scene, checking every key. @throws SceneError listing every
/// problem (file, JSON pointer, found, expected).
Scene scene_from_json(const nlohmann::json& doc, const std::string& file);

/// Reads `path`, applies `--set` overrides in order, then checks. @throws SceneError.
Scene load_scene(const std::filesystem::path& path, const std::vector<std::string>& overrides = {});

/// The simulation built from a scene, with the handle of each collider and emitter in scene order.
struct SceneWorld {
  sim::World world;
  std::vector<sim::ColliderHandle> colliders;
  std::vector<sim::ParticleSystemHandle> systems;
  std::vector<sim::ClothHandle> cloths;
  std::vector<sim::ForceFieldHandle> force_fields;            ///< scene order
  std::vector<sim::AttractorSpringHandle> attractor_springs;  ///< scene order
};

/// The engine body of a `"motion": "dynamic"` collider (`c.dynamic.enabled`; box, sphere or
/// cylinder): one shape of the collider's geometry and response material at an identity offset,
/// pose from the collider, density or mass, velocities (rad/s), damping and the scene's gravity.
/// @throws std::invalid_argument for a plane or mesh (the loader never produces one).
sim::BodyDef dynamic_body_def(const ColliderScene& c);

/// @throws SceneError if the engine rejects a definition (should not happen after checking).
SceneWorld build_world(const Scene& scene);

}  // namespace simreel::app
