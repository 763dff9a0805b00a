#pragma once
// Triangle and edge contacts of cloth (private): cloth triangles against collider corners and
// sphere centres, cloth edges against collider edges and axes (a box's edge, a thin pole, a
// mesh's sharp ridge), and optionally cloth against itself and against other cloths.
//
// What was chosen (Bridson, Fedkiw & Anderson 2002, "Robust treatment of collisions, contact and
// friction for cloth animation"): the vertex–triangle and edge–edge pairs of that paper, found
// over an AABB tree of the cloth triangles' swept boxes (Coutinho §2.2), each tested for
// proximity within a thickness at the end of the step and for a continuous crossing (the cubic
// coplanarity times of the four moving points, §4 of the paper) during it. Unlike the paper's
// velocity impulses, a contact is resolved on positions (Gauss-Seidel over the contacts, a few
// rounds of detect-and-resolve): the pair's separation along its normal is brought up to the
// thickness with the correction shared by inverse mass and barycentric weight, the tangential
// relative displacement is cut by friction × the normal correction (Coulomb, Coutinho §3.6.1),
// and every moved vertex's velocity takes the correction / h so that x = x_start + h v still
// holds. The normal side is the side the pair was on at the start of the step, so a pair found
// crossed is pushed back, not through. Contacts still present after the rounds (self and
// cloth–cloth only) fall back to the paper's failsafe in its simplest form: the vertices involved
// return to their start-of-step positions (which were free of intersections) at rest, repeated
// until no crossing remains. Colliders are immovable here (inverse mass 0); a dynamic body takes
// the opposite of the momentum the cloth gained through the impulse log (Coutinho §3.7).

#include <array>
#include <cstdint>
#include <vector>

#include "collision/body_impulses.hpp"
#include "collision/bvh.hpp"
#include "collision/collider_impl.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim {
class ClothTopology;
}

namespace simreel::sim::detail {

/// One cloth taking part in a contact pass (views into its state).
struct ContactCloth {
  std::vector<Vec3>* x = nullptr;         ///< end-of-step positions (m), corrected in place
  std::vector<Vec3>* v = nullptr;         ///< velocities (m/s), corrected in place
  const std::vector<Vec3>* x0 = nullptr;  ///< start-of-step positions (m)
  const std::vector<std::uint8_t>* free = nullptr;
  const ClothTopology* topo = nullptr;
  double vertex_mass = 0.0;  ///< (kg)
  double thickness = 0.0;    ///< (m)
  double friction = 0.0;
  bool self = false;         ///< test this cloth against itself
  bool others = false;       ///< test this cloth against other cloths (both must allow it)
  /// When set (n each): a vertex a kinematic body's feature pushed gets hit = 2 and the push's
  /// direction in pushed_normal, as the vertex pass does (cloth_collide.hpp).
  std::vector<std::uint8_t>* hit = nullptr;
  std::vector<Vec3>* pushed_normal = nullptr;
};

/// Counters of one pass.
struct ContactStats {
  std::size_t contacts = 0;   ///< pair contacts resolved (over all rounds)
  std::size_t rounds = 0;     ///< detect-and-resolve rounds run
  std::size_t failsafe = 0;   ///< vertices returned to their start positions
  bool kinematic = false;     ///< a contact was with a kinematic (not dynamic) body's feature
};

/// Reusable buffers (no allocation per step once warm, except the AABB tree's).
struct ContactScratch {
  std::vector<Vec3> x0, x;          // node positions: cloth vertices then collider features
  std::vector<double> winv, radius;  // inverse mass (1/kg), feature radius (m)
  std::vector<std::int32_t> cloth_of;  // node -> cloth index, or -(1 + collider index)
  std::vector<std::uint32_t> offset;   // cloth -> first node
  std::vector<std::uint32_t> edge_offset, tri_offset;
  std::vector<std::array<std::uint32_t, 2>> segments;  // collider edges/axes (node ids)
  std::vector<std::uint32_t> points;                   // collider corners/centres (node ids)
  std::vector<std::int32_t> segment_collider, point_collider;
  /// Per feature, the direction (end pose, world) the cloth must stay on: outward from the solid
  /// at a box's or mesh's corner or edge; zero for sphere centres and axes (radius > 0), whose
  /// side is the one the pair started on.
  std::vector<Vec3> segment_out, point_out;
  std::vector<Triangle> boxes;  // swept triangle boxes encoded as triangles for Bvh
  /// The tree over `boxes`: built at the first round after `rebuild` is set (the caller sets it
  /// at the start of every step, so the tree is a function of the step's state, and a loaded
  /// state continues bit-identically), refitted in the rounds and calls after that.
  Bvh bvh;
  bool rebuild = true;
  /// The triangle boxes and their tree for the cloth–cloth and self pairs when those reach less
  /// far than the collider contacts (a cloth kept 0.5 m from colliders, whose self contacts
  /// stay within a quarter of its shortest edge): built and refitted with `bvh`. With boxes
  /// grown by the collider thickness, every triangle of a 2 m flag met every other and a step
  /// took seconds.
  std::vector<Triangle> pair_boxes;
  Bvh pair_bvh;
  std::vector<Vec3> edge_lo, edge_hi;  // swept boxes of the cloth edges (global edge order)
  struct Contact {
    std::array<std::uint32_t, 4> id{};
    std::array<double, 4> w{};
    int count = 0;
    Vec3 n = Vec3::Zero();
    double offset = 0.0;  // separation = n · Σ w x - offset
    double delta = 0.0;   // wanted separation (m)
    double friction = 0.0;
    std::int32_t collider = -1;
  };
  std::vector<Contact> contacts;
  std::vector<std::uint8_t> touched;
};

/// One pass over `cloths`: collider features of `colliders` (may be null) against every cloth,
/// and cloth–cloth / self pairs when `pairs` is set; planes of the colliders are kept as vertex
/// constraints in the same rounds. h: the step (s). Returns the counters.
ContactStats collide_cloth_features(std::vector<ContactCloth>& cloths,
                                    const std::vector<Collider>* colliders, bool pairs, double h,
                                    ContactScratch& scratch, BodyImpulses* impulses = nullptr);

}  // namespace simreel::sim::detail
