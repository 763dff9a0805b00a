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

/// Indexed triangle mesh, z up, metres.
struct TriangleMesh {
  std::vector<Eigen::Vector3f> positions;           ///< (n) vertex positions (m)
  std::vector<Eigen::Vector3f> normals;             ///< (n) unit vertex normals
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< (m) counter-clockwise seen from outside
};

/// A mesh file could not be imported; the message names the file and assimp's reason.
class AssetError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Imports every mesh of a file (OBJ, STL, PLY, glTF, FBX, DAE, ...) into one mesh with node
/// transforms applied: triangulated, identical vertices joined, normals generated where missing.
/// @throws AssetError naming the file when it is missing, unreadable, unsupported or has no triangles.
TriangleMesh load_mesh(const std::filesystem::path& path);

}  // namespace simreel::assets
