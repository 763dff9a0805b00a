// Mesh import through assimp: a cube as OBJ, and clear errors for missing and broken files.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "simreel/assets/mesh.hpp"

namespace fs = std::filesystem;
using simreel::assets::AssetError;
using simreel::assets::load_mesh;

namespace {

fs::path temp_file(const std::string& name, const std::string& text) {
  const fs::path p = fs::temp_directory_path() / ("simreel-assets-" + std::to_string(::getpid()) + "-" + name);
  std::ofstream(p) << text;
  return p;
}

}  // namespace

TEST(Mesh, ObjCubeImportsAsTwelveTriangles) {
  const auto p = temp_file("cube.obj",
                           "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                           "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
  const auto mesh = load_mesh(p);
  fs::remove(p);
  EXPECT_EQ(mesh.triangles.size(), 12u);  // quads triangulated
  ASSERT_EQ(mesh.normals.size(), mesh.positions.size());
  for (const auto& n : mesh.normals) EXPECT_NEAR(n.norm(), 1.0f, 1e-4f);
  Eigen::Vector3f lo = mesh.positions[0], hi = mesh.positions[0];
  for (const auto& v : mesh.positions) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  EXPECT_TRUE(lo.isApprox(Eigen::Vector3f(0, 0, 0)));
  EXPECT_TRUE(hi.isApprox(Eigen::Vector3f(1, 1, 1)));
}

TEST(Mesh, MissingFileNamesTheFile) {
  try {
    (void)load_mesh("/nonexistent/rock.obj");
    FAIL();
  } catch (const AssetError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/rock.obj"), std::string::npos) << e.what();
  }
}

TEST(Mesh, BrokenAndEmptyFilesAreClearErrors) {
  for (const auto& [name, text] : {std::pair{"garbage.stl", std::string("\x01\x02 not a mesh at all")},
                                   std::pair{"empty.obj", std::string("# nothing\n")}}) {
    const auto p = temp_file(name, text);
    try {
      (void)load_mesh(p);
      ADD_FAILURE() << name << " imported";
    } catch (const AssetError& e) {
      EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    }
    fs::remove(p);
  }
}
