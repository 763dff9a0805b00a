#pragma once
// Mass properties of rigid bodies: closed forms for the primitive shapes, exact integrals over
// closed triangle meshes, compounds by the parallel-axis theorem, principal axes (Coutinho
// App. D; Mirtich 1996, "Fast and Accurate Computation of Polyhedral Mass Properties").
// Private; the public BodyDef/ShapeDef come with the rigid-body issue.
//
// Frames: every result is in the shape's own (body) frame. `center_of_mass` is a position in
// that frame; `inertia` is taken about the centre of mass with axes parallel to that frame.
// Inertia convention: I = ∫ρ ((r·r) E - r rᵀ) dV, so the products of inertia carry the minus
// sign (I_xy = -∫ρ x y dV), Coutinho eq. (D.4).

#include <array>
#include <cstdint>
#include <span>
#include <string>

#include "simreel/sim/types.hpp"

namespace simreel::sim::detail {

/// Mass, centre of mass, inertia and volume of a rigid body in its own frame.
struct MassProperties {
  double mass = 0.0;                   ///< (kg) > 0
  Vec3 center_of_mass = Vec3::Zero();  ///< (m) body frame
  Mat3 inertia = Mat3::Zero();         ///< (kg m²) about the centre of mass, body-frame axes
  double volume = 0.0;                 ///< (m³) > 0
};

/// Solid sphere of `radius` (m) centred at the origin; `density` (kg/m³).
/// V = 4/3 π r³, I = 2/5 m r² E. Throws std::invalid_argument if radius or density is not a
/// positive finite number.
MassProperties sphere_mass(double radius, double density);

/// Solid box centred at the origin with `half_extents` (m) along x, y, z; `density` (kg/m³).
/// V = 8 hx hy hz, I_xx = m/3 (hy² + hz²) and cyclic. Throws std::invalid_argument on a
/// non-positive or non-finite extent or density.
MassProperties box_mass(const Vec3& half_extents, double density);

/// Solid cylinder along z, centred at the origin: `radius` (m), `half_height` (m) (z in
/// [-half_height, half_height]); `density` (kg/m³). With H = 2 half_height:
/// V = π r² H, I_zz = m r²/2, I_xx = I_yy = m (3 r² + H²)/12. Throws std::invalid_argument on a
/// non-positive or non-finite argument.
MassProperties cylinder_mass(double radius, double half_height, double density);

/// Solid hemisphere of `radius` (m): flat face on z = 0, dome towards +z; `density` (kg/m³).
/// V = 2/3 π r³, centre of mass (0, 0, 3r/8), I_zz = 2/5 m r², I_xx = I_yy = 83/320 m r² (about
/// the centre of mass). The building block of the capsule. Throws std::invalid_argument on a
/// non-positive or non-finite argument.
MassProperties hemisphere_mass(double radius, double density);

/// Solid capsule along z, centred at the origin: a cylinder of `radius` (m) over
/// z in [-half_height, half_height] closed by two hemispheres of the same radius (total length
/// 2 half_height + 2 radius); `density` (kg/m³). half_height = 0 is a sphere.
/// With m_c = ρ π r² 2h and m_s = ρ 4/3 π r³ (both hemispheres):
///   I_zz = m_c r²/2 + 2/5 m_s r²,
///   I_xx = I_yy = m_c (r²/4 + h²/3) + m_s (83/320 r² + (h + 3r/8)²)
/// — each hemisphere's own 83/320 m r² moved by the parallel-axis theorem from its centre of
/// mass, h + 3r/8 from the capsule's centre. Throws std::invalid_argument on a non-positive
/// radius or density, a negative half_height, or a non-finite argument.
MassProperties capsule_mass(double radius, double half_height, double density);

/// Solid bounded by a closed triangle mesh, uniform `density` (kg/m³).
///
/// `vertices` (n) are positions (m) in the body frame; `triangles` (m) index them, each wound
/// counter-clockwise seen from outside (outward normal (b - a) × (c - a)), the convention of
/// MeshDef and of convex_hull().
///
/// Method: signed-tetrahedron sums, the triangle case of the divergence theorem of Coutinho
/// App. D / Mirtich 1996. Each triangle (a, b, c) spans with a reference point o a tetrahedron of
/// signed volume det[a-o, b-o, c-o]/6; its first and second moments are exact polynomials of the
/// vertices (∫ r dV = V s/4, ∫ r rᵀ dV = V/20 (Σ p pᵀ + s sᵀ), s = sum of the four corners), and
/// the signed sums over a closed surface are the integrals over the solid. It is the same
/// integral as Mirtich's projection/face/line integrals, specialised to triangles: no choice of
/// projection plane per face and no division by a normal component, so it is shorter and keeps
/// its accuracy on faces nearly perpendicular to a coordinate plane; it is exact for polyhedra
/// up to rounding. The reference point o is the mean of the vertices, so a mesh far from the
/// origin loses no digits to cancellation.
///
/// Checks, each a std::invalid_argument naming the problem: fewer than 4 triangles, an index out
/// of range, a triangle with a repeated index, a non-finite vertex, a non-positive or non-finite
/// density; an open mesh (an edge a→b without a triangle holding b→a); inconsistent orientation
/// or a non-manifold edge (an edge a→b used by two triangles); a volume that is not positive
/// (at most 1e-12 × the cube of the bounding-box diagonal: a flat mesh). An inside-out mesh (every
/// triangle wound clockwise from outside) is rejected by that last check rather than silently
/// flipped: a reversed winding is usually an export bug that would also turn the collision normals
/// inwards.
MassProperties mesh_mass(std::span<const Vec3> vertices,
                         std::span<const std::array<std::uint32_t, 3>> triangles, double density);

/// Empty if `triangles` form a closed, consistently oriented surface (every directed edge a→b
/// used by exactly one triangle and its opposite b→a by another); otherwise what is wrong, naming
/// the first offending edge. Indices are not range-checked here.
std::string closed_oriented_error(std::span<const std::array<std::uint32_t, 3>> triangles);

/// The same body with its mass set to `mass` (kg) instead of coming from a density: mass and
/// inertia scale by mass / props.mass; centre of mass and volume are unchanged. Throws
/// std::invalid_argument if `mass` is not positive and finite or props.mass is not positive.
MassProperties with_mass(const MassProperties& props, double mass);

/// One part of a compound: its own mass properties and the pose of its frame in the compound
/// frame, x_compound = rotation · x_part + translation.
struct MassPart {
  MassProperties props;
  Vec3 translation = Vec3::Zero();   ///< (m) part origin in the compound frame
  Mat3 rotation = Mat3::Identity();  ///< part axes in the compound frame (proper rotation)
};

/// Mass properties of `props` after moving the body by x' = rotation · x + translation:
/// centre of mass rotation · c + translation, inertia rotation · I · rotationᵀ.
MassProperties transformed(const MassProperties& props, const Mat3& rotation,
                           const Vec3& translation);

/// Combines the parts of a compound body (parts must not overlap: volumes and masses add).
/// Mass M = Σ m_i; centre C = Σ m_i c_i / M with c_i = R_i c_i' + t_i; inertia about C by the
/// parallel-axis theorem, I = Σ R_i I_i R_iᵀ + m_i ((d_i·d_i) E - d_i d_iᵀ), d_i = c_i - C
/// (Coutinho App. D, eq. D.1–D.3 summed over polyhedra). Throws std::invalid_argument on an
/// empty list or a part with non-positive mass.
MassProperties combine(std::span<const MassPart> parts);

/// Principal axes of an inertia tensor: inertia = rotation · diag(moments) · rotationᵀ.
struct PrincipalAxes {
  Vec3 moments = Vec3::Zero();       ///< (kg m²) principal moments, ascending
  Mat3 rotation = Mat3::Identity();  ///< columns: unit principal axes in the body frame;
                                     ///< a proper rotation (det = +1, right-handed)
};

/// Eigen-decomposition of a symmetric inertia tensor (Eigen::SelfAdjointEigenSolver); the
/// third axis is flipped if needed so that the axes form a right-handed frame. Throws
/// std::invalid_argument if `inertia` is not finite and symmetric (relative 1e-9).
PrincipalAxes principal_axes(const Mat3& inertia);

}  // namespace simreel::sim::detail
