#pragma once
// Particles against cloth triangles with the impulse shared by the triangle's vertices (private).

#include <vector>

#include "collision/bvh.hpp"
#include "particles/particle_store.hpp"
#include "simreel/sim/cloth.hpp"

namespace simreel::sim::detail {

/// Reusable buffers of the pass (one per World: no allocation per particle).
struct ClothParticleScratch {
  std::vector<Triangle> triangles;
  std::vector<Vec3> shift;    ///< per triangle: centroid displacement over the step (m)
  std::vector<Vec3> impulse;  ///< per vertex (N s)
};

/// Collides the particles of `s` (moved over the step of length h already) with the triangles
/// of `cloth` (stepped over the same interval). Each particle is swept as a sphere of radius
/// (particle radius + cloth thickness) from its start-of-step to its end position, in the frame
/// translating with each candidate triangle's centroid, against the end-of-step triangle
/// (narrow_phase.hpp: face, edges, vertices; exact for a translating triangle, first order for a
/// deforming one). Candidates come from an AABB tree over the end-of-step triangles (Coutinho
/// §2.2), queried with the particle's box grown by the largest vertex displacement.
/// At the first contact (one per particle per step) the impulse J follows Coutinho §3.6.1 with
/// the triangle's contact point as the second body: its velocity Σ w_k v_k and inverse mass
/// Σ w_k² / m_k (barycentric weights w, pinned vertices infinitely heavy); the relative normal
/// velocity becomes -e v_n (e = ClothDef::restitution) and Coulomb friction
/// (ClothDef::friction) removes at most μ|J_n| of tangential momentum, never reversing the
/// slide. The particle gets J / m (J recomputed from its float velocity after rounding, so
/// momentum balances exactly), ends at the contact plus the rest of the step at its new
/// relative velocity, and each vertex k gets -w_k J: total momentum of particles + cloth is
/// conserved (exactly but for rounding when no vertex is pinned).
/// @returns the number of particle contacts.
std::size_t collide_particles_with_cloth(ParticleStore& s, double h, Cloth& cloth,
                                         ClothParticleScratch& scratch);

}  // namespace simreel::sim::detail
