#pragma once
// Self-collision and cloth–cloth contacts over all of a world's cloths (private); the pass itself
// is collide_cloth_features (cloth_contacts.hpp).

#include <vector>

#include "cloth/cloth_contacts.hpp"
#include "simreel/sim/cloth.hpp"

namespace simreel::sim::detail {

/// Reaches a Cloth's state for the passes that see several cloths at once.
struct ClothAccess {
  static ContactCloth view(Cloth& c);
  static void refresh(Cloth& c);  ///< float views after a change of state
  /// The maximum-deformation pass again (§3.9.2) over the step's paths; true if it moved a vertex.
  static bool limit_strain(Cloth& c);
};

/// After every cloth stepped over [t0, t0 + h]: vertex–triangle and edge–edge contacts of each
/// cloth with ClothDef::self_collision against itself and between cloths that both allow
/// ClothDef::collide_cloths, with the collider features (and planes) kept in the same rounds so
/// a fold pushed apart is not pushed into a collider. Does nothing when no cloth asks for it.
/// Velocities are corrected with the positions (x = x_start + h v).
ContactStats collide_cloths(std::vector<Cloth>& cloths, const std::vector<Collider>& colliders,
                            double h, ContactScratch& scratch, BodyImpulses* impulses);

}  // namespace simreel::sim::detail
