// World::state_hash: FNV-1a 64 over the bytes of the complete state in a fixed order (world.hpp).
#include <cstring>
#include <type_traits>

#include "core/world_impl.hpp"

namespace simreel::sim {

namespace {

/// FNV-1a, 64 bits (offset basis 0xcbf29ce484222325, prime 0x100000001b3).
class Fnv1a {
 public:
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h_ = (h_ ^ p[i]) * 0x100000001b3ULL;
  }
  template <class T>
  void value(const T& v) {
    static_assert(std::is_arithmetic_v<T>);
    bytes(&v, sizeof v);
  }
  /// The first n elements of an array (count included, so arrays cannot run into each other).
  template <class Array>
  void array(const Array& a, std::size_t n) {
    value(std::uint64_t(n));
    if (n > 0) bytes(a.data(), n * sizeof(typename Array::value_type));
  }
  void vec(const Vec3& v) {
    for (int k = 0; k < 3; ++k) value(v[k]);
  }
  void rng(const Rng& r) {
    const Rng::State s = r.state();
    for (std::uint64_t w : s.s) value(w);
    value(s.has_cached ? s.cached : 0.0);
    value(std::uint8_t(s.has_cached));
  }
  [[nodiscard]] std::uint64_t get() const { return h_; }

 private:
  std::uint64_t h_ = 0xcbf29ce484222325ULL;
};

}  // namespace

std::uint64_t World::state_hash() const {
  const detail::WorldState& w = *impl_;
  Fnv1a f;
  f.value(w.time);
  f.value(w.steps);
  f.value(std::uint64_t(w.systems.size()));
  for (const detail::ParticleSystemState& ps : w.systems.dense()) {
    const detail::ParticleStore& st = ps.store;
    const std::size_t n = st.count;
    f.value(std::uint64_t(n));
    f.array(st.position, 3 * n);
    f.array(st.velocity, 3 * n);
    f.array(st.prev_position, st.track_prev ? 3 * n : 0);
    f.array(st.color, 4 * n);
    f.array(st.radius, n);
    f.array(st.mass, n);
    f.array(st.age, n);
    f.array(st.lifetime, n);
    f.array(st.id, n);
    f.array(st.charge, st.has_charge ? n : 0);
    f.array(st.base_radius, n);
    f.array(st.tint, n);
    f.array(st.split_generation, n);
    f.array(st.split_countdown, n);
    // Only with sub-emitters (which read it), so the hashes of scenes before them are unchanged.
    if (!ps.sub_emitters.empty()) f.array(st.from_split, n);
    f.array(st.rest, st.track_rest ? 4 * n : 0);
    f.value(ps.next_id);
    f.value(ps.emitter.scheduled);
    f.array(ps.emitter.bursts_fired, ps.emitter.bursts_fired.size());
    f.rng(ps.emitter.rng);
    f.rng(ps.split_rng);
    f.rng(ps.charge_rng);
    f.rng(ps.splash_rng);
  }
  f.value(std::uint64_t(w.cloths.size()));
  for (const Cloth& c : w.cloths.dense()) {
    f.value(std::uint64_t(c.positions().size()));
    for (const Vec3& x : c.positions()) f.vec(x);
    for (const Vec3& v : c.velocities()) f.vec(v);
  }
  f.value(std::uint64_t(w.shapes.size()));
  for (const detail::Collider& c : w.shapes) {
    f.vec(c.center);
    for (int k = 0; k < 4; ++k) f.value(c.rotation.coeffs()[k]);
  }
  // Dynamic bodies' velocities (their poses are in the shapes above). Absent without one, so
  // the hashes of scenes before Ch. 4 are unchanged.
  if (w.dyn.dynamic_count > 0) {
    const detail::RigidBodies& r = w.dyn.rigid;
    f.value(std::uint64_t(r.size()));
    for (std::size_t i = 0; i < r.size(); ++i) {
      f.vec(r.position[i]);
      f.vec(r.linear_velocity[i]);
      f.vec(r.angular_momentum[i]);
    }
  }
  return f.get();
}

}  // namespace simreel::sim
