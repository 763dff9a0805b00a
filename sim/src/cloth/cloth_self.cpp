// Self-collision and cloth–cloth contacts (Bridson, Fedkiw & Anderson 2002; Coutinho §3.9.2).
#include "cloth/cloth_self.hpp"

#include "cloth/cloth_state.hpp"

namespace simreel::sim::detail {

constexpr int kStrainRounds = 3;  // strain pass -> contacts, after the first contact pass

ContactCloth ClothAccess::view(Cloth& c) { return c.s_->contact_view(); }
void ClothAccess::refresh(Cloth& c) { c.s_->refresh_views(); }
bool ClothAccess::limit_strain(Cloth& c) { return c.s_->max_deformation_pass(); }

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
  const std::vector<Collider>* cs = collide && !colliders.empty() ? &colliders : nullptr;
  scratch.rebuild = true;  // a new step: the contact tree is rebuilt once, then refitted
  ContactStats st = collide_cloth_features(views, cs, true, h, scratch, impulses);
  // The contacts may stretch springs past the limit: the strain pass again, then the contacts
  // again, a few times; the contacts have the last word (folds never cross).
  for (int round = 0; round < kStrainRounds && (st.contacts > 0 || st.failsafe > 0); ++round) {
    bool moved = false;
    for (Cloth& c : cloths) moved |= ClothAccess::limit_strain(c);
    if (!moved) break;
    const ContactStats again = collide_cloth_features(views, cs, true, h, scratch, impulses);
    st.contacts += again.contacts;
    st.failsafe += again.failsafe;
    if (again.contacts == 0 && again.failsafe == 0) break;
  }
  if (st.contacts > 0 || st.failsafe > 0)
    for (Cloth& c : cloths) ClothAccess::refresh(c);
  return st;
}

}  // namespace simreel::sim::detail
