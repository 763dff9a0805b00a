// Mass properties (Coutinho App. D; Mirtich 1996): triangle meshes against closed forms, the
// primitives against each other through compounds, principal axes, rejected meshes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <stdexcept>
#include <utility>
#include <vector>

#include "rigid/mass_properties.hpp"
#include "rigid_test_meshes.hpp"

namespace simreel::sim::detail {
namespace {

using test::Mesh;
constexpr double kPi = std::numbers::pi;

/// Largest entry-wise difference relative to the largest entry of `b`.
double rel_diff(const Mat3& a, const Mat3& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

void expect_same(const MassProperties& a, const MassProperties& b, double tol) {
  EXPECT_NEAR(a.mass, b.mass, tol * b.mass);
  EXPECT_NEAR(a.volume, b.volume, tol * b.volume);
  const double length = std::cbrt(b.volume);
  EXPECT_LE((a.center_of_mass - b.center_of_mass).norm(), tol * length)
      << a.center_of_mass.transpose() << " vs " << b.center_of_mass.transpose();
  EXPECT_LE(rel_diff(a.inertia, b.inertia), tol) << a.inertia << "\nvs\n" << b.inertia;
}

Mat3 rotation(double angle, const Vec3& axis) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

MassProperties mass_of(const Mesh& m, double density) {
  return mesh_mass(m.vertices, m.triangles, density);
}

TEST(MassPropertiesPrimitive, SphereBoxCylinderClosedForms) {
  const MassProperties s = sphere_mass(0.5, 1000.0);
  EXPECT_NEAR(s.volume, 4.0 / 3.0 * kPi * 0.125, 1e-15);
  EXPECT_NEAR(s.inertia(0, 0), 0.4 * s.mass * 0.25, 1e-12);
  const MassProperties b = box_mass(Vec3(0.5, 1.0, 1.5), 2.0);  // sides 1 x 2 x 3
  EXPECT_DOUBLE_EQ(b.mass, 12.0);
  EXPECT_DOUBLE_EQ(b.inertia(0, 0), 12.0 / 12.0 * (4.0 + 9.0));
  EXPECT_DOUBLE_EQ(b.inertia(1, 1), 12.0 / 12.0 * (1.0 + 9.0));
  EXPECT_DOUBLE_EQ(b.inertia(2, 2), 12.0 / 12.0 * (1.0 + 4.0));
  const MassProperties c = cylinder_mass(0.5, 1.0, 1.0);  // r 0.5, length 2
  EXPECT_NEAR(c.mass, kPi * 0.25 * 2.0, 1e-15);
  EXPECT_NEAR(c.inertia(0, 0), c.mass * (3.0 * 0.25 + 4.0) / 12.0, 1e-14);
  EXPECT_NEAR(c.inertia(2, 2), c.mass * 0.25 / 2.0, 1e-14);
  EXPECT_THROW(sphere_mass(-1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(box_mass(Vec3(1.0, 0.0, 1.0), 1.0), std::invalid_argument);
  EXPECT_THROW(cylinder_mass(1.0, 1.0, NAN), std::invalid_argument);
}

TEST(MassPropertiesMesh, TriangulatedBoxIsExact) {
  const Vec3 h(0.3, 0.7, 1.1);
  const MassProperties mesh = mass_of(test::box_mesh(h), 750.0);
  expect_same(mesh, box_mass(h, 750.0), 1e-12);
  EXPECT_LE(mesh.center_of_mass.norm(), 1e-15);
  // Off-diagonal terms vanish for the axis-aligned box.
  EXPECT_LE(
      std::abs(mesh.inertia(0, 1)) + std::abs(mesh.inertia(0, 2)) + std::abs(mesh.inertia(1, 2)),
      1e-13 * mesh.inertia(0, 0));
}

TEST(MassPropertiesMesh, RightTetrahedronTextbookFormula) {
  // Corner tetrahedron (0, a e_x, b e_y, c e_z): V = abc/6, centre (a, b, c)/4, and about the
  // centre I_xx = 3m (b² + c²)/80 (cyclic), I_xy = +m ab/80 (cyclic): ∫x² dV = V a²/10 and
  // ∫xy dV = V ab/20 about the corner, by integrating over the cross-sections.
  const double a = 1.0, b = 2.0, c = 3.0, rho = 5.0;
  Mesh t;
  t.vertices = {Vec3::Zero(), Vec3(a, 0, 0), Vec3(0, b, 0), Vec3(0, 0, c)};
  t.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const MassProperties p = mass_of(t, rho);
  const double v = a * b * c / 6.0, m = rho * v;
  EXPECT_NEAR(p.volume, v, 1e-15);
  EXPECT_LE((p.center_of_mass - Vec3(a, b, c) / 4.0).norm(), 1e-15);
  Mat3 expected;
  expected << 3 * m * (b * b + c * c) / 80, m * a * b / 80, m * a * c / 80,  //
      m * a * b / 80, 3 * m * (a * a + c * c) / 80, m * b * c / 80,          //
      m * a * c / 80, m * b * c / 80, 3 * m * (a * a + b * b) / 80;
  EXPECT_LE(rel_diff(p.inertia, expected), 1e-14) << p.inertia;
}

TEST(MassPropertiesMesh, GeneralTetrahedronTonon2004) {
  // The worked example of Tonon 2004, "Explicit exact formulas for the 3-D tetrahedron inertia
  // tensor in terms of its vertex coordinates" (J. Math. Stat. 1(1)), density 1: centre
  // (15.92492, 0.78281, 3.72962); a = I_xx, b = I_yy, c = I_zz; a' = -I_yz, b' = -I_xz,
  // c' = -I_xy about the centre.
  Mesh t;
  t.vertices = {Vec3(8.33220, -11.86875, 0.93355), Vec3(0.75523, 5.00000, 16.37072),
                Vec3(52.61236, 5.00000, -5.38580), Vec3(2.00000, 5.00000, 3.00000)};
  t.triangles = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  const auto& v = t.vertices;
  if ((v[3] - v[0]).dot((v[1] - v[0]).cross(v[2] - v[0])) > 0)
    for (auto& tri : t.triangles) std::swap(tri[1], tri[2]);  // wind outwards
  const MassProperties p = mass_of(t, 1.0);
  // The paper's figures were computed from coordinates with more digits than it prints (the
  // printed centre differs from the mean of the printed vertices by 3e-5), so agreement is to
  // ~1e-8 relative, not to rounding; a wrong formula misses by orders more.
  EXPECT_LE((p.center_of_mass - Vec3(15.92492, 0.78281, 3.72962)).norm(), 5e-5);
  const auto near = [](double got, double paper) { EXPECT_NEAR(got, paper, 1e-7 * 194711.0); };
  near(p.inertia(0, 0), 43520.33257);
  near(p.inertia(1, 1), 194711.28938);
  near(p.inertia(2, 2), 191168.76173);
  near(-p.inertia(1, 2), 4417.66150);
  near(-p.inertia(0, 2), -46343.16662);
  near(-p.inertia(0, 1), 11996.20119);
}

TEST(MassPropertiesMesh, SphereMeshConvergesAtSecondOrder) {
  // An icosphere inscribed in the unit sphere: the error of a polyhedral approximation falls as
  // the square of the edge length, so each subdivision (edge length halved) divides it by ~4.
  const double rho = 1000.0;
  const MassProperties exact = sphere_mass(1.0, rho);
  double previous_volume_error = 0.0, previous_inertia_error = 0.0;
  for (int level = 1; level <= 6; ++level) {
    const MassProperties p = mass_of(test::icosphere(level, 1.0), rho);
    const double volume_error = std::abs(p.volume - exact.volume) / exact.volume;
    const double inertia_error = rel_diff(p.inertia, exact.inertia);
    EXPECT_LE(p.center_of_mass.norm(), 1e-13);
    if (level > 1) {
      const double rv = previous_volume_error / volume_error;
      const double ri = previous_inertia_error / inertia_error;
      std::printf(
          "icosphere level %d: volume error %.3e (ratio %.3f), inertia error %.3e "
          "(ratio %.3f)\n",
          level, volume_error, rv, inertia_error, ri);
      if (level >= 4) {
        EXPECT_NEAR(rv, 4.0, 0.15);
        EXPECT_NEAR(ri, 4.0, 0.15);
      }
    }
    previous_volume_error = volume_error;
    previous_inertia_error = inertia_error;
  }
  EXPECT_LT(previous_volume_error, 1e-3);
}

TEST(MassPropertiesMesh, TranslatedAndRotatedMeshMovesTheCentreAndRotatesTheInertia) {
  const Vec3 h(0.2, 0.5, 0.9);
  const Mat3 r = rotation(0.7, Vec3(1.0, -2.0, 0.5));
  const Vec3 t(3.0, -1.0, 12.0);
  Mesh m = test::box_mesh(h);
  for (auto& v : m.vertices) v = r * v + t;
  const MassProperties moved = mass_of(m, 300.0);
  const MassProperties box = box_mass(h, 300.0);
  EXPECT_NEAR(moved.mass, box.mass, 1e-12 * box.mass);
  EXPECT_LE((moved.center_of_mass - t).norm(), 1e-13 * t.norm());
  EXPECT_LE(rel_diff(moved.inertia, r * box.inertia * r.transpose()), 1e-12);
  // The same through transformed(): the mesh result equals the moved closed form.
  expect_same(moved, transformed(box, r, t), 1e-12);
  // Not the unrotated inertia: the test sees a rotation.
  EXPECT_GT(rel_diff(moved.inertia, box.inertia), 1e-2);
}

TEST(MassPropertiesMesh, MassInsteadOfDensityScales) {
  const Mesh m = test::box_mesh(Vec3(0.5, 0.5, 1.0));  // volume 2 m³
  const MassProperties from_density = mass_of(m, 3.5);
  const MassProperties from_mass = with_mass(mass_of(m, 1.0), 7.0);
  expect_same(from_mass, from_density, 1e-14);
  EXPECT_DOUBLE_EQ(from_mass.mass, 7.0);
  EXPECT_THROW(with_mass(from_density, 0.0), std::invalid_argument);
}

TEST(MassPropertiesMesh, RejectsOpenInconsistentInsideOutAndBadInput) {
  const Mesh box = test::box_mesh(Vec3(1, 1, 1));
  const auto message_of = [](const Mesh& m) {
    try {
      mass_of(m, 1.0);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  Mesh open = box;
  open.triangles.pop_back();
  EXPECT_NE(message_of(open).find("open"), std::string::npos) << message_of(open);
  Mesh flipped_one = box;
  std::swap(flipped_one.triangles[3][1], flipped_one.triangles[3][2]);
  EXPECT_NE(message_of(flipped_one).find("consistently oriented"), std::string::npos)
      << message_of(flipped_one);
  Mesh inside_out = box;
  for (auto& t : inside_out.triangles) std::swap(t[1], t[2]);
  EXPECT_NE(message_of(inside_out).find("inside out"), std::string::npos) << message_of(inside_out);
  Mesh bad_index = box;
  bad_index.triangles[0][0] = 99;
  EXPECT_NE(message_of(bad_index).find(">= vertex count"), std::string::npos);
  Mesh flat;  // a square, both sides (different diagonals): closed, oriented, zero volume
  flat.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)};
  flat.triangles = {{0, 1, 3}, {0, 3, 2}, {0, 2, 1}, {1, 2, 3}};
  EXPECT_NE(message_of(flat).find("flat"), std::string::npos) << message_of(flat);
  EXPECT_THROW(mesh_mass(box.vertices, box.triangles, -1.0), std::invalid_argument);
}

TEST(MassPropertiesCompound, CapsuleIsCylinderPlusTwoHemispheres) {
  const double r = 0.4, h = 0.75, rho = 900.0;
  const MassProperties cap = capsule_mass(r, h, rho);
  const MassProperties hemi = hemisphere_mass(r, rho);
  // Top hemisphere: flat face at z = h, dome up. Bottom: turned over (π about x), face at -h.
  const std::vector<MassPart> parts = {
      {cylinder_mass(r, h, rho), Vec3::Zero(), Mat3::Identity()},
      {hemi, Vec3(0, 0, h), Mat3::Identity()},
      {hemi, Vec3(0, 0, -h), rotation(kPi, Vec3::UnitX())},
  };
  expect_same(combine(parts), cap, 1e-14);
  // The pitfall the closed form avoids: the sphere's 2/5 m r² shifted by h is too small.
  const MassProperties sphere = sphere_mass(r, rho);
  const double naive =
      cylinder_mass(r, h, rho).inertia(0, 0) + sphere.inertia(0, 0) + sphere.mass * h * h;
  EXPECT_GT(cap.inertia(0, 0) - naive, 0.01 * cap.inertia(0, 0));
  // A capsule of zero length is the sphere; two hemispheres face to face are the sphere.
  expect_same(capsule_mass(r, 0.0, rho), sphere, 1e-15);
  const std::vector<MassPart> halves = {{hemi, Vec3::Zero(), Mat3::Identity()},
                                        {hemi, Vec3::Zero(), rotation(kPi, Vec3::UnitY())}};
  expect_same(combine(halves), sphere, 1e-15);
}

TEST(MassPropertiesCompound, HemisphereMatchesAFineMesh) {
  const double r = 0.5;
  const MassProperties mesh = mass_of(test::hemisphere_mesh(r, 256, 128), 1.0);
  const MassProperties exact = hemisphere_mass(r, 1.0);
  EXPECT_NEAR(mesh.center_of_mass.z(), exact.center_of_mass.z(), 1e-3 * r);
  EXPECT_LE(rel_diff(mesh.inertia, exact.inertia), 1e-3) << mesh.inertia;
  EXPECT_NEAR(mesh.volume, exact.volume, 1e-3 * exact.volume);
}

TEST(MassPropertiesCompound, TwoBoxesSideBySideAreOneBoxOfDoubleLength) {
  const Vec3 h(0.5, 0.25, 0.1);
  const MassProperties one = box_mass(h, 100.0);
  const std::vector<MassPart> parts = {{one, Vec3(-h.x(), 0, 0), Mat3::Identity()},
                                       {one, Vec3(h.x(), 0, 0), Mat3::Identity()}};
  expect_same(combine(parts), box_mass(Vec3(2 * h.x(), h.y(), h.z()), 100.0), 1e-14);
  // Rotated and moved as a whole, the compound rotates like a single body.
  const Mat3 r = rotation(1.1, Vec3(0.3, 1.0, -0.4));
  const Vec3 t(1.0, 2.0, 3.0);
  std::vector<MassPart> moved = parts;
  for (auto& p : moved) {
    p.rotation = r;
    p.translation = r * p.translation + t;
  }
  expect_same(combine(moved), transformed(box_mass(Vec3(2 * h.x(), h.y(), h.z()), 100.0), r, t),
              1e-13);
  EXPECT_THROW(combine(std::span<const MassPart>{}), std::invalid_argument);
}

TEST(MassPropertiesPrincipal, AxesDiagonaliseAndAreRightHanded) {
  const Vec3 h(0.1, 0.4, 0.9);
  const Mat3 r = rotation(0.9, Vec3(1.0, 1.0, 0.2));
  const Mat3 inertia = r * box_mass(h, 10.0).inertia * r.transpose();
  const PrincipalAxes axes = principal_axes(inertia);
  const MassProperties box = box_mass(h, 10.0);
  // Ascending moments: the smallest is about the box's long axis (z), then y, then x.
  EXPECT_NEAR(axes.moments[0], box.inertia(2, 2), 1e-12);
  EXPECT_NEAR(axes.moments[1], box.inertia(1, 1), 1e-12);
  EXPECT_NEAR(axes.moments[2], box.inertia(0, 0), 1e-12);
  EXPECT_NEAR(axes.rotation.determinant(), 1.0, 1e-12);
  EXPECT_LE((axes.rotation.transpose() * axes.rotation - Mat3::Identity()).norm(), 1e-12);
  const Mat3 rebuilt = axes.rotation * axes.moments.asDiagonal() * axes.rotation.transpose();
  EXPECT_LE(rel_diff(rebuilt, inertia), 1e-12);
  // The principal axis of least inertia is the box's long axis, r e_z (up to sign).
  EXPECT_NEAR(std::abs(axes.rotation.col(0).dot(r.col(2))), 1.0, 1e-12);
  Mat3 asymmetric = inertia;
  asymmetric(0, 1) += 1.0;
  EXPECT_THROW(principal_axes(asymmetric), std::invalid_argument);
}

}  // namespace
}  // namespace simreel::sim::detail
