#pragma once
// Structure-of-arrays particle storage and the per-step kernels over it (private).
// Coutinho §3.1–3.3: point masses under gravity and viscous drag; Appendix B: integrators.

#include <cstddef>
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "simreel/sim/particle_system.hpp"

namespace simreel::sim::detail {

/// One per-particle array of a ParticleStore: the part of std::vector's interface the kernels
/// use, over storage whose live elements may start past its beginning. Emission order is age
/// order, so the particles that die in a step are most often the oldest, at the front: dropping
/// them moves the start (O(1)) where erasing them moved every survivor down (in the PARTICLES
/// peer scene, 2,000 deaths a frame in front of 238,000 survivors, that memmove was 15% of the
/// step). The live run is moved back to the beginning only when an append would pass the end,
/// once per (capacity - size) deaths. Storage is left untouched until used; elements added by
/// resize() are value-initialised, as std::vector's are. A column of 2 MiB or more asks the
/// kernel for huge pages (Linux, where transparent huge pages are on "madvise"): a new world's
/// first touch of its particle arrays otherwise takes one page fault per 4 KiB, a fifth of the
/// PARTICLES peer scene's time on this machine.
template <class T>
class Column {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);
  struct Free {
    void operator()(T* p) const { std::free(p); }
  };
  static T* allocate(std::size_t n) {
    constexpr std::size_t kHuge = std::size_t(2) << 20;
    const std::size_t bytes = std::max<std::size_t>(n * sizeof(T), 1);
    void* p = nullptr;
    if (bytes >= kHuge) {
      p = std::aligned_alloc(kHuge, (bytes + kHuge - 1) / kHuge * kHuge);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
      if (p) (void)::madvise(p, (bytes + kHuge - 1) / kHuge * kHuge, MADV_HUGEPAGE);  // a hint only
#endif
    } else {
      p = std::malloc(bytes);
    }
    if (!p) throw std::bad_alloc();
    return static_cast<T*>(p);
  }

 public:
  using value_type = T;
  Column() = default;
  Column(const Column& o) { *this = o; }
  Column& operator=(const Column& o) {
    if (this == &o) return *this;
    buf_.reset(o.cap_ ? allocate(o.cap_) : nullptr);
    cap_ = o.cap_;
    head_ = 0;
    size_ = o.size_;
    std::copy(o.begin(), o.end(), buf_.get());
    return *this;
  }
  Column(Column&&) noexcept = default;
  Column& operator=(Column&&) noexcept = default;

  [[nodiscard]] T* data() { return buf_.get() + head_; }
  [[nodiscard]] const T* data() const { return buf_.get() + head_; }
  [[nodiscard]] std::size_t size() const { return size_; }
  [[nodiscard]] bool empty() const { return size_ == 0; }
  /// Elements the column holds without allocating (moving its live run to the start if needed).
  [[nodiscard]] std::size_t capacity() const { return cap_; }
  T& operator[](std::size_t i) { return buf_.get()[head_ + i]; }
  const T& operator[](std::size_t i) const { return buf_.get()[head_ + i]; }
  T* begin() { return data(); }
  T* end() { return data() + size_; }
  const T* begin() const { return data(); }
  const T* end() const { return data() + size_; }

  void reserve(std::size_t n) {
    if (n > cap_) relocate(n);
  }
  void resize(std::size_t n, const T& value = T{}) {
    if (head_ + n > cap_) {
      if (n <= cap_) {
        std::copy(begin(), end(), buf_.get());  // forward, overlapping toward lower addresses
        head_ = 0;
      } else {
        relocate(std::max(n, 2 * cap_));
      }
    }
    if (n > size_) std::fill(data() + size_, data() + n, value);
    size_ = n;
  }
  void push_back(const T& v) { resize(size_ + 1, v); }
  void assign(std::size_t n, const T& value) {
    clear();
    resize(n, value);
  }
  void clear() { head_ = size_ = 0; }
  /// Removes the first k elements (k <= size()) without moving the others.
  void drop_front(std::size_t k) {
    head_ += k;
    size_ -= k;
    if (size_ == 0) head_ = 0;
  }

 private:
  void relocate(std::size_t cap) {
    std::unique_ptr<T, Free> b(allocate(cap));
    std::copy(begin(), end(), b.get());
    buf_ = std::move(b);
    cap_ = cap;
    head_ = 0;
  }
  std::unique_ptr<T, Free> buf_;
  std::size_t cap_ = 0, head_ = 0, size_ = 0;
};

/// Sleep of particles at rest (ParticleStore::rest): slower than kSleepSpeed (m/s), by velocity
/// or by the motion over each step, for kSleepTime (s) — Box2D's linear sleep tolerance and time
/// to sleep.
inline constexpr float kSleepSpeed = 0.01f;
inline constexpr float kSleepTime = 0.5f;

/// Floats per particle in ParticleStore::memo (CollideMemo::kStride).
inline constexpr std::size_t kMemoStride = 14;

/// Live particles of one system. Every array holds exactly `count` particles (xyz arrays
/// 3 * count floats, color 4 * count); capacity for `max_particles` is reserved at creation so
/// neither emission nor compaction allocates. The view's pointers move when the oldest die at
/// the front (Column::drop_front) and when an append moves the live run back to the start.
struct ParticleStore {
  std::size_t count = 0;
  Column<float> position;       ///< (count x 3) world frame (m)
  Column<float> velocity;       ///< (count x 3) world frame (m/s)
  Column<float> prev_position;  ///< (count x 3) position at the start of the current step,
                                     ///< kept only when `track_prev` (see there)
  Column<float> color;          ///< (count x 4) linear RGBA
  Column<float> radius;         ///< (count) (m)
  Column<float> mass;           ///< (count) (kg)
  Column<float> age;            ///< (count) (s)
  Column<float> lifetime;       ///< (count) (s)
  Column<std::uint64_t> id;     ///< (count) emission order
  Column<float> charge;         ///< (count) (C), kept only when `has_charge`
  /// The swept collision test needs each particle's start-of-step position. Semi-implicit Euler
  /// moves in a straight line at the new velocity (x1 = x0 + dt v1), so x0 is recovered from the
  /// end state for free; RK4's chord is not dt v1, so RK4 systems that collide store it.
  bool track_prev = false;
  bool has_charge = false;  ///< the system has a charge distribution other than 0
  // Emitter and split state (emitter.cpp, split.cpp).
  Column<float> base_radius;             ///< (count) radius as drawn (m), before size over
                                              ///< lifetime
  Column<float> tint;                    ///< (count) brightness factor on the gradient RGB
  Column<std::uint8_t> split_generation; ///< (count) splits in the lineage (0 = emitted)
  Column<std::uint32_t> split_countdown; ///< (count) steps left before a child splits
  Column<std::uint8_t> from_split;       ///< (count) 1: created by a split (§3.9.1), 0:
                                         ///< emitted or spawned (sub-emitter filter)
  /// Sleep of particles at rest in a particle–particle group (collision/particle_collisions.hpp):
  /// (count x 4) the position it sleeps at (m, world; while awake, its position at the end of
  /// the last step, for the motion test) and the time (s) it has been slower than the sleep
  /// speed; asleep from kSleepTime on. Kept only when `track_rest` (systems that
  /// collide with each other's particles); part of the state.
  Column<float> rest;
  bool track_rest = false;
  /// The collision pass's memo of each particle's last response (collision/collide_memo.hpp):
  /// (count x 14) the integrated position, velocity, radius and mass it saw, then the position
  /// and velocity it wrote; memo_epoch (count) the pass environment it was recorded in, 0 for
  /// none (a new particle). A cache, not state: the state hash and exports leave it out, and
  /// dropping it changes no result. Kept once `track_memo` (set by the pass when it first
  /// uses it).
  Column<float> memo;
  Column<std::uint32_t> memo_epoch;
  bool track_memo = false;

  void reserve(std::size_t capacity);
  /// Appends n zero-initialised particles; returns the index of the first.
  std::size_t append(std::size_t n);
  /// Removes particles with age >= lifetime from index `first` on, keeping the survivors' order
  /// (so exports sorted by id stay sorted). Moves contiguous runs with memmove. Returns how many
  /// were removed.
  std::size_t compact(std::size_t first = 0);
  [[nodiscard]] ParticleView view() const;
};

/// Gravity + viscous and quadratic drag parameters of a system (§3.3.1–3.3.2):
/// a = g - (k_d + c_2 |v|) v / m.
struct ForceParams {
  float gravity[3];
  float drag;  ///< k_d (kg/s)
  float drag_quadratic = 0.0f;  ///< c_2 (kg/m): F = -c_2 |v| v
  /// Divergence bounds (WorldDef): a velocity component beyond max_speed (m/s) or a coordinate
  /// beyond max_distance (m), like NaN and inf, makes the integrators report a bad state.
  float max_speed = 1e4f;
  float max_distance = 1e6f;
};

/// The fast path for gravity + drag only (semi_implicit_euler or rk4): advances particles
/// [begin, end) by h, adds h to their ages, and (when s.track_prev) saves the start-of-step
/// positions for the swept collision test, split statically over `threads` when the range is
/// large. Returns true if any resulting position or velocity is not finite.
bool integrate(ParticleStore& s, std::size_t begin, std::size_t end, double h,
               const ForceParams& f, Integrator integrator, int threads = 1);

/// Advances one particle by its own dt (a newborn released part-way through a step).
/// The age is not changed. Returns true if the result is not finite.
bool integrate_one(ParticleStore& s, std::size_t i, double dt, const ForceParams& f,
                   Integrator integrator);

/// Colour-over-lifetime gradient, piecewise linear in normalised age (one key = constant).
class ColorGradient {
 public:
  ColorGradient() = default;
  explicit ColorGradient(const std::vector<ColorKey>& keys);
  [[nodiscard]] bool constant() const { return t_.size() <= 1; }
  /// rgba at normalised age u (clamped to the first/last key outside their range).
  void eval(float u, float* rgba) const;
  /// Writes the colour of particles [begin, end) from their age / lifetime.
  void apply(ParticleStore& s, std::size_t begin, std::size_t end) const;

 private:
  std::vector<float> t_;     ///< key positions, non-decreasing
  std::vector<float> rgba_;  ///< (keys x 4)
};

}  // namespace simreel::sim::detail
