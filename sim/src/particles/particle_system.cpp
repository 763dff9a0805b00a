// Particle storage, integrators and colour over lifetime (Coutinho §3.1–3.3, Appendix B).
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>

#include "core/same_bits.hpp"
#include "core/vector_clones.hpp"
#include "particles/forces.hpp"
#include "particles/particle_store.hpp"

#if SIMREEL_HAS_VECTOR_CLONES
#include <immintrin.h>
#endif

namespace simreel::sim::detail {

// ---------------------------------------------------------------------------------------------
// Storage

void ParticleStore::reserve(std::size_t capacity) {
  position.reserve(3 * capacity);
  velocity.reserve(3 * capacity);
  if (track_prev) prev_position.reserve(3 * capacity);
  color.reserve(4 * capacity);
  radius.reserve(capacity);
  mass.reserve(capacity);
  age.reserve(capacity);
  lifetime.reserve(capacity);
  id.reserve(capacity);
  if (has_charge) charge.reserve(capacity);
  base_radius.reserve(capacity);
  tint.reserve(capacity);
  split_generation.reserve(capacity);
  split_countdown.reserve(capacity);
  from_split.reserve(capacity);
  if (track_rest) rest.reserve(4 * capacity);
  if (track_memo) {
    memo.reserve(kMemoStride * capacity);
    memo_epoch.reserve(capacity);
  }
}

namespace {
void resize_all(ParticleStore& s, std::size_t n) {
  s.position.resize(3 * n);
  s.velocity.resize(3 * n);
  if (s.track_prev) s.prev_position.resize(3 * n);
  s.color.resize(4 * n);
  s.radius.resize(n);
  s.mass.resize(n);
  s.age.resize(n);
  s.lifetime.resize(n);
  s.id.resize(n);
  if (s.has_charge) s.charge.resize(n);
  s.base_radius.resize(n);
  s.tint.resize(n, 1.0f);  // a particle not from the emitter keeps its colour
  s.split_generation.resize(n);
  s.split_countdown.resize(n);
  s.from_split.resize(n);
  if (s.track_rest) s.rest.resize(4 * n);  // awake, no time at rest
  if (s.track_memo) {
    s.memo.resize(kMemoStride * n);
    s.memo_epoch.resize(n);  // 0: no entry
  }
  s.count = n;
}

template <class T>
void move_run(Column<T>& a, std::size_t stride, std::size_t dst, std::size_t src,
              std::size_t n) {
  std::memmove(a.data() + stride * dst, a.data() + stride * src, sizeof(T) * stride * n);
}
}  // namespace

std::size_t ParticleStore::append(std::size_t n) {
  const std::size_t first = count;
  resize_all(*this, count + n);
  return first;
}

std::size_t ParticleStore::compact(std::size_t first) {
  const std::size_t n = count;
  auto alive = [this](std::size_t i) { return age[i] < lifetime[i]; };
  // Find the first death a block at a time: most steps nobody dies, and a branch-free block
  // scan vectorises where a per-particle early exit does not.
  constexpr std::size_t kBlock = 256;
  std::size_t i = first;
  while (i < n) {
    const std::size_t e = std::min(n, i + kBlock);
    unsigned dead = 0;
    for (std::size_t j = i; j < e; ++j) dead |= unsigned(!(age[j] < lifetime[j]));
    if (dead) break;
    i = e;
  }
  if (i >= n) return 0;  // the common case: nothing moves
  while (alive(i)) ++i;
  if (i == 0) {
    // The oldest died (emission order is age order): drop them from the front of every
    // column, moving nobody, and compact what follows.
    std::size_t k = 0;
    while (k < n && !alive(k)) ++k;
    for (auto* c : {&position, &velocity, &color}) c->drop_front((c == &color ? 4 : 3) * k);
    if (track_prev) prev_position.drop_front(3 * k);
    for (auto* c : {&radius, &mass, &age, &lifetime, &base_radius, &tint}) c->drop_front(k);
    if (has_charge) charge.drop_front(k);
    id.drop_front(k);
    split_generation.drop_front(k);
    split_countdown.drop_front(k);
    from_split.drop_front(k);
    if (track_rest) rest.drop_front(4 * k);
    if (track_memo) {
      memo.drop_front(kMemoStride * k);
      memo_epoch.drop_front(k);
    }
    count = n - k;
    return k + compact(0);
  }
  std::size_t w = i;
  while (i < n) {
    while (i < n && !alive(i)) ++i;
    const std::size_t run = i;
    while (i < n && alive(i)) ++i;
    const std::size_t len = i - run;
    if (len == 0) break;
    // prev_position is scratch for the current step's collision pass, already done: not moved.
    move_run(position, 3, w, run, len);
    move_run(velocity, 3, w, run, len);
    move_run(color, 4, w, run, len);
    move_run(radius, 1, w, run, len);
    move_run(mass, 1, w, run, len);
    move_run(age, 1, w, run, len);
    move_run(lifetime, 1, w, run, len);
    move_run(id, 1, w, run, len);
    if (has_charge) move_run(charge, 1, w, run, len);
    move_run(base_radius, 1, w, run, len);
    move_run(tint, 1, w, run, len);
    move_run(split_generation, 1, w, run, len);
    move_run(split_countdown, 1, w, run, len);
    move_run(from_split, 1, w, run, len);
    if (track_rest) move_run(rest, 4, w, run, len);
    if (track_memo) {
      move_run(memo, kMemoStride, w, run, len);
      move_run(memo_epoch, 1, w, run, len);
    }
    w += len;
  }
  resize_all(*this, w);
  return n - w;
}

ParticleView ParticleStore::view() const {
  ParticleView v;
  v.count = count;
  v.position = position.data();
  v.velocity = velocity.data();
  v.color = color.data();
  v.radius = radius.data();
  v.mass = mass.data();
  v.age = age.data();
  v.lifetime = lifetime.data();
  v.id = id.data();
  v.charge = has_charge ? charge.data() : nullptr;
  return v;
}

// ---------------------------------------------------------------------------------------------
// Integrators

namespace {

/// out[3k], out[3k + 1], out[3k + 2] = p[k] for k < n (out: 3 n floats). Without AVX-512, four
/// particles at a time by three 128-bit shuffles: the compiler's own spread used lane-crossing
/// vpermd, which issues as 3 micro-ops with a throughput of one per 4 cycles on AMD Zen 1 (the
/// semi-implicit kernel held 80 of them; docs/benchmarks.md, stop 86). With AVX-512 the
/// compiler's clone spreads sixteen at a time, which the shuffles would not beat.
inline void spread3(const float* p, std::size_t n, float* out) {
#if SIMREEL_HAS_VECTOR_CLONES
  static const bool avx512 = cpu_has_avx512vl();
  std::size_t k = 0;
  if (!avx512)
    for (; k + 4 <= n; k += 4) {
      const __m128 q = _mm_loadu_ps(p + k);
      _mm_storeu_ps(out + 3 * k, _mm_shuffle_ps(q, q, _MM_SHUFFLE(1, 0, 0, 0)));
      _mm_storeu_ps(out + 3 * k + 4, _mm_shuffle_ps(q, q, _MM_SHUFFLE(2, 2, 1, 1)));
      _mm_storeu_ps(out + 3 * k + 8, _mm_shuffle_ps(q, q, _MM_SHUFFLE(3, 3, 3, 2)));
    }
  for (; k < n; ++k) out[3 * k] = out[3 * k + 1] = out[3 * k + 2] = p[k];
#else
  for (std::size_t k = 0; k < n; ++k) out[3 * k] = out[3 * k + 1] = out[3 * k + 2] = p[k];
#endif
}

/// Semi-implicit (symplectic) Euler, Coutinho App. B / §3.3 — with the drag taken at the new
/// velocity:  v' = (v + h g) d, d = 1 / (1 + h k_d / m);  x' = x + h v' - h²/2 a(v') d², where
/// a(v') = g - k_d v' / m. Explicit drag multiplies v by (1 - h k_d / m) each step, which
/// diverges once h k_d / m > 2 (a light particle drawn near its mass floor in heavy drag); the
/// implicit form is stable for any drag and keeps the exact terminal velocity m g / k_d as its
/// fixed point. The position term makes a ballistic arc exact (x' = x + h v + h² g / 2 without
/// drag), is zero at the terminal velocity, and fades (d²) where the drag is stiff, so a heavily
/// damped transient still moves by about v0 m / k_d.
/// Because the velocity update is implicit Euler, h a(v') = v' - v exactly, so the position
/// update is x' = x + h (v' + c (v - v')) with c = d² / 2: per particle one division (d) and no
/// more, which keeps the kernel as fast as plain semi-implicit Euler. Without drag (d = 1) it is
/// x' = x + h v' - h² g / 2, written so because summing h v' and a constant keeps float
/// rounding from drifting over thousands of steps (1000 steps of 1 ms land within 1e-5 m).
/// Chunks of particles are processed as flat float arrays (x and v are (n x 3) interleaved), with
/// the per-particle d and c spread to a per-float pattern first, so the main loop is a plain
/// element-wise loop the compiler vectorises without shuffles. Float throughout: the method's
/// O(h) error dwarfs float rounding.
template <bool kDrag>
SIMREEL_VECTOR_CLONES unsigned semi_implicit_euler(ParticleStore& s, std::size_t begin, std::size_t end, float h,
                             const ForceParams& f) {
  constexpr std::size_t kChunk = 128;
  float* __restrict x = s.position.data();
  float* __restrict v = s.velocity.data();
  float* __restrict age = s.age.data();
  const float* __restrict m = s.mass.data();
  alignas(16) float hg[3 * kChunk];   // h g, repeating x y z
  alignas(16) float hhg[3 * kChunk];  // h² g / 2, repeating x y z
  for (std::size_t j = 0; j < 3 * kChunk; ++j) {
    hg[j] = h * f.gravity[j % 3];
    hhg[j] = 0.5f * h * h * f.gravity[j % 3];
  }
  const float hk = h * f.drag;
  const float vmax = f.max_speed, xmax = f.max_distance;

  unsigned bad = 0;
  for (std::size_t i0 = begin; i0 < end; i0 += kChunk) {
    const std::size_t n = std::min(kChunk, end - i0);
    float* __restrict xb = x + 3 * i0;
    float* __restrict vb = v + 3 * i0;
    alignas(16) float damp3[3 * kChunk];  // d = m / (m + h k_d), per float
    if constexpr (kDrag) {
      if (same_bits(m + i0, n)) {
        // One mass for the chunk (an emitter's particles): one division gives every particle
        // the bits of its own.
        std::fill(damp3, damp3 + 3 * n, m[i0] / (m[i0] + hk));
      } else {
        alignas(16) float damp[kChunk];
        for (std::size_t k = 0; k < n; ++k) damp[k] = m[i0 + k] / (m[i0 + k] + hk);
        spread3(damp, n, damp3);
      }
    }
    for (std::size_t j = 0; j < 3 * n; ++j) {
      const float v0 = vb[j];
      float vv = v0 + hg[j];
      float xx;
      if constexpr (kDrag) {
        const float d = damp3[j];
        vv = vv * d;
        xx = xb[j] + h * (vv + (0.5f * d * d) * (v0 - vv));
      } else {
        xx = xb[j] + h * vv - hhg[j];
      }
      vb[j] = vv;
      xb[j] = xx;
      // Not (|.| <= bound): true for inf, NaN and a blow-up; a compare the loop vectorises.
      bad |= unsigned(!(std::fabs(vv) <= vmax)) | unsigned(!(std::fabs(xx) <= xmax));
    }
    for (std::size_t k = 0; k < n; ++k) age[i0 + k] += h;
  }
  return bad;
}

/// Semi-implicit Euler with quadratic drag (c_2 != 0): as above with the drag taken at the new
/// velocity, v' = (v + h g) d, d = 1 / (1 + h (k_d + c_2 |v'|) / m) solved in closed form
/// (quadratic_drag_damp, float here), and x' = x + h v' - h²/2 (g - (k_d + c_2 |v'|) v' / m) d².
/// Exact for a constant acceleration, stable for any drag, and the terminal speed √(m g / c_2)
/// is its fixed point. One square root per particle.
unsigned semi_implicit_euler_quadratic(ParticleStore& s, std::size_t begin, std::size_t end,
                                       float h, const ForceParams& f) {
  float* __restrict x = s.position.data();
  float* __restrict v = s.velocity.data();
  const float hg[3] = {h * f.gravity[0], h * f.gravity[1], h * f.gravity[2]};
  const float hhg[3] = {0.5f * h * h * f.gravity[0], 0.5f * h * h * f.gravity[1],
                        0.5f * h * h * f.gravity[2]};
  const float vmax = f.max_speed, xmax = f.max_distance;
  unsigned bad = 0;
  for (std::size_t i = begin; i < end; ++i) {
    float* xi = x + 3 * i;
    float* vi = v + 3 * i;
    const float m = s.mass[i];
    const float u0 = vi[0] + hg[0], u1 = vi[1] + hg[1], u2 = vi[2] + hg[2];
    const float su = std::sqrt(u0 * u0 + u1 * u1 + u2 * u2);
    const float a = 1.0f + h * f.drag / m, b = h * f.drag_quadratic / m;
    const float d = 2.0f / (a + std::sqrt(a * a + 4.0f * b * su));
    const float kd = f.drag + f.drag_quadratic * (su * d);
    const float d2 = d * d;
    const float hv = h + 0.5f * h * (h * kd) / m * d2;
    const float u[3] = {u0, u1, u2};
    for (int j = 0; j < 3; ++j) {
      const float vv = u[j] * d;
      const float xx = xi[j] + hv * vv - hhg[j] * d2;
      vi[j] = vv;
      xi[j] = xx;
      bad |= unsigned(!(std::fabs(vv) <= vmax)) | unsigned(!(std::fabs(xx) <= xmax));
    }
    s.age[i] += h;
  }
  return bad;
}

/// RK4 with quadratic drag: a(v) = g - (k_d + c_2 |v|) v / m couples the components, so the
/// state is the 3-vector pair (x, v), in double; sub-steps as in rk4_one, with z from the
/// effective coefficient at the start speed plus the speed gravity adds over the step.
inline unsigned rk4_quadratic(float* x, float* v, double m, double h, const ForceParams& f) {
  const Vec3 g(f.gravity[0], f.gravity[1], f.gravity[2]);
  const double kd = f.drag, c2 = f.drag_quadratic;
  Vec3 xv(x[0], x[1], x[2]), vv(v[0], v[1], v[2]);
  const auto acc = [&](const Vec3& w) { return Vec3(g - (kd + c2 * w.norm()) / m * w); };
  const double z = (kd + c2 * (vv.norm() + g.norm() * h)) / m * h;
  const int n = z > 0.5 ? int(std::min(std::ceil(z / 0.5), 65536.0)) : 1;
  const double hs = h / n;
  for (int k = 0; k < n; ++k) {
    const Vec3 v0 = vv;
    const Vec3 k1 = acc(v0);
    const Vec3 v2 = v0 + 0.5 * hs * k1;
    const Vec3 k2 = acc(v2);
    const Vec3 v3 = v0 + 0.5 * hs * k2;
    const Vec3 k3 = acc(v3);
    const Vec3 v4 = v0 + hs * k3;
    const Vec3 k4 = acc(v4);
    vv = v0 + (hs / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    xv = xv + (hs / 6.0) * (v0 + 2.0 * v2 + 2.0 * v3 + v4);
  }
  unsigned bad = 0;
  for (int j = 0; j < 3; ++j) {
    v[j] = float(vv[j]);
    x[j] = float(xv[j]);
    bad |= unsigned(!(std::abs(vv[j]) <= double(f.max_speed)) ||
                    !(std::abs(xv[j]) <= double(f.max_distance)));
  }
  return bad;
}

/// Classical RK4 (Coutinho App. B) on (x, v) with a(v) = g - c v, c = k_d / m, in double. The
/// components are decoupled (drag is linear), so each is a scalar 2-state system. RK4 is explicit
/// and diverges once z = c h > 2.78, so a particle whose own z exceeds 0.5 takes ceil(z / 0.5)
/// equal sub-steps (at most 65536): a per-particle fixed refinement, deterministic, in the spirit
/// of App. B's step control; ordinary particles take exactly one classical step.
inline unsigned rk4_one(float* x, float* v, double m, double h, const ForceParams& f) {
  if (f.drag_quadratic != 0.0f) return rk4_quadratic(x, v, m, h, f);
  const double c = double(f.drag) / m;
  const double z = c * h;
  const int n = z > 0.5 ? int(std::min(std::ceil(z / 0.5), 65536.0)) : 1;
  const double hs = h / n;
  unsigned bad = 0;
  for (int j = 0; j < 3; ++j) {
    const double g = f.gravity[j];
    double xj = x[j], vj = v[j];
    for (int k = 0; k < n; ++k) {
      const double v0 = vj;
      const double k1v = g - c * v0;
      const double v2 = v0 + 0.5 * hs * k1v;
      const double k2v = g - c * v2;
      const double v3 = v0 + 0.5 * hs * k2v;
      const double k3v = g - c * v3;
      const double v4 = v0 + hs * k3v;
      const double k4v = g - c * v4;
      vj = v0 + (hs / 6.0) * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
      xj = xj + (hs / 6.0) * (v0 + 2.0 * v2 + 2.0 * v3 + v4);
    }
    v[j] = float(vj);
    x[j] = float(xj);
    // Checked on the doubles: NaN, inf, or beyond the divergence bounds.
    bad |= unsigned(!(std::abs(vj) <= double(f.max_speed)) ||
                    !(std::abs(xj) <= double(f.max_distance)));
  }
  return bad;
}

}  // namespace

bool integrate(ParticleStore& s, std::size_t begin, std::size_t end, double h,
               const ForceParams& f, Integrator integrator, int threads) {
  if (begin >= end) return false;
  unsigned bad = 0;
  const float hf = float(h);
  if (integrator == Integrator::semi_implicit_euler) {
    // Static partition into blocks of whole 128-particle chunks: each particle's arithmetic is
    // the same whichever thread runs it, so results are bit-identical at any thread count.
    const std::size_t n = end - begin;
    const int parts = n >= kParallelMin && threads > 1 ? threads : 1;
    const std::size_t per = ((n + std::size_t(parts) - 1) / std::size_t(parts) + 127) / 128 * 128;
#pragma omp parallel for schedule(static) num_threads(parts) reduction(| : bad) if (parts > 1)
    for (int p = 0; p < parts; ++p) {
      const std::size_t b = begin + std::min(n, std::size_t(p) * per);
      const std::size_t e = begin + std::min(n, std::size_t(p + 1) * per);
      if (b < e)
        bad |= f.drag_quadratic != 0.0f ? semi_implicit_euler_quadratic(s, b, e, hf, f)
               : f.drag != 0.0f         ? semi_implicit_euler<true>(s, b, e, hf, f)
                                        : semi_implicit_euler<false>(s, b, e, hf, f);
    }
  } else {
#pragma omp parallel for schedule(static) num_threads(threads) reduction(| : bad) \
    if (end - begin >= kParallelMin && threads > 1)
    for (std::size_t i = begin; i < end; ++i) {
      if (s.track_prev)
        std::memcpy(&s.prev_position[3 * i], &s.position[3 * i], 3 * sizeof(float));
      bad |= rk4_one(&s.position[3 * i], &s.velocity[3 * i], s.mass[i], h, f);
      s.age[i] += hf;
    }
  }
  return bad != 0;
}

bool integrate_one(ParticleStore& s, std::size_t i, double dt, const ForceParams& f,
                   Integrator integrator) {
  float* x = &s.position[3 * i];
  float* v = &s.velocity[3 * i];
  if (integrator == Integrator::rk4) return rk4_one(x, v, s.mass[i], dt, f) != 0;
  // Same float arithmetic as the bulk kernel, with this particle's own step.
  if (f.drag_quadratic != 0.0f) {
    const float a0 = s.age[i];
    const unsigned bad = semi_implicit_euler_quadratic(s, i, i + 1, float(dt), f);
    s.age[i] = a0;  // the age is not changed here
    return bad != 0;
  }
  const float h = float(dt);
  const bool drag = f.drag != 0.0f;
  const float damp = drag ? s.mass[i] / (s.mass[i] + h * f.drag) : 1.0f;
  const float d2 = damp * damp;
  const float hv = drag ? h + 0.5f * h * (h * f.drag) / s.mass[i] * d2 : h;
  unsigned bad = 0;
  for (int j = 0; j < 3; ++j) {
    float vv = v[j] + h * f.gravity[j];
    if (drag) vv = vv * damp;
    v[j] = vv;
    x[j] = x[j] + hv * vv - 0.5f * h * h * f.gravity[j] * d2;
    bad |= unsigned(!(std::fabs(v[j]) <= f.max_speed)) | unsigned(!(std::fabs(x[j]) <= f.max_distance));
  }
  return bad != 0;
}

// ---------------------------------------------------------------------------------------------
// Colour over lifetime

ColorGradient::ColorGradient(const std::vector<ColorKey>& keys) {
  t_.reserve(keys.size());
  rgba_.reserve(4 * keys.size());
  for (const ColorKey& k : keys) {
    t_.push_back(float(k.t));
    rgba_.insert(rgba_.end(), k.rgba.begin(), k.rgba.end());
  }
}

void ColorGradient::eval(float u, float* rgba) const {
  const std::size_t n = t_.size();
  std::size_t k = 0;
  while (k + 1 < n && u >= t_[k + 1]) ++k;
  if (k + 1 >= n) {
    std::memcpy(rgba, &rgba_[4 * (n - 1)], 4 * sizeof(float));
    return;
  }
  // Before the first key w clamps to 0; a zero-width segment is never selected (u >= t_[k+1]
  // moved past it).
  const float w = std::clamp((u - t_[k]) / (t_[k + 1] - t_[k]), 0.0f, 1.0f);
  for (int c = 0; c < 4; ++c)
    rgba[c] = rgba_[4 * k + std::size_t(c)] +
              w * (rgba_[4 * (k + 1) + std::size_t(c)] - rgba_[4 * k + std::size_t(c)]);
}

void ColorGradient::apply(ParticleStore& s, std::size_t begin, std::size_t end) const {
  for (std::size_t i = begin; i < end; ++i) {
    const float u = s.lifetime[i] > 0.0f ? s.age[i] / s.lifetime[i] : 1.0f;
    eval(u, &s.color[4 * i]);
  }
}

}  // namespace simreel::sim::detail
