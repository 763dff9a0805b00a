// Triangle meshes: geometry helpers (closed, outward, right volume), drawing (same pixels as
// the built-in box, two-sided lighting, textures), shadows cast by meshes, errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>

#include "render_test_util.hpp"
#include "simreel/render/context.hpp"
#include "simreel/render/image.hpp"
#include "simreel/render/mesh.hpp"
#include "simreel/render/renderer.hpp"

namespace simreel::render {
namespace {

int luminance(const std::uint8_t* p) { return (2 * p[0] + 5 * p[1] + p[2]) / 8; }

/// Signed volume by the divergence theorem: sum over triangles of a . (b x c) / 6. Positive
/// for a closed surface whose triangles wind counter-clockwise seen from outside.
double signed_volume(const MeshDesc& m) {
  double v = 0.0;
  for (std::size_t t = 0; t < m.indices.size(); t += 3) {
    const auto p = [&](std::size_t k) {
      const std::uint32_t i = m.indices[t + k];
      return Eigen::Vector3d(m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]);
    };
    v += p(0).dot(p(1).cross(p(2))) / 6.0;
  }
  return v;
}

/// Axis-aligned box mesh with flat face normals, counter-clockwise from outside.
MeshDesc box_mesh(const Vec3f& half) {
  MeshDesc m;
  for (int axis = 0; axis < 3; ++axis) {
    for (const float sign : {-1.f, 1.f}) {
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      const auto base = std::uint32_t(m.positions.size() / 3);
      const float corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
      for (const auto& c : corners) {
        float p[3], n[3] = {0, 0, 0};
        p[axis] = sign * half[axis];
        p[a] = c[0] * half[a];
        p[b] = (sign > 0 ? c[1] : -c[1]) * half[b];
        n[axis] = sign;
        m.positions.insert(m.positions.end(), p, p + 3);
        m.normals.insert(m.normals.end(), n, n + 3);
      }
      for (const std::uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m.indices.push_back(base + i);
    }
  }
  return m;
}

/// A unit quad in the x-z plane (y = 0) facing -y (towards test::front_camera) or +y.
MeshDesc quad_mesh(bool facing_camera) {
  MeshDesc m;
  m.positions = {-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1};
  m.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  m.indices = facing_camera ? std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3}
                            : std::vector<std::uint32_t>{0, 2, 1, 0, 3, 2};
  return m;
}

TEST(MeshHelpers, SphereIsClosedOutwardAndConvergesToTheBallVolume) {
  const double exact = 4.0 / 3.0 * std::numbers::pi * 0.8 * 0.8 * 0.8;
  double previous_error = 1.0;
  for (const int segments : {8, 16, 32, 64}) {
    const MeshDesc m = make_sphere_mesh(0.8f, segments);
    const double error = std::abs(signed_volume(m) - exact) / exact;
    EXPECT_GT(signed_volume(m), 0.0) << segments;  // outward winding
    // An inscribed polyhedron: second order, the error falls about 4x per doubling.
    EXPECT_LT(error, previous_error / 3.0) << segments;
    previous_error = error;
  }
  EXPECT_LT(previous_error, 6e-3);
}

TEST(MeshHelpers, CylinderHasThePrismVolumeAndOutwardNormals) {
  const int n = 12;
  const MeshDesc m = make_cylinder_mesh(0.5f, 0.75f, n);
  // Exact volume of the inscribed regular n-gon prism.
  const double prism = 0.5 * n * std::sin(2.0 * std::numbers::pi / n) * 0.25 * 1.5;
  EXPECT_NEAR(signed_volume(m), prism, 1e-5);
  for (std::size_t i = 0; i < m.positions.size(); i += 3) {
    const Eigen::Vector3f p(m.positions[i], m.positions[i + 1], m.positions[i + 2]);
    const Eigen::Vector3f nrm(m.normals[i], m.normals[i + 1], m.normals[i + 2]);
    EXPECT_NEAR(nrm.norm(), 1.f, 1e-5f);
    EXPECT_GE(p.dot(nrm), 0.f);  // no normal points inwards
  }
  EXPECT_THROW(make_cylinder_mesh(0.f, 1.f, 8), std::invalid_argument);
  EXPECT_THROW(make_sphere_mesh(1.f, 2), std::invalid_argument);
}

// The capsule (sim::ShapeDef::capsule): a sphere of radius r cut at its equator and pulled apart
// by 2 h. Its volume converges to the exact 4/3 π r³ + 2 π r² h (outward winding, closed), and
// every normal is the unit vector from the segment's nearest point.
TEST(MeshHelpers, CapsuleConvergesToTheCapsuleVolumeWithOutwardNormals) {
  const double r = 0.3, h = 0.5;
  const double exact = 4.0 / 3.0 * std::numbers::pi * r * r * r + 2.0 * std::numbers::pi * r * r * h;
  double previous_error = 1.0;
  for (const int segments : {8, 16, 32, 64}) {
    const MeshDesc m = make_capsule_mesh(float(r), float(h), segments);
    EXPECT_GT(signed_volume(m), 0.0) << segments;
    const double error = std::abs(signed_volume(m) - exact) / exact;
    EXPECT_LT(error, previous_error / 3.0) << segments;
    previous_error = error;
    for (std::size_t i = 0; i < m.positions.size(); i += 3) {
      const Eigen::Vector3f p(m.positions[i], m.positions[i + 1], m.positions[i + 2]);
      const Eigen::Vector3f nrm(m.normals[i], m.normals[i + 1], m.normals[i + 2]);
      const Eigen::Vector3f axis_point(0.f, 0.f, std::clamp(p.z(), float(-h), float(h)));
      EXPECT_NEAR(nrm.norm(), 1.f, 1e-5f);
      EXPECT_LT((axis_point + float(r) * nrm - p).norm(), 1e-5f);
    }
  }
  EXPECT_LT(previous_error, 6e-3);
  EXPECT_THROW(make_capsule_mesh(0.1f, 0.f, 8), std::invalid_argument);
  EXPECT_THROW(make_capsule_mesh(0.1f, 0.1f, 2), std::invalid_argument);
}

TEST(MeshHelpers, ComputedNormalsMatchTheSphereRadii) {
  const MeshDesc m = make_sphere_mesh(2.f, 48);
  std::vector<float> normals(m.positions.size());
  compute_vertex_normals(m.positions, m.indices, normals);
  std::vector<bool> used(normals.size() / 3, false);
  for (const std::uint32_t i : m.indices) used[i] = true;
  double worst = 1.0;
  for (std::size_t i = 0; i < normals.size(); i += 3) {
    if (!used[i / 3]) continue;  // the pole copies on the UV seam belong to no triangle
    const Eigen::Vector3f a(normals[i], normals[i + 1], normals[i + 2]);
    const Eigen::Vector3f b(m.normals[i], m.normals[i + 1], m.normals[i + 2]);
    worst = std::min(worst, double(a.dot(b)));
  }
  EXPECT_GT(worst, 0.995);
  const std::vector<std::uint32_t> bad = {0, 1, 99999};
  EXPECT_THROW(compute_vertex_normals(m.positions, bad, normals), std::invalid_argument);
}

class MeshScene : public ::testing::Test {
 protected:
  void SetUp() override {
    context_ = create_context(Backend::osmesa);
    renderer_ = std::make_unique<Renderer>(*context_, test::small_settings());
    renderer_->set_camera(test::front_camera());
  }
  Renderer& r() { return *renderer_; }
  std::unique_ptr<Context> context_;
  std::unique_ptr<Renderer> renderer_;
};

TEST_F(MeshScene, BoxMeshDrawsLikeTheBuiltInBox) {
  // Same colour, pose and light: the mesh path (normals, winding, culling, shading) must give
  // the built-in box's pixels. A rotation makes three faces visible.
  const Mat3f rot = (Eigen::AngleAxisf(0.5f, Vec3f::UnitZ()) * Eigen::AngleAxisf(0.3f, Vec3f::UnitX()))
                        .toRotationMatrix();
  const Vec3f at(-0.8f, 0.f, 0.4f), half(0.9f, 0.5f, 0.3f);
  BoxDesc box;
  box.half_extents = half;
  box.color = Vec4f(0.8f, 0.45f, 0.2f, 1.f);
  r().add_box(1, box);
  r().set_transform(1, at, rot);
  const Image reference = r().render();
  r().remove(1);
  MeshDesc m = box_mesh(half);
  m.material.base_color = box.color;
  r().add_mesh(1, m);
  r().set_transform(1, at, rot);
  const Image mesh = r().render();
  const test::Blob blob = test::find_blob(mesh, test::is_warm);
  ASSERT_GT(blob.count, 300);
  EXPECT_LT(blob.x, test::kWidth / 2.0 - 5.0);  // placed left of centre
  int worst = 0;
  for (std::size_t i = 0; i < mesh.rgba.size(); ++i) {
    worst = std::max(worst, std::abs(int(mesh.rgba[i]) - int(reference.rgba[i])));
  }
  EXPECT_LE(worst, 2);
}

TEST_F(MeshScene, RotatedLongMeshStandsUpright) {
  MeshDesc m = box_mesh(Vec3f(1.5f, 0.2f, 0.2f));
  m.material.base_color = Vec4f(0.9f, 0.3f, 0.1f, 1.f);
  r().add_mesh(1, m);
  auto extent = [&](const Image& img) {
    int x0 = img.width, x1 = -1, y0 = img.height, y1 = -1;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x)
        if (test::is_warm(img.pixel(x, y))) {
          x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
        }
    return std::pair{x1 - x0 + 1, y1 - y0 + 1};
  };
  const auto [w_lying, h_lying] = extent(r().render());
  r().set_transform(1, Vec3f::Zero(), Eigen::AngleAxisf(std::numbers::pi_v<float> / 2, Vec3f::UnitY()).toRotationMatrix());
  const auto [w_up, h_up] = extent(r().render());
  EXPECT_GT(w_lying, 3 * h_lying);
  EXPECT_GT(h_up, 3 * w_up);
}

TEST_F(MeshScene, DoubleSidedQuadIsLitFromBothSides) {
  Light sun;
  sun.direction = Vec3f(0.2f, 1.f, -0.3f);  // from behind the camera
  r().set_light(sun);
  MeshDesc front = quad_mesh(true), back = quad_mesh(false);
  front.material.double_sided = back.material.double_sided = true;
  r().add_mesh(1, front);
  const Image a = r().render();
  r().remove(1);
  r().add_mesh(1, back);  // wound the other way: its normal faces away from the camera
  const Image b = r().render();
  const auto* ca = a.pixel(test::kWidth / 2, test::kHeight / 2);
  const auto* cb = b.pixel(test::kWidth / 2, test::kHeight / 2);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(int(ca[c]), int(cb[c]), 1) << c;
  // And lit by the sun, not only by the ambient light.
  sun.color = Vec3f::Zero();
  r().set_light(sun);
  EXPECT_GT(luminance(cb), luminance(r().render().pixel(test::kWidth / 2, test::kHeight / 2)) + 40);
}

TEST_F(MeshScene, SingleSidedBackFaceIsCulled) {
  const Image sky = r().render();
  r().add_mesh(1, quad_mesh(false));
  EXPECT_EQ(r().render().rgba, sky.rgba);
  r().remove(1);
  r().add_mesh(1, quad_mesh(true));
  EXPECT_NE(r().render().rgba, sky.rgba);
}

TEST_F(MeshScene, TextureQuadrantsShowUpRightWayUp) {
  // 2 x 2 texture, rows top to bottom: red green / blue white.
  MeshDesc m = quad_mesh(true);
  m.material.base_color = Vec4f::Ones();
  m.material.specular = 0.f;
  m.material.texture_rgba = {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255};
  m.material.texture_width = 2;
  m.material.texture_height = 2;
  auto check = [&](const Image& img) {
    // The quad spans about +-1 m at 10 m: quadrant centres at +-0.5 m, ~ +-8 pixels.
    const int cx = test::kWidth / 2, cy = test::kHeight / 2, d = 8;
    const auto* tl = img.pixel(cx - d, cy - d);
    const auto* tr = img.pixel(cx + d, cy - d);
    const auto* bl = img.pixel(cx - d, cy + d);
    const auto* br = img.pixel(cx + d, cy + d);
    EXPECT_GT(tl[0], tl[1] + 60);
    EXPECT_GT(tl[0], tl[2] + 60);
    EXPECT_GT(tr[1], tr[0] + 60);
    EXPECT_GT(tr[1], tr[2] + 60);
    EXPECT_GT(bl[2], bl[0] + 60);
    EXPECT_GT(bl[2], bl[1] + 60);
    EXPECT_GT(std::min({br[0], br[1], br[2]}), 120);
  };
  r().add_mesh(1, m);
  check(r().render());

  // The same texture from a PNG file.
  test::TempDir dir("mesh-texture");
  Image tex(2, 2);
  tex.rgba = m.material.texture_rgba;
  write_png(dir.path() / "t.png", tex);
  MeshDesc from_file = quad_mesh(true);
  from_file.material = m.material;
  from_file.material.texture_rgba.clear();
  from_file.material.texture_path = (dir.path() / "t.png").string();
  r().remove(1);
  r().add_mesh(1, from_file);
  check(r().render());

  from_file.material.texture_path = (dir.path() / "missing.png").string();
  EXPECT_THROW(r().add_mesh(2, from_file), IoError);
}

TEST_F(MeshScene, MeshShadowFallsOnTheGroundAwayFromTheSun) {
  Camera top;
  top.position = Vec3f(0.f, 0.f, 10.f);
  top.target = Vec3f::Zero();
  top.up = Vec3f::UnitY();
  r().set_camera(top);
  Light sun;
  sun.direction = Vec3f(1.f, 0.f, -1.f);  // travels towards +x: shadows fall on the +x side
  r().set_light(sun);
  PlaneDesc ground;
  ground.checker_m = 0.f;
  r().add_plane(1, ground);
  r().add_mesh(2, make_sphere_mesh(0.5f, 24));
  r().set_transform(2, Vec3f(0.f, 0.f, 1.5f), Mat3f::Identity());
  const Image img = r().render();
  // 120 pixels span 2 x 10 tan(20 deg) = 7.28 m: the shadow centre (x = +1.5 m) is ~25 px right.
  const int cy = test::kHeight / 2, cx = test::kWidth / 2;
  const int shadowed = luminance(img.pixel(cx + 25, cy));
  const int lit = luminance(img.pixel(cx - 25, cy));
  EXPECT_GT(lit, shadowed + 30) << lit << " vs " << shadowed;
}

TEST_F(MeshScene, UpdateMeshMovesTheVertices) {
  MeshDesc m = quad_mesh(true);
  m.dynamic = true;
  m.material.base_color = Vec4f(0.9f, 0.3f, 0.1f, 1.f);
  r().add_mesh(1, m);
  const test::Blob before = test::find_blob(r().render(), test::is_warm);
  std::vector<float> moved = m.positions;
  for (std::size_t i = 0; i < moved.size(); i += 3) moved[i] += 2.f;  // 2 m to the right
  r().update_mesh(1, moved);  // normals recomputed
  const test::Blob after = test::find_blob(r().render(), test::is_warm);
  ASSERT_GT(before.count, 100);
  ASSERT_GT(after.count, 100);
  EXPECT_GT(after.x - before.x, 20.0);
  EXPECT_NEAR(after.count, before.count, before.count / 5);
}

TEST_F(MeshScene, EachPartIsDrawnInItsOwnMaterial) {
  // The quad's two triangles as two parts: the lower-right one red, the upper-left one blue
  // (a compound body's shapes in their own colours), then the red one textured green.
  MeshDesc m = quad_mesh(true);
  Material red, blue;
  red.base_color = Vec4f(0.9f, 0.05f, 0.05f, 1.f);
  blue.base_color = Vec4f(0.05f, 0.1f, 0.9f, 1.f);
  m.material.base_color = Vec4f(0.1f, 0.9f, 0.1f, 1.f);  // unused once there are parts
  m.parts = {{0, 1, red}, {1, 1, blue}};
  r().add_mesh(1, m);
  const int cx = test::kWidth / 2, cy = test::kHeight / 2;
  const auto check = [&](const Image& img, int x, int y, int channel) {
    const auto* p = img.pixel(x, y);
    for (int c = 0; c < 3; ++c) {
      if (c != channel) {
        EXPECT_GT(int(p[channel]), int(p[c]) + 40) << "at " << x << "," << y << " channel " << c;
      }
    }
  };
  const Image a = r().render();
  check(a, cx + 6, cy + 6, 0);  // below the diagonal, right: triangle 0
  check(a, cx - 6, cy - 6, 2);  // above it, left: triangle 1
  r().remove(1);
  m.parts[0].material.base_color = Vec4f::Ones();
  m.parts[0].material.texture_rgba = {0, 255, 0, 255};
  m.parts[0].material.texture_width = m.parts[0].material.texture_height = 1;
  r().add_mesh(1, m);
  const Image b = r().render();
  check(b, cx + 6, cy + 6, 1);
  check(b, cx - 6, cy - 6, 2);
  // Parts must tile the triangles in order.
  for (const std::vector<MeshPart>& bad : {std::vector<MeshPart>{{0, 1, red}},
                                           std::vector<MeshPart>{{1, 1, red}, {0, 1, blue}},
                                           std::vector<MeshPart>{{0, 0, red}, {0, 2, blue}},
                                           std::vector<MeshPart>{{0, 3, red}}}) {
    MeshDesc q = quad_mesh(true);
    q.parts = bad;
    EXPECT_THROW(r().add_mesh(2, q), std::invalid_argument);
  }
}

TEST_F(MeshScene, BadMeshesAreRejected) {
  MeshDesc m = quad_mesh(true);
  m.indices.push_back(0);
  EXPECT_THROW(r().add_mesh(1, m), std::invalid_argument);  // not m x 3
  m = quad_mesh(true);
  m.indices[2] = 4;
  EXPECT_THROW(r().add_mesh(1, m), std::invalid_argument);  // index out of range
  m = quad_mesh(true);
  m.uvs.pop_back();
  EXPECT_THROW(r().add_mesh(1, m), std::invalid_argument);
  m = quad_mesh(true);
  m.material.texture_rgba = {1, 2, 3};
  m.material.texture_width = 1;
  m.material.texture_height = 1;
  EXPECT_THROW(r().add_mesh(1, m), std::invalid_argument);
  r().add_mesh(1, quad_mesh(true));
  EXPECT_THROW(r().add_mesh(1, quad_mesh(true)), std::invalid_argument);  // key used
  const std::vector<float> short_positions(6, 0.f);
  EXPECT_THROW(r().update_mesh(1, short_positions), std::invalid_argument);
  EXPECT_THROW(r().update_mesh(7, short_positions), std::out_of_range);
  r().add_box(2, BoxDesc{});
  EXPECT_THROW(r().update_mesh(2, short_positions), std::invalid_argument);
}

TEST(MeshBackground, SolidBackgroundFillsTheFrame) {
  const auto context = create_context(Backend::osmesa);
  RenderSettings s = test::small_settings();
  s.background = Background::solid;
  s.background_color = Vec3f(0.2f, 0.2f, 0.2f);  // sRGB 124
  Renderer r(*context, s);
  const Image img = r.render();
  for (const auto& [x, y] : {std::pair{0, 0}, {test::kWidth - 1, test::kHeight - 1}}) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(int(img.pixel(x, y)[c]), 124, 1);
  }
}

}  // namespace
}  // namespace simreel::render
