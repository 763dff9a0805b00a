// Mass properties: primitive closed forms, signed-tetrahedron sums over closed triangle meshes,
// compounds, principal axes (Coutinho App. D; Mirtich 1996).
#include "rigid/mass_properties.hpp"
#include "simreel/sim/ranges.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace simreel::sim::detail {
namespace {

constexpr double kPi = std::numbers::pi;

void require_positive(double value, const char* what, const char* name) {
  if (!(std::isfinite(value) && value > 0.0)) {
    std::ostringstream m;
    m << what << ": " << name << " must be a positive finite number, got " << value;
    throw std::invalid_argument(m.str());
  }
}

/// Diagonal inertia diag(ixx, iyy, izz).
Mat3 diagonal(double ixx, double iyy, double izz) { return Vec3(ixx, iyy, izz).asDiagonal(); }

/// Directed edge a→b as one sortable key.
std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  return (std::uint64_t(a) << 32) | std::uint64_t(b);
}

}  // namespace

std::string closed_oriented_error(std::span<const std::array<std::uint32_t, 3>> triangles) {
  // Closed and consistently oriented <=> every directed edge a→b occurs exactly once and its
  // opposite b→a occurs too (each edge shared by exactly two triangles wound opposite ways
  // along it). A sorted vector, not a hash set, so the error reported does not depend on hashing.
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * triangles.size());
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) edges.push_back(edge_key(t[k], t[(k + 1) % 3]));
  std::sort(edges.begin(), edges.end());
  const auto name = [](std::uint64_t e) {
    return std::to_string(e >> 32) + "->" + std::to_string(e & 0xffffffffu);
  };
  for (std::size_t i = 1; i < edges.size(); ++i)
    if (edges[i] == edges[i - 1])
      return "edge " + name(edges[i]) +
             " is used twice in the same direction: triangles are not consistently oriented (or "
             "the edge is shared by more than two triangles)";
  for (const std::uint64_t e : edges) {
    const std::uint64_t opposite = ((e & 0xffffffffu) << 32) | (e >> 32);
    if (!std::binary_search(edges.begin(), edges.end(), opposite))
      return "the mesh is open: edge " + name(e) + " has no triangle on its other side";
  }
  return {};
}

MassProperties sphere_mass(double radius, double density) {
  require_positive(radius, "sphere_mass", "radius");
  require_positive(density, "sphere_mass", "density");
  MassProperties p;
  p.volume = 4.0 / 3.0 * kPi * radius * radius * radius;
  p.mass = density * p.volume;
  const double i = 0.4 * p.mass * radius * radius;
  p.inertia = diagonal(i, i, i);
  return p;
}

MassProperties box_mass(const Vec3& half_extents, double density) {
  for (int k = 0; k < 3; ++k) require_positive(half_extents[k], "box_mass", "half_extents");
  require_positive(density, "box_mass", "density");
  const Vec3 h2 = half_extents.cwiseProduct(half_extents);
  MassProperties p;
  p.volume = 8.0 * half_extents.prod();
  p.mass = density * p.volume;
  p.inertia = diagonal(h2.y() + h2.z(), h2.z() + h2.x(), h2.x() + h2.y()) * (p.mass / 3.0);
  return p;
}

MassProperties cylinder_mass(double radius, double half_height, double density) {
  require_positive(radius, "cylinder_mass", "radius");
  require_positive(half_height, "cylinder_mass", "half_height");
  require_positive(density, "cylinder_mass", "density");
  const double r2 = radius * radius, h2 = half_height * half_height;
  MassProperties p;
  p.volume = kPi * r2 * 2.0 * half_height;
  p.mass = density * p.volume;
  // m (3 r² + H²)/12 with H = 2h is m (r²/4 + h²/3).
  const double ixx = p.mass * (r2 / 4.0 + h2 / 3.0);
  p.inertia = diagonal(ixx, ixx, 0.5 * p.mass * r2);
  return p;
}

MassProperties hemisphere_mass(double radius, double density) {
  require_positive(radius, "hemisphere_mass", "radius");
  require_positive(density, "hemisphere_mass", "density");
  const double r2 = radius * radius;
  MassProperties p;
  p.volume = 2.0 / 3.0 * kPi * r2 * radius;
  p.mass = density * p.volume;
  p.center_of_mass = Vec3(0.0, 0.0, 3.0 / 8.0 * radius);
  // About the flat face's centre I_xx = 2/5 m r² (half a sphere); moving to the centre of mass
  // subtracts m (3r/8)² = 45/320 m r², leaving 83/320 m r².
  const double ixx = 83.0 / 320.0 * p.mass * r2;
  p.inertia = diagonal(ixx, ixx, 0.4 * p.mass * r2);
  return p;
}

MassProperties capsule_mass(double radius, double half_height, double density) {
  require_positive(radius, "capsule_mass", "radius");
  require_positive(density, "capsule_mass", "density");
  if (!(std::isfinite(half_height) && half_height >= 0.0))
    throw std::invalid_argument("capsule_mass: half_height must be finite and >= 0, got " +
                                format_number(half_height));
  const double r = radius, h = half_height, r2 = r * r;
  const double v_cyl = kPi * r2 * 2.0 * h;
  const double v_sph = 4.0 / 3.0 * kPi * r2 * r;
  const double m_cyl = density * v_cyl, m_sph = density * v_sph;
  // Each hemisphere's centre of mass lies h + 3r/8 from the capsule centre: its own 83/320 m r²
  // plus the parallel-axis term m (h + 3r/8)², not the sphere's 2/5 m r² shifted by h.
  const double arm = h + 3.0 / 8.0 * r;
  const double ixx = m_cyl * (r2 / 4.0 + h * h / 3.0) + m_sph * (83.0 / 320.0 * r2 + arm * arm);
  const double izz = 0.5 * m_cyl * r2 + 0.4 * m_sph * r2;
  MassProperties p;
  p.volume = v_cyl + v_sph;
  p.mass = m_cyl + m_sph;
  p.inertia = diagonal(ixx, ixx, izz);
  return p;
}

MassProperties mesh_mass(std::span<const Vec3> vertices,
                         std::span<const std::array<std::uint32_t, 3>> triangles, double density) {
  require_positive(density, "mesh_mass", "density");
  if (triangles.size() < 4)
    throw std::invalid_argument("mesh_mass: a closed mesh needs at least 4 triangles, got " +
                                std::to_string(triangles.size()));
  const auto n = vertices.size();
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const auto& tri = triangles[t];
    for (const std::uint32_t i : tri)
      if (i >= n)
        throw std::invalid_argument("mesh_mass: triangle " + std::to_string(t) + " has index " +
                                    std::to_string(i) + " >= vertex count " + std::to_string(n));
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0])
      throw std::invalid_argument("mesh_mass: triangle " + std::to_string(t) +
                                  " repeats a vertex index");
  }
  Vec3 origin = Vec3::Zero();
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (std::size_t i = 0; i < n; ++i) {
    if (!vertices[i].allFinite())
      throw std::invalid_argument("mesh_mass: vertex " + std::to_string(i) + " is not finite");
    origin += vertices[i];
    lo = lo.cwiseMin(vertices[i]);
    hi = hi.cwiseMax(vertices[i]);
  }
  origin /= double(n);
  if (const std::string error = closed_oriented_error(triangles); !error.empty())
    throw std::invalid_argument("mesh_mass: " + error);

  // Sums over the tetrahedra (origin, a, b, c), each weighted by d = det[a b c] = 6 V_tet
  // (coordinates relative to `origin`): Σ d, Σ d s and Σ d (aaᵀ + bbᵀ + ccᵀ + s sᵀ), s = a+b+c.
  double sum_d = 0.0;
  Vec3 sum_first = Vec3::Zero();
  Mat3 sum_second = Mat3::Zero();
  for (const auto& tri : triangles) {
    const Vec3 a = vertices[tri[0]] - origin;
    const Vec3 b = vertices[tri[1]] - origin;
    const Vec3 c = vertices[tri[2]] - origin;
    const double d = a.dot(b.cross(c));
    const Vec3 s = a + b + c;
    sum_d += d;
    sum_first += d * s;
    sum_second +=
        d * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
  }
  const double volume = sum_d / 6.0;
  // Non-positive volume: inside out (clockwise winding) or flat. The threshold is relative to the
  // bounding box so that rounding on a flat mesh is not mistaken for a body.
  const double diag = (hi - lo).norm();
  if (!(volume > 1e-12 * diag * diag * diag)) {
    std::ostringstream m;
    m << "mesh_mass: the enclosed volume is " << volume << " m^3, not positive: "
      << (volume < 0.0 ? "the mesh is inside out (triangles wound clockwise seen from outside)"
                       : "the mesh is flat");
    throw std::invalid_argument(m.str());
  }
  // ∫ r dV = Σ V_tet s/4 = Σ d s / 24;  ∫ r rᵀ dV = Σ V_tet/20 (…) = Σ d (…) / 120.
  const Vec3 com = sum_first / (24.0 * volume);
  const Mat3 second_about_com = sum_second / 120.0 - volume * com * com.transpose();
  MassProperties p;
  p.volume = volume;
  p.mass = density * volume;
  p.center_of_mass = origin + com;
  p.inertia = density * (second_about_com.trace() * Mat3::Identity() - second_about_com);
  // Exact symmetry (the sums are symmetric up to rounding in the subtraction).
  p.inertia = 0.5 * (p.inertia + p.inertia.transpose()).eval();
  return p;
}

MassProperties with_mass(const MassProperties& props, double mass) {
  require_positive(mass, "with_mass", "mass");
  require_positive(props.mass, "with_mass", "props.mass");
  MassProperties p = props;
  const double scale = mass / props.mass;
  p.mass = mass;
  p.inertia *= scale;
  return p;
}

MassProperties transformed(const MassProperties& props, const Mat3& rotation,
                           const Vec3& translation) {
  MassProperties p = props;
  p.center_of_mass = rotation * props.center_of_mass + translation;
  p.inertia = rotation * props.inertia * rotation.transpose();
  return p;
}

MassProperties combine(std::span<const MassPart> parts) {
  if (parts.empty()) throw std::invalid_argument("combine: no parts");
  MassProperties total;
  Vec3 weighted = Vec3::Zero();
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (!(parts[i].props.mass > 0.0))
      throw std::invalid_argument("combine: part " + std::to_string(i) + " has non-positive mass " +
                                  format_number(parts[i].props.mass));
    const auto& part = parts[i];
    total.mass += part.props.mass;
    total.volume += part.props.volume;
    weighted += part.props.mass * (part.rotation * part.props.center_of_mass + part.translation);
  }
  total.center_of_mass = weighted / total.mass;
  for (const auto& part : parts) {
    const MassProperties moved = transformed(part.props, part.rotation, part.translation);
    const Vec3 d = moved.center_of_mass - total.center_of_mass;
    total.inertia +=
        moved.inertia + part.props.mass * (d.squaredNorm() * Mat3::Identity() - d * d.transpose());
  }
  return total;
}

PrincipalAxes principal_axes(const Mat3& inertia) {
  const double scale = inertia.cwiseAbs().maxCoeff();
  if (!inertia.allFinite() || (inertia - inertia.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale)
    throw std::invalid_argument("principal_axes: the inertia tensor is not finite and symmetric");
  const Eigen::SelfAdjointEigenSolver<Mat3> solver(inertia);
  PrincipalAxes axes;
  axes.moments = solver.eigenvalues();  // ascending
  axes.rotation = solver.eigenvectors();
  // Eigenvectors are defined up to sign; flip the last so that x × y = z.
  if (axes.rotation.determinant() < 0.0) axes.rotation.col(2) *= -1.0;
  return axes;
}

}  // namespace simreel::sim::detail
