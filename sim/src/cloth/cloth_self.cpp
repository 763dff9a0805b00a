// Self-collision and cloth–cloth contacts (Bridson, Fedkiw & Anderson 2002; Coutinho §3.9.2).
#include "cloth/cloth_self.hpp"

#include "cloth/cloth_state.hpp"

namespace simreel::sim::detail {

ContactCloth ClothAccess::view(Cloth& c) { return c.s_->contact_view(); }
void ClothAccess::refresh(Cloth& c) { c.s_->refresh_views(); }

ContactStats collide_cloths(std::vector<Cloth>& cloths, const std::vector<Collider>& colliders,
                            double h, ContactScratch& scratch, BodyImpulses* impulses) {
  bool self = false;
  std::size_t others = 0;
  for (Cloth& c : cloths) {
    const ClothDef& d = c.definition();
    self |= d.self_collision;
    others += d.collide_cloths ? 1 : 0;
  }
  if (!self && others < 2) return {};
  thread_local std::vector<ContactCloth> views;
  views.clear();
  bool collide = false;
  for (Cloth& c : cloths) {
    views.push_back(ClothAccess::view(c));
    collide |= c.definition().collide;
  }
  // Cloths that do not collide with colliders still get no collider features: the features
  // are shared, so only pass them when every cloth collides.
  for (Cloth& c : cloths) collide &= c.definition().collide;
  ContactStats st = collide_cloth_features(views, collide && !colliders.empty() ? &colliders : nullptr,
                                           true, h, scratch, impulses);
  if (st.contacts > 0 || st.failsafe > 0)
    for (Cloth& c : cloths) ClothAccess::refresh(c);
  return st;
}

}  // namespace simreel::sim::detail
