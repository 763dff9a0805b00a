// Mesh import through assimp into plain z-up triangle meshes.
#include "simreel/assets/mesh.hpp"

#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <new>
#include <sstream>
#include <string>

namespace simreel::assets {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

/// glTF by specification; others when their metadata names y as the up axis (see mesh.hpp).
bool is_y_up(const std::filesystem::path& path, const aiScene& scene) {
  const std::string ext = lower(path.extension().string());
  if (ext == ".gltf" || ext == ".glb") return true;
  if (scene.mMetaData != nullptr) {
    int up = -1;
    if (scene.mMetaData->Get("UpAxis", up)) return up == 1;
  }
  return false;
}

MeshMaterial read_material(const aiMaterial& m, const std::filesystem::path& folder) {
  MeshMaterial out;
  aiString name;
  if (m.Get(AI_MATKEY_NAME, name) == AI_SUCCESS) out.name = name.C_Str();
  aiColor4D c;
  if (m.Get(AI_MATKEY_BASE_COLOR, c) == AI_SUCCESS || m.Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS)
    out.base_color = {c.r, c.g, c.b, c.a};
  aiString tex;
  if (m.GetTexture(aiTextureType_BASE_COLOR, 0, &tex) == AI_SUCCESS ||
      m.GetTexture(aiTextureType_DIFFUSE, 0, &tex) == AI_SUCCESS) {
    const std::string t = tex.C_Str();
    out.texture = !t.empty() && t[0] == '*' ? std::filesystem::path(t) : folder / t;
  }
  return out;
}

/// Bytes of address space the process uses now (/proc/self/statm), 0 if unknown.
std::uint64_t address_space_in_use() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return 0;
  unsigned long long pages = 0;
  const bool ok = std::fscanf(f, "%llu", &pages) == 1;
  std::fclose(f);
  const long page = ::sysconf(_SC_PAGESIZE);
  return ok && page > 0 ? pages * std::uint64_t(page) : 0;
}

/// For its lifetime, caps the address space at what is in use plus `budget` bytes, so an import
/// whose file declares billions of elements fails its allocation (std::bad_alloc) instead of
/// taking the machine's memory. Nothing is changed where a limit is already set or the use is
/// unknown. Imports run while the scene loads, before any other thread of simreel starts.
class AddressSpaceBudget {
 public:
  explicit AddressSpaceBudget(std::uint64_t budget) {
#if defined(__SANITIZE_ADDRESS__)
    // AddressSanitizer reserves terabytes of shadow address space and must grow it freely: an
    // address-space cap makes every later allocation fail. Sanitizer builds import uncapped.
    return;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
    return;  // clang's spelling of the same check
#endif
#endif
    const std::uint64_t used = address_space_in_use();
    if (used == 0 || ::getrlimit(RLIMIT_AS, &old_) != 0 || old_.rlim_cur != RLIM_INFINITY) return;
    rlimit capped = old_;
    capped.rlim_cur = rlim_t(used + budget);
    active_ = ::setrlimit(RLIMIT_AS, &capped) == 0;
  }
  ~AddressSpaceBudget() {
    if (active_) ::setrlimit(RLIMIT_AS, &old_);
  }
  AddressSpaceBudget(const AddressSpaceBudget&) = delete;
  AddressSpaceBudget& operator=(const AddressSpaceBudget&) = delete;

 private:
  rlimit old_{};
  bool active_ = false;
};

/// Throws AssetError naming `file` and the first vertex of `scene` with a coordinate that is NaN
/// or infinite (a float beyond 3.4e38 reads as infinite).
void refuse_non_finite(const aiScene& scene, const std::string& file) {
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& am = *scene.mMeshes[m];
    for (unsigned v = 0; v < am.mNumVertices; ++v) {
      const aiVector3D& p = am.mVertices[v];
      if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) continue;
      std::ostringstream msg;
      msg << file << ": cannot import mesh: a vertex at (" << p.x << ", " << p.y << ", " << p.z
          << ") (mesh " << m << ", vertex " << v << " as imported), expected finite coordinates "
          << "(at most 3.4e38 in size: they are read as 32-bit floats)";
      throw AssetError(msg.str());
    }
  }
}

}  // namespace

/// Checks the file and reads it with `importer` (the steps of load_mesh; with `keep_groups`, the
/// node hierarchy is kept so meshes are not joined by material). Returns the scene.
/// @throws AssetError as load_mesh.
static const aiScene* import_scene(Assimp::Importer& importer, const std::filesystem::path& path,
                                   bool keep_groups) {
  const std::string file = path.string();
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) throw AssetError(file + ": cannot import mesh: no such file");
  // A FIFO would block the import, /dev/zero would never end.
  if (!std::filesystem::is_regular_file(status))
    throw AssetError(file + ": cannot import mesh: not a regular file (a directory, device or FIFO)");
  const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
  if (ec || bytes > kMaxMeshFileBytes)
    throw AssetError(file + ": cannot import mesh: " + (ec ? ec.message() : std::to_string(bytes) + " bytes") +
                     ", expected at most " + std::to_string(kMaxMeshFileBytes) + " (the mesh file size limit)");
  if (keep_groups) importer.SetPropertyBool(AI_CONFIG_PP_PTV_KEEP_HIERARCHY, true);
  // Points and lines are removed rather than imported as degenerate triangles.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // ValidateDataStructure first: a malformed file (assimp's own corpus has some) becomes an error
  // instead of a crash or an assertion in the later steps.
  // The vertices are checked as the file gives them, before the post-processing: joining
  // identical vertices compares positions, and a NaN one was merged into some other vertex (an
  // OBJ "v 1 1 nan" silently became a copy of a neighbour) instead of being refused.
  const aiScene* scene = nullptr;
  const auto refuse_broken = [&] {
    if (scene && !(scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) && scene->mRootNode) return;
    std::string reason = importer.GetErrorString();
    std::replace(reason.begin(), reason.end(), '\n', ' ');
    if (reason.empty()) reason = "unknown assimp error";
    throw AssetError(file + ": cannot import mesh: " + reason);
  };
  try {
    const AddressSpaceBudget budget(kMaxMeshImportBytes);
    scene = importer.ReadFile(file, aiProcess_ValidateDataStructure);
    refuse_broken();
    refuse_non_finite(*scene, file);
    scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                         aiProcess_GenSmoothNormals | aiProcess_SortByPType |
                                         aiProcess_PreTransformVertices);
  } catch (const std::bad_alloc&) {
    throw AssetError(file + ": cannot import mesh: needs more than " + std::to_string(kMaxMeshImportBytes >> 20) +
                     " MiB of memory (the mesh import memory limit)");
  }
  refuse_broken();
  // Node transforms can take finite positions beyond float's range.
  refuse_non_finite(*scene, file);
  return scene;
}

TriangleMesh load_mesh(const std::filesystem::path& path) {
  const std::string file = path.string();
  Assimp::Importer importer;
  const aiScene* scene = import_scene(importer, path, false);
  const bool y_up = is_y_up(path, *scene);
  auto to_z_up = [y_up](const aiVector3D& p) {
    return y_up ? Eigen::Vector3f(p.x, -p.z, p.y) : Eigen::Vector3f(p.x, p.y, p.z);
  };
  std::uint64_t vertices = 0;
  std::uint64_t triangles = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    vertices += scene->mMeshes[m]->mNumVertices;
    triangles += scene->mMeshes[m]->mNumFaces;
  }
  if (vertices > kMaxMeshVertices || triangles > kMaxMeshTriangles)
    throw AssetError(file + ": cannot import mesh: " + std::to_string(vertices) + " vertices and " +
                     std::to_string(triangles) + " faces, expected at most " + std::to_string(kMaxMeshVertices) +
                     " and " + std::to_string(kMaxMeshTriangles) + " (the mesh size limit)");
  TriangleMesh mesh;
  const std::filesystem::path folder = path.parent_path();
  for (unsigned k = 0; k < scene->mNumMaterials; ++k)
    mesh.materials.push_back(read_material(*scene->mMaterials[k], folder));
  if (mesh.materials.empty()) mesh.materials.emplace_back();
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* am = scene->mMeshes[m];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const auto base = static_cast<std::uint32_t>(mesh.positions.size());
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      mesh.positions.push_back(to_z_up(am->mVertices[v]));
      Eigen::Vector3f n = am->mNormals ? to_z_up(am->mNormals[v]) : Eigen::Vector3f::UnitZ();
      if (!(n.norm() > 0.0f) || !n.allFinite()) n = Eigen::Vector3f::UnitZ();  // degenerate faces
      mesh.normals.push_back(n.normalized());
      mesh.uvs.emplace_back(am->mTextureCoords[0] ? am->mTextureCoords[0][v].x : 0.0f,
                            am->mTextureCoords[0] ? am->mTextureCoords[0][v].y : 0.0f);
    }
    const std::uint32_t material = std::min<std::uint32_t>(am->mMaterialIndex, std::uint32_t(mesh.materials.size() - 1));
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;
      mesh.triangles.push_back({base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
      mesh.triangle_material.push_back(material);
    }
  }
  if (mesh.triangles.empty()) throw AssetError(file + ": cannot import mesh: the file has no triangles");
  return mesh;
}

std::vector<MeshGroup> load_mesh_groups(const std::filesystem::path& path) {
  Assimp::Importer importer;
  const aiScene* scene = import_scene(importer, path, true);
  const bool y_up = is_y_up(path, *scene);
  std::vector<MeshGroup> groups;
  const auto add = [&](const std::string& name, const aiMesh& am) {
    if (name.empty() || !(am.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) return;
    auto it = std::find_if(groups.begin(), groups.end(), [&](const MeshGroup& g) { return g.name == name; });
    if (it == groups.end()) it = groups.insert(groups.end(), MeshGroup{name, {}});
    for (unsigned v = 0; v < am.mNumVertices; ++v) {
      const aiVector3D& p = am.mVertices[v];
      it->positions.push_back(y_up ? Eigen::Vector3f(p.x, -p.z, p.y) : Eigen::Vector3f(p.x, p.y, p.z));
    }
  };
  // Node names (OBJ "o"/"g", glTF nodes) and mesh names (glTF meshes), depth first in file order.
  std::vector<const aiNode*> stack{scene->mRootNode};
  while (!stack.empty()) {
    const aiNode* node = stack.back();
    stack.pop_back();
    for (unsigned k = 0; k < node->mNumMeshes; ++k) {
      const aiMesh& am = *scene->mMeshes[node->mMeshes[k]];
      if (node != scene->mRootNode) add(node->mName.C_Str(), am);
      if (std::string(am.mName.C_Str()) != node->mName.C_Str()) add(am.mName.C_Str(), am);
    }
    for (unsigned c = node->mNumChildren; c-- > 0;) stack.push_back(node->mChildren[c]);
  }
  return groups;
}

}  // namespace simreel::assets
