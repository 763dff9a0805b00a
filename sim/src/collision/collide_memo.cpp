// The environment check of the collision pass's response memo (collide_memo.hpp).
#include "collision/collide_memo.hpp"

#include <algorithm>
#include <cstring>

namespace simreel::sim::detail {

namespace {

// Bit for bit: -0 and +0 differ, and a NaN equals only its own bits, so "the same" can never
// let two environments through that the pass would treat differently.
template <class T>
bool same_bits(const T& a, const T& b) {
  static_assert(std::is_trivially_copyable_v<T>);
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}

template <class M>
bool same_matrix(const M& a, const M& b) {
  return std::memcmp(a.data(), b.data(), sizeof(typename M::Scalar) * std::size_t(a.size())) == 0;
}

bool same_split(const SplitOnHit& a, const SplitOnHit& b) {
  return same_bits(a.min_radius, b.min_radius) && a.count == b.count &&
         same_bits(a.speed_fraction, b.speed_fraction) &&
         same_bits(a.size_fraction, b.size_fraction) && same_bits(a.lifetime, b.lifetime) &&
         same_bits(a.spread_deg, b.spread_deg);
}

bool same_material(const Material& a, const Material& b) {
  return same_bits(a.restitution, b.restitution) && same_bits(a.friction, b.friction) &&
         same_bits(a.static_friction, b.static_friction) && a.on_hit == b.on_hit &&
         same_split(a.split, b.split);
}

// Every field of a Collider, so that a field added later and left out here is caught by review
// of this one list rather than silently ignored.
bool same_collider(const Collider& a, const Collider& b) {
  return a.shape == b.shape && same_material(a.material, b.material) &&
         same_matrix(a.point, b.point) && same_matrix(a.normal, b.normal) &&
         same_matrix(a.local_normal, b.local_normal) &&
         same_matrix(a.half_extents, b.half_extents) && same_bits(a.radius, b.radius) &&
         same_bits(a.half_height, b.half_height) && a.mesh == b.mesh && a.hull == b.hull &&
         same_matrix(a.offset.translation, b.offset.translation) &&
         same_matrix(a.offset.rotation.coeffs(), b.offset.rotation.coeffs()) &&
         a.offset_identity == b.offset_identity && a.moving == b.moving &&
         same_matrix(a.center, b.center) && same_matrix(a.rotation.coeffs(), b.rotation.coeffs()) &&
         same_matrix(a.R, b.R) && same_matrix(a.velocity, b.velocity) &&
         same_matrix(a.angular_velocity, b.angular_velocity) &&
         same_matrix(a.prev_center, b.prev_center) && same_matrix(a.prev_R, b.prev_R) &&
         a.unposed == b.unposed && same_matrix(a.aabb_center, b.aabb_center) &&
         same_matrix(a.aabb_half, b.aabb_half);
}

bool same_forces(const ForceParams& a, const ForceParams& b) {
  return std::memcmp(a.gravity, b.gravity, sizeof a.gravity) == 0 && same_bits(a.drag, b.drag) &&
         same_bits(a.drag_quadratic, b.drag_quadratic) && same_bits(a.max_speed, b.max_speed) &&
         same_bits(a.max_distance, b.max_distance);
}

}  // namespace

std::uint32_t CollideMemo::begin_pass(ParticleStore& s, const std::vector<Collider>& colliders,
                                      const ForceParams& f, double h, double contact_speed,
                                      const HitAction* on_hit, const SplitOnHit* on_hit_split) {
  reused = 0;
  if (!s.track_memo) {
    // From now on the store keeps the columns through appends and compaction; reserved for the
    // store's capacity, so that emission does not reallocate them.
    s.track_memo = true;
    s.memo.reserve(kStride * s.age.capacity());
    s.memo_epoch.reserve(s.age.capacity());
  }
  if (s.memo.size() != kStride * s.count || s.memo_epoch.size() != s.count) {
    // First use, or the particles were replaced wholesale (a loaded state): no entries.
    s.memo.assign(kStride * s.count, 0.0f);
    s.memo_epoch.assign(s.count, 0u);
  }
  bool same = have_env_ && colliders.size() == colliders_.size() && same_forces(f, forces_) &&
              same_bits(h, h_) && same_bits(contact_speed, contact_speed_) &&
              has_on_hit_ == (on_hit != nullptr);
  const SplitOnHit split = on_hit_split != nullptr ? *on_hit_split : SplitOnHit{};
  if (same && on_hit != nullptr) same = *on_hit == on_hit_ && same_split(split, on_hit_split_);
  for (std::size_t k = 0; same && k < colliders.size(); ++k)
    same = same_collider(colliders[k], colliders_[k]);
  if (same) return epoch_;
  have_env_ = true;
  colliders_ = colliders;
  forces_ = f;
  h_ = h;
  contact_speed_ = contact_speed;
  has_on_hit_ = on_hit != nullptr;
  if (on_hit != nullptr) on_hit_ = *on_hit;
  on_hit_split_ = split;
  if (++epoch_ == 0) {  // wrapped: no entry may carry an epoch that names this environment
    std::fill(s.memo_epoch.begin(), s.memo_epoch.end(), 0u);
    epoch_ = 1;
  }
  return epoch_;
}

}  // namespace simreel::sim::detail
