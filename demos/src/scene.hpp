#pragma once
/// @file scene.hpp
/// Scene files: JSON -> checked definitions -> a sim::World and the renderer's drawables.
/// The format is documented key by key in README.md ("Scene format").

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <memory>
#include <optional>
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

/// A capsule collider or body (colliders[i] "type": "capsule"): the segment from -half_height to
/// +half_height along its local z axis grown by `radius` (sim::ShapeDef::capsule).
struct CapsuleScene {
  sim::Transform transform;   ///< centre (m) and rotation (local z = the capsule's axis)
  double radius = 0.25;       ///< (m) > 0
  double half_height = 0.5;   ///< (m) > 0: half the inner segment (total length 2 (half_height + radius))
  sim::Material material;
  sim::KeyframePath path;     ///< kinematic capsules
};

/// How one shape of a bodies[i] body is drawn: from its imported file (a "mesh" shape, or a
/// dynamic mesh's parts), else from its ShapeDef (primitives; a hull's own triangles).
struct BodyShapeDraw {
  std::shared_ptr<const assets::TriangleMesh> asset;  ///< the file, unscaled; null: from the ShapeDef
  std::array<double, 3> scale{1, 1, 1};               ///< applied to the asset's positions
  /// Draws nothing: the later parts of a dynamic mesh (its file is drawn once, with the first
  /// part's shape; all parts share the shape frame).
  bool skip = false;
  /// shapes[k].material's drawing keys, when given: the shape is drawn in its own linear RGBA
  /// colour and/or texture (a path) instead of the body's.
  std::optional<std::array<float, 4>> color;
  std::string texture;
};

struct ColliderScene {
  std::string name;
  /// `body`: an entry of bodies[i] (README "bodies[i]"), read into `body` (any body type, any
  /// number of shapes); the others: colliders[i].
  enum class Type { plane, box, sphere, cylinder, mesh, capsule, body } type = Type::plane;
  sim::BodyDef body;                    ///< Type::body: ready for World::add_body
  std::vector<BodyShapeDraw> body_draw;  ///< Type::body: one per body.shapes
  std::string texture;                  ///< Type::body: material.texture, a path (drawing only)
  std::string pointer;                  ///< Type::body: its JSON pointer ("/bodies/3"), for messages
  sim::PlaneDef plane;
  sim::BoxDef box;
  sim::SphereDef sphere;
  sim::CylinderDef cylinder;
  CapsuleScene capsule;
  sim::MeshDef mesh;  ///< vertices already scaled, in the mesh's local frame
  /// The imported file (positions unscaled, normals, UVs, materials) for drawing; `scale`
  /// below maps it to the collider's local frame.
  std::shared_ptr<const assets::TriangleMesh> mesh_asset;
  std::array<double, 3> mesh_scale{1, 1, 1};
  render::Vec4f color{0.6f, 0.6f, 0.62f, 1.f};
  /// The scene gave `color` (or material.color): a mesh file with several materials is then
  /// drawn in it; otherwise in the file's own materials.
  bool color_given = false;
  float checker_m = 0.f;        ///< (m) plane checker cell; 0 = plain
  float draw_half_size = 20.f;  ///< (m) drawn extent of an infinite plane
  /// "motion": "dynamic" (box, sphere, cylinder, capsule); for Type::body only `enabled` (a
  /// dynamic body) is set, the rest is in `body`.
  DynamicScene dynamic;
};

/// emitters[i].sub_emitters[k]: the engine definition without its target, which build_world
/// resolves from the emitter name.
struct SubEmitterScene {
  sim::SubEmitterDef def;
  std::string emitter;  ///< name of the target emitter (system)
  std::string pointer;  ///< its JSON pointer, for messages
};

struct EmitterScene {
  sim::ParticleSystemDef system;
  std::vector<SubEmitterScene> sub_emitters;
  render::ParticleStyle style = render::ParticleStyle::soft;
  float streak_s = 0.02f;  ///< (s) streak length per unit speed (render_style "streak")
  float trail_s = 0.f;     ///< (s) additive: glowing trail behind each particle, velocity x trail_s
  float emissive = 1.f;    ///< additive: colour multiplier (> 1 glows through the bloom pass)
  float strobe_hz = 0.f;   ///< additive: on/off flashes per second of each particle; 0 = steady
  float strobe_duty = 0.5f;  ///< additive: fraction of each strobe period a particle is lit
  render::ParticleTexture texture = render::ParticleTexture::none;
  /// The emitter moves with the camera: its `position` is an offset (world axes) from the
  /// camera's eye projected on the ground, (eye_x, eye_y, 0); build_world turns it into a path
  /// through the eye's ground point at every frame (follow_camera_path).
  bool follow_camera = false;
};

/// The path of an emitter that follows the camera (EmitterScene::follow_camera): a key at every
/// frame time k / fps, k = 0..frames (one key when the camera does not move), at
/// `pose.translation` + (eye_x, eye_y, 0) with the rotation of `pose`, linear in between.
sim::KeyframePath follow_camera_path(const render::CameraMotion& motion, double fps, int frames,
                                     const sim::Transform& pose);

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

/// A joint between two scene bodies (joints[i], or made by a chain or ragdoll generator;
/// Coutinho Ch. 5). README "joints[i]".
struct JointScene {
  /// Engine units (m, rad, N m s/rad, N); body_a / body_b are filled by build_world.
  sim::JointDef def;
  std::string body_a = "world";  ///< a collider's name or "world"
  std::string body_b = "world";
  /// Indices into Scene::colliders; kWorld = the static world.
  static constexpr std::size_t kWorld = std::size_t(-1);
  std::size_t index_a = kWorld;
  std::size_t index_b = kWorld;
};

/// A damped spring between two scene bodies' points or a body's point and the world (springs[i];
/// Coutinho §4.3.3). README "springs[i]".
struct BodySpringScene {
  sim::BodySpringDef def;  ///< engine units; body handles filled by build_world
  std::string body_a = "world", body_b = "world";
  std::size_t index_a = JointScene::kWorld, index_b = JointScene::kWorld;  ///< into colliders
};

/// What a generator (chains[i], ragdolls[i]) added: colliders [first_collider, +collider_count)
/// and joints [first_joint, +joint_count) of the Scene, for tests and messages.
struct GeneratedGroup {
  std::string kind;  ///< "chain" or "ragdoll"
  std::string name;
  std::size_t first_collider = 0, collider_count = 0;
  std::size_t first_joint = 0, joint_count = 0;
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
  /// joints[i] in file order after the joints of the generators (chains, then ragdolls).
  std::vector<JointScene> joints;
  std::vector<BodySpringScene> springs;  ///< springs[i], file order
  std::vector<GeneratedGroup> generated;  ///< chains, then ragdolls, in file order
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
  std::vector<sim::JointHandle> joints;                       ///< Scene::joints order
  std::vector<sim::BodySpringHandle> springs;                 ///< Scene::springs order
};

/// The engine body of a `"motion": "dynamic"` collider (`c.dynamic.enabled`; box, sphere or
/// cylinder, capsule): one shape of the collider's geometry and response material at an identity offset,
/// pose from the collider, density or mass, velocities (rad/s), damping and the scene's gravity.
/// @throws std::invalid_argument for a plane or mesh (the loader never produces one).
sim::BodyDef dynamic_body_def(const ColliderScene& c);

/// @throws SceneError if the engine rejects a definition (should not happen after checking).
SceneWorld build_world(const Scene& scene);

}  // namespace simreel::app
