// Mesh import through assimp into plain z-up triangle meshes.
#include "simreel/assets/mesh.hpp"

#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
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

}  // namespace

TriangleMesh load_mesh(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw AssetError(file + ": cannot import mesh: no such file");
  Assimp::Importer importer;
  // Points and lines are removed rather than imported as degenerate triangles.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene = importer.ReadFile(
      file, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_GenSmoothNormals |
                aiProcess_SortByPType | aiProcess_PreTransformVertices);
  if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->mRootNode) {
    std::string reason = importer.GetErrorString();
    std::replace(reason.begin(), reason.end(), '\n', ' ');
    if (reason.empty()) reason = "unknown assimp error";
    throw AssetError(file + ": cannot import mesh: " + reason);
  }
  const bool y_up = is_y_up(path, *scene);
  auto to_z_up = [y_up](const aiVector3D& p) {
    return y_up ? Eigen::Vector3f(p.x, -p.z, p.y) : Eigen::Vector3f(p.x, p.y, p.z);
  };
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

}  // namespace simreel::assets
