#pragma once
/// @file mesh.hpp
/// Plain triangle meshes and their import through assimp. The engine and the renderer take
/// these plain arrays; no assimp type leaves this module.

#include <array>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace simreel::assets {

/// A surface material as the file gives it (base colour and, if any, the colour texture).
struct MeshMaterial {
  std::string name;
  std::array<float, 4> base_color{0.8f, 0.8f, 0.8f, 1.0f};  ///< linear RGBA in [0, 1]
  std::filesystem::path texture;  ///< diffuse/base-colour texture, resolved against the mesh
                                  ///< file's folder; empty if none (embedded textures: "*0", ...)
};

/// Indexed triangle mesh, z up, metres (as the file's units; no unit conversion).
struct TriangleMesh {
  std::vector<Eigen::Vector3f> positions;           ///< (n) vertex positions (m)
  std::vector<Eigen::Vector3f> normals;             ///< (n) unit vertex normals
  std::vector<Eigen::Vector2f> uvs;                 ///< (n) first UV channel; (0, 0) where absent
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< (m) counter-clockwise seen from outside
  std::vector<std::uint32_t> triangle_material;     ///< (m) index into `materials`
  std::vector<MeshMaterial> materials;              ///< at least one
};

/// A mesh file could not be imported; the message is one line naming the file and assimp's reason.
class AssetError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bounds on an import: larger files are refused before assimp reads them; more vertices or
/// faces (after triangulation, before joining) are refused after.
inline constexpr std::uintmax_t kMaxMeshFileBytes = 256ull << 20;  ///< 256 MiB
inline constexpr std::uint64_t kMaxMeshVertices = 10'000'000;
inline constexpr std::uint64_t kMaxMeshTriangles = 10'000'000;
/// Memory one import may take (address space beyond what the process used before it): 4 GiB.
inline constexpr std::uint64_t kMaxMeshImportBytes = 4ull << 30;
/// Time one import may take: 10 s plus 1 s per 2 MiB of file, or $SIMREEL_MESH_IMPORT_SECONDS
/// when that is a positive number of seconds.

/// Imports every mesh of a file (OBJ, STL, PLY, glTF/GLB, FBX, DAE, ...) into one mesh: node
/// transforms applied, triangulated, identical vertices joined, normals generated where missing
/// (smooth), lines and points dropped.
///
/// Up axis (simreel is z up): glTF files (.gltf, .glb) are y up by specification and files whose
/// metadata says "UpAxis" = 1 (FBX, Collada) are y up; both are turned to z up by the rotation
/// (x, y, z) -> (x, -z, y) (+90 degrees about x). OBJ, STL and PLY carry no up axis and are taken
/// as written, i.e. z up.
/// assimp reads the file in a forked child process (where the process cannot fork, in this one),
/// which sends the plain arrays back through a pipe: a file that makes assimp crash, abort or
/// loop is an error, not the end of the caller.
/// @throws AssetError naming the file when it is missing, not a regular file, unreadable,
///         unsupported, broken (assimp's data-structure validation, or assimp crashed on it or
///         did not finish within the time limit above), beyond the limits above,
///         has a vertex coordinate that is NaN or infinite as a float (checked before identical
///         vertices are joined, and again after the node transforms) or has no triangles.
TriangleMesh load_mesh(const std::filesystem::path& path);

/// A named part of a mesh file: an OBJ object or group ("o name", "g name"), a glTF node or
/// mesh, ... as assimp names them, with the positions of its vertices (m, z up, as load_mesh
/// gives them; a vertex on the border of two groups is in both).
struct MeshGroup {
  std::string name;
  std::vector<Eigen::Vector3f> positions;
};

/// The named groups of a mesh file, in file order (a name given twice is one group). Parts
/// without a name are left out. Same checks and errors as load_mesh.
std::vector<MeshGroup> load_mesh_groups(const std::filesystem::path& path);

}  // namespace simreel::assets
