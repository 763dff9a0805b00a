#pragma once
/// @file scene_read.hpp
/// The scene loader's readers, one file per object kind (private to demos/; scene.hpp is the
/// API). Each reader takes the object's JSON, its pointer and the file, appends every problem to
/// `errors` (file, JSON pointer, found, expected) and returns the object read with defaults.
///   scene_values.cpp     shared value readers: distributions (Coutinho §3.8), keyframe paths
///   scene_camera.cpp     "render", "camera" (path / orbit), "light"
///   scene_colliders.cpp  "colliders" and their response materials (§3.6.1, §3.6.3)
///   scene_bodies.cpp     colliders' "motion" and the keys of a dynamic collider (Ch. 4)
///   scene_body_list.cpp  "bodies": bodies with shapes (compounds, convex hulls, meshes; Ch. 4)
///   scene_emitters.cpp   "emitters" (§3.8-3.9.1): shape, rate, distributions, colours, split
///   scene_forces.cpp     per-system forces and integrators, "force_fields", "attractor_springs"
///                        (§3.3, App. B)
///   scene_cloths.cpp     "cloths" (§3.9.2)
///   scene_joints.cpp     "joints" between named bodies (Ch. 5)
///   scene_generators.cpp "chains" and "ragdolls": expanded into dynamic colliders and joints
///   scene.cpp            scene_from_json (the top level, in file order), load_scene, build_world

#include <array>
#include <cstddef>
#include <filesystem>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "json_reader.hpp"
#include "scene.hpp"
#include "simreel/assets/mesh.hpp"

namespace simreel::app::scene_read {

/// The ranges written once for the loader and the engine (simreel/sim/ranges.hpp).
namespace ranges = sim::ranges;

inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr double kDeg = std::numbers::pi / 180.0;

inline sim::Vec3 to_vec(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }
inline render::Vec3f to_vec3f(const std::array<double, 3>& a) { return {float(a[0]), float(a[1]), float(a[2])}; }
inline render::Vec3f to_vec3f(const std::array<double, 4>& a) { return {float(a[0]), float(a[1]), float(a[2])}; }

/// rotation_deg = [rx, ry, rz]: rotations about the world x, then y, then z axes (R = Rz Ry Rx).
sim::Quat rotation_from_deg(const std::array<double, 3>& r);

/// "" if one frame (1 / fps s) takes at most sim::ranges::kMaxStepsPerAdvance internal steps of
/// at most max_step s (World::advance refuses more); otherwise what is wrong and how to fix it.
std::string steps_per_frame_problem(double fps, double max_step);

/// Reads an object member; reports and returns nullptr if present but not an object.
const json* object_member(ObjectReader& r, const std::string& key);

/// A parameter given as a number (no deviation), {"mean", "deviation", "min", "max"} (Coutinho
/// §3.8: mean + deviation, drawn from a normal distribution, clamped to [min, max]) or
/// {"min", "max"} alone: uniform on [min, max]. `unit` is named in messages.
sim::Distribution distribution(ObjectReader& r, const std::string& key, sim::Distribution fallback,
                               double min, double max, const std::string& unit);

/// {"loop", "smooth", "keys": [{"time" (s), "position" (m), "rotation_deg"}]}; empty if absent.
sim::KeyframePath keyframe_path(ObjectReader& r, const std::string& key);

/// A mesh file's "scale": one number for all axes or [sx, sy, sz], each > 0 (default 1).
std::array<double, 3> mesh_scale(ObjectReader& r);

/// The largest coordinate (m) a scaled mesh vertex may have: beyond it the renderer's and the
/// particles' 32-bit floats are infinite (a mesh scaled by 1e300 was accepted and vanished from
/// the frames while still colliding).
inline constexpr double kMaxScaledCoordinate = 3e38;

/// The largest light "color", "ambient" or "ground_ambient" component (1 is full intensity).
inline constexpr double kMaxLightIntensity = 1000.0;

/// False, with an error at r's "scale", when `scale` takes some vertex of `positions` (the mesh
/// file's, m) beyond kMaxScaledCoordinate on some axis.
bool scale_keeps_mesh_finite(ObjectReader& r, const std::array<double, 3>& scale,
                             const std::vector<Eigen::Vector3f>& positions);

/// "" when `path` is an image the renderer can draw as a texture (a regular file that
/// render::read_image decodes); otherwise why not (the file and the reader's reason).
std::string texture_problem(const std::filesystem::path& path);

/// False, with an error at r's `key`, when some material of the mesh file `path` (loaded as
/// `mesh`) names a texture that texture_problem() refuses: the renderer would stop on it after
/// the outputs were opened (exit 1, no pointer). Embedded textures ("*0", ...) are not read.
bool mesh_textures_readable(ObjectReader& r, const std::string& key, const std::filesystem::path& path,
                            const assets::TriangleMesh& mesh);

/// Calls each(object, pointer, index) for every element of the array r[key]; reports non-arrays
/// and non-object elements.
template <class F>
void object_array(ObjectReader& r, const std::string& key, F&& each) {
  const json* a = r.get(key);
  if (!a) return;
  if (!a->is_array()) {
    r.error(key, "an array of objects", *a);
    return;
  }
  for (std::size_t i = 0; i < a->size(); ++i) {
    const std::string p = r.pointer(key) + "/" + std::to_string(i);
    if (!(*a)[i].is_object()) {
      r.error_at(p, "expected an object, found " + describe((*a)[i]));
      continue;
    }
    each((*a)[i], p, i);
  }
}

// scene_camera.cpp: the top-level "render", "camera" and "light" objects, into `scene`.
void render_settings(ObjectReader& r, Scene& scene);
void camera(ObjectReader& r, Scene& scene);
void light(ObjectReader& r, Scene& scene);

// scene_colliders.cpp
/// colliders[i] "motion" and the dynamic keys (scene_bodies.cpp); `type` is the collider type.
void collider_motion(ObjectReader& r, const std::string& type, bool has_path, ColliderScene& c);

ColliderScene collider(const json& j, const std::string& ptr, const std::string& file,
                       std::vector<std::string>& errors, std::size_t index);
// scene_body_list.cpp
/// bodies[i] (Coutinho Ch. 4): a body of any type with one or more shapes; `gravity` (m/s²) is the
/// scene's, a dynamic body's.
ColliderScene body(const json& j, const std::string& ptr, const std::string& file, std::vector<std::string>& errors,
                   std::size_t index, const sim::Vec3& gravity);

/// An emitter's own "on_hit" and its droplets "on_hit_split" (the emitter's "split" key is the
/// §3.9.1 particle split).
sim::Material material_hit(ObjectReader& r);

// scene_emitters.cpp; `gravity` (m/s²) is the scene's, the default of the emitter's own.
EmitterScene emitter(const json& j, const std::string& ptr, const std::string& file,
                     std::vector<std::string>& errors, std::size_t index, const sim::Vec3& gravity);

// scene_forces.cpp
/// The emitter-object keys of the force and integrator half of a particle system.
void particle_forces(ObjectReader& r, sim::ParticleSystemDef& s);
ForceFieldScene force_field(const json& j, const std::string& ptr, const std::string& file,
                            std::vector<std::string>& errors);
AttractorSpringScene attractor_spring(const json& j, const std::string& ptr, const std::string& file,
                                      std::vector<std::string>& errors);

// scene_cloths.cpp
ClothScene cloth(const json& j, const std::string& ptr, const std::string& file,
                 std::vector<std::string>& errors, std::size_t index, const sim::Vec3& gravity);

// scene_joints.cpp (Coutinho Ch. 5)
/// joints[i]: type, body names (resolved against scene.colliders; "world" = the static world),
/// anchor, axis, limits (degrees in JSON, radians in the JointDef), damping, motor, breaking.
JointScene joint(const json& j, const std::string& ptr, const std::string& file,
                 std::vector<std::string>& errors, std::size_t index, const Scene& scene);
/// springs[i] (scene_joints.cpp): a damped spring between scene bodies (§4.3.3).
BodySpringScene body_spring(const json& j, const std::string& ptr, const std::string& file,
                            std::vector<std::string>& errors, std::size_t index, const Scene& scene);
/// Reports colliders whose names repeat an earlier one (joints name bodies, so names must be unique).
void check_body_names(const Scene& scene, std::vector<std::string>& errors);
/// Index of the collider named `name`, JointScene::kWorld for "world", or nullopt with a message
/// (expected, found, a "did you mean" hint) appended to `errors` at `pointer`.
std::optional<std::size_t> body_index(const Scene& scene, const std::string& name, const std::string& pointer,
                                      std::vector<std::string>& errors);

// scene_generators.cpp: chains[i] and ragdolls[i] expand into dynamic colliders and joints of
// `scene` (a GeneratedGroup records which).
void chain(const json& j, const std::string& ptr, const std::string& file, std::vector<std::string>& errors,
           std::size_t index, const sim::Vec3& gravity, Scene& scene);
void ragdoll(const json& j, const std::string& ptr, const std::string& file, std::vector<std::string>& errors,
             std::size_t index, const sim::Vec3& gravity, Scene& scene);

}  // namespace simreel::app::scene_read
