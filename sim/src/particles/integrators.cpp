// General integrators (Coutinho Appendix B): explicit and semi-implicit Euler, midpoint RK2,
// RK4, linearised implicit Euler, adaptive step doubling (eq. B.31 with the 0.8 safety factor).
#include "particles/integrators.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <initializer_list>

#include "core/same_bits.hpp"
#include "core/vector_clones.hpp"
#include "particles/row_lanes.hpp"

namespace simreel::sim::detail {

namespace {

using Vec = std::vector<double>;

/// out = a + s b over 3n doubles (element-wise, so any split over threads gives the same bits).
void axpy(std::size_t m, double* out, const double* a, double s, const double* b, int threads) {
#pragma omp parallel for schedule(static) num_threads(threads) if (m >= 3 * kParallelMin)
  for (std::size_t k = 0; k < m; ++k) out[k] = a[k] + s * b[k];
}

/// One classical RK4 step of the whole system: (x, v) at t -> (xo, vo) at t + h.
void rk4_step(Dynamics& dyn, double t, double h, const double* x, const double* v, double* xo,
              double* vo, IntegratorWorkspace& w) {
  const std::size_t m = 3 * dyn.n;
  const int th = dyn.threads;
  dyn.eval(t, x, v, w.a1.data(), true);
  axpy(m, w.xt.data(), x, 0.5 * h, v, th);
  axpy(m, w.v2.data(), v, 0.5 * h, w.a1.data(), th);
  dyn.eval(t + 0.5 * h, w.xt.data(), w.v2.data(), w.a2.data(), true);
  axpy(m, w.xt.data(), x, 0.5 * h, w.v2.data(), th);
  axpy(m, w.v3.data(), v, 0.5 * h, w.a2.data(), th);
  dyn.eval(t + 0.5 * h, w.xt.data(), w.v3.data(), w.a3.data(), true);
  axpy(m, w.xt.data(), x, h, w.v3.data(), th);
  axpy(m, w.vt.data(), v, h, w.a3.data(), th);
  dyn.eval(t + h, w.xt.data(), w.vt.data(), w.a4.data(), true);
  const double h6 = h / 6.0;
#pragma omp parallel for schedule(static) num_threads(th) if (m >= 3 * kParallelMin)
  for (std::size_t k = 0; k < m; ++k) {
    xo[k] = x[k] + h6 * (v[k] + 2.0 * w.v2[k] + 2.0 * w.v3[k] + w.vt[k]);
    vo[k] = v[k] + h6 * (w.a1[k] + 2.0 * w.a2[k] + 2.0 * w.a3[k] + w.a4[k]);
  }
}

/// Linearised backward Euler (Baraff & Witkin 1998; Coutinho App. B, implicit Euler):
///   (M - h ∂f/∂v - h² ∂f/∂x) Δv = h (f + h ∂f/∂x v),  v += Δv,  x += h v - h²/2 (g - k_d v / m) d²
/// with d = 1 / (1 + h k_d / m).
/// The last term (as in semi-implicit Euler) makes free flight exact for a constant acceleration
/// and vanishes at the terminal velocity; it is a constant offset for the springs' stability.
/// ∂f/∂x and ∂f/∂v come from the springs (the transverse term of a compressed spring is dropped,
/// which keeps the matrix symmetric positive definite for conjugate gradients), the drag and the
/// attractor springs; fields and pair forces are taken explicitly (only in f).
void implicit_euler_step(Dynamics& dyn, double t, double h, double* x, double* v,
                         IntegratorWorkspace& w) {
  const std::size_t n = dyn.n;
  double* a = w.a1.data();
  dyn.eval(t, x, v, a, true);
  // Diagonal stiffness and damping per particle from the attractor springs.
  Vec& ks_diag = w.a2;  // reuse scratch: first n entries
  Vec& kd_diag = w.a3;
  std::fill(ks_diag.begin(), ks_diag.begin() + std::ptrdiff_t(n), 0.0);
  // The quadratic drag enters the damping as its secant coefficient c_2 |v| (its full force is
  // in a, so the terminal speed stays the fixed point).
  for (std::size_t i = 0; i < n; ++i) kd_diag[i] = dyn.drag_at(v + 3 * i);
  for (const Dynamics::Pull& p : dyn.pulls) {
    auto add = [&](std::size_t i) {
      ks_diag[i] += p.def->stiffness;
      kd_diag[i] += p.def->damping;
    };
    if (p.all)
      for (std::size_t i = 0; i < n; ++i) add(i);
    else
      for (std::uint32_t i : p.index) add(i);
  }
  if (dyn.springs.empty()) {  // block-diagonal: closed form per particle
    for (std::size_t i = 0; i < n; ++i) {
      const double m = dyn.mass[i];
      const double d = m + h * kd_diag[i] + h * h * ks_diag[i];
      for (int k = 0; k < 3; ++k) {
        const std::size_t c = 3 * i + std::size_t(k);
        const double b = h * (m * a[c] - h * ks_diag[i] * v[c]);
        v[c] += b / d;
      }
      const double kd = dyn.drag_at(v + 3 * i), dd = m / (m + h * kd);
      for (int k = 0; k < 3; ++k) {
        const std::size_t c = 3 * i + std::size_t(k);
        x[c] += h * v[c] - 0.5 * h * h * (dyn.gravity[k] - kd / m * v[c]) * dd * dd;
      }
    }
    return;
  }
  using Sparse = Eigen::SparseMatrix<double>;
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(3 * n + 36 * dyn.springs.size());
  Eigen::VectorXd rhs(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const double m = dyn.mass[i];
    const double d = m + h * kd_diag[i] + h * h * ks_diag[i];
    for (int k = 0; k < 3; ++k) {
      const std::size_t c = 3 * i + std::size_t(k);
      trip.emplace_back(int(c), int(c), d);
      rhs[Eigen::Index(c)] = h * (m * a[c] - h * ks_diag[i] * v[c]);
    }
  }
  for (const Dynamics::Spring& s : dyn.springs) {
    const Vec3 l(x[3 * s.i] - x[3 * s.j], x[3 * s.i + 1] - x[3 * s.j + 1],
                 x[3 * s.i + 2] - x[3 * s.j + 2]);
    const double len = l.norm();
    if (!(len > 1e-12)) continue;
    const Vec3 u = l / len;
    const Mat3 P = u * u.transpose();
    // -∂f_i/∂x_i = k_s [P + max(0, 1 - r/|l|)(I - P)];  -∂f_i/∂v_i = k_d P.
    const Mat3 Ks = s.ks * (P + std::max(0.0, 1.0 - s.rest / len) * (Mat3::Identity() - P));
    const Mat3 B = h * s.kd * P + h * h * Ks;
    const Vec3 dv(v[3 * s.i] - v[3 * s.j], v[3 * s.i + 1] - v[3 * s.j + 1],
                  v[3 * s.i + 2] - v[3 * s.j + 2]);
    const Vec3 kv = -(Ks * dv);  // (∂f/∂x v)_i
    for (int r = 0; r < 3; ++r) {
      rhs[Eigen::Index(3 * s.i + r)] += h * h * kv[r];
      rhs[Eigen::Index(3 * s.j + r)] -= h * h * kv[r];
      for (int c = 0; c < 3; ++c) {
        trip.emplace_back(int(3 * s.i + r), int(3 * s.i + c), B(r, c));
        trip.emplace_back(int(3 * s.j + r), int(3 * s.j + c), B(r, c));
        trip.emplace_back(int(3 * s.i + r), int(3 * s.j + c), -B(r, c));
        trip.emplace_back(int(3 * s.j + r), int(3 * s.i + c), -B(r, c));
      }
    }
  }
  Sparse A(Eigen::Index(3 * n), Eigen::Index(3 * n));
  A.setFromTriplets(trip.begin(), trip.end());
  Eigen::ConjugateGradient<Sparse, Eigen::Lower | Eigen::Upper> cg;
  cg.setTolerance(1e-12);
  cg.compute(A);
  const Eigen::VectorXd dv = cg.solve(rhs);
  for (std::size_t c = 0; c < 3 * n; ++c) v[c] += dv[Eigen::Index(c)];
  for (std::size_t c = 0; c < 3 * n; ++c) {
    const double m = dyn.mass[c / 3], kd = dyn.drag_at(v + 3 * (c / 3)), dd = m / (m + h * kd);
    x[c] += h * v[c] - 0.5 * h * h * (dyn.gravity[int(c % 3)] - kd / m * v[c]) * dd * dd;
  }
}

/// Semi-implicit Euler for one particle of mass m, (x, v) in place, a its acceleration without
/// the drag: the drag at the new velocity (see Integrator::semi_implicit_euler), the rest
/// explicit; the position takes -h²/2 (g - k_d v' / m) d², exact for a constant acceleration
/// (the springs, fields and pair forces stay symplectic Euler: their stability is unchanged).
inline void semi_implicit_particle(const Dynamics& dyn, double h, double m, double* x, double* v,
                                   const double* a) {
  double c = dyn.drag / m;
  double damp = 1.0 / (1.0 + h * c);
  if (dyn.drag_quadratic != 0.0) {
    // v' = u / (1 + h (k_d + c_2 |v'|) / m), u = v + h a: |v'| solves a quadratic.
    double u[3];
    for (int k = 0; k < 3; ++k) u[k] = v[k] + h * a[k];
    damp = quadratic_drag_damp(h, m, dyn.drag, dyn.drag_quadratic,
                               std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]));
    const double s1 = damp * std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    c = (dyn.drag + dyn.drag_quadratic * s1) / m;
  }
  for (int k = 0; k < 3; ++k) {
    v[k] = (v[k] + h * a[k]) * damp;
    x[k] += h * v[k] - 0.5 * h * h * (dyn.gravity[k] - c * v[k]) * damp * damp;
  }
}

/// Float store rows -> double (m entries each).
SIMREEL_VECTOR_CLONES
void widen_lanes(std::size_t m, const float* __restrict px, const float* __restrict pv,
                 double* __restrict x, double* __restrict v) {
  for (std::size_t k = 0; k < m; ++k) {
    x[k] = px[k];
    v[k] = pv[k];
  }
}

/// Double -> float store rows (m entries each); true on a value beyond the divergence bounds
/// (or NaN).
SIMREEL_VECTOR_CLONES
bool narrow_lanes(std::size_t m, const double* __restrict x, const double* __restrict v,
                  double max_distance, double max_speed, float* __restrict px,
                  float* __restrict pv) {
  unsigned bad = 0;
  for (std::size_t k = 0; k < m; ++k) {
    bad |= unsigned(!(std::abs(x[k]) <= max_distance)) | unsigned(!(std::abs(v[k]) <= max_speed));
    px[k] = float(x[k]);
    pv[k] = float(v[k]);
  }
  return bad != 0;
}

/// Semi-implicit Euler over [begin, end) of s when every acceleration is the particle's own
/// (Dynamics::local()): blocks of Dynamics::kBlock particles go from the float store to double,
/// through eval_block() and semi_implicit_particle(), and back, so the (n x 3) double arrays
/// are never written. Bit for bit integrate_system()'s general path (the same operations per
/// particle). Returns true on a non-finite or diverging value.
bool semi_implicit_blocks(ParticleStore& s, std::size_t begin, std::size_t end, double t0,
                          double h, Dynamics& dyn, bool par) {
  constexpr std::size_t B = Dynamics::kBlock;
  const std::size_t n = end - begin, blocks = (n + B - 1) / B;
  dyn.pose_fields(t0);
  const bool linear = dyn.drag_quadratic == 0.0;
  unsigned bad = 0;
#pragma omp parallel for schedule(static) num_threads(dyn.threads) reduction(| : bad) if (par)
  for (std::size_t blk = 0; blk < blocks; ++blk) {
    const std::size_t b = begin + blk * B, len = std::min(end, b + B) - b;
    alignas(64) double x[3 * B], v[3 * B], a[3 * B], m[B];
    float* px = s.position.data() + 3 * b;
    float* pv = s.velocity.data() + 3 * b;
    widen_lanes(3 * len, px, pv, x, v);
    for (std::size_t i = 0; i < len; ++i) m[i] = s.mass[b + i];
    dyn.eval_block(t0, len, x, v, m, a, false);
    if (linear)
      semi_implicit_linear_rows(len, h, dyn.drag, dyn.gravity.x(), dyn.gravity.y(),
                                 dyn.gravity.z(), m, x, v, a);
    else
      for (std::size_t i = 0; i < len; ++i)
        semi_implicit_particle(dyn, h, m[i], x + 3 * i, v + 3 * i, a + 3 * i);
    bad |= unsigned(narrow_lanes(3 * len, x, v, dyn.max_distance, dyn.max_speed, px, pv));
  }
  return bad != 0;
}

/// Points dyn's mass and charge at w's double copies of particles [begin, begin + n) of s (no
/// charge without one), as the pair forces and eval() read them.
void bind_mass_charge(const ParticleStore& s, std::size_t begin, std::size_t n, Dynamics& dyn,
                      IntegratorWorkspace& w) {
  if (w.m.size() < n) w.m.resize(n);
  for (std::size_t i = 0; i < n; ++i) w.m[i] = s.mass[begin + i];
  dyn.n = n;
  dyn.mass = w.m.data();
  dyn.charge = nullptr;
  dyn.one_mass_charge = false;
  if (s.has_charge) {
    if (w.q.size() < n) w.q.resize(n);
    for (std::size_t i = 0; i < n; ++i) w.q[i] = s.charge[begin + i];
    dyn.charge = w.q.data();
  }
}

/// Semi-implicit Euler over [begin, end) of s when pair forces are the only forces between
/// particles (no springs or attractor springs): the pair-force grid from the float store's
/// positions (Dynamics::compute_pair_forces), then blocks of Dynamics::kBlock particles from
/// the store to double, through eval_block(), plus each row's pair acceleration,
/// semi_implicit_particle() and back to the store, so positions, velocities and accelerations
/// are never written as (n x 3) double arrays (the 100k-particle pair-force step took ~15 % less
/// time without those passes, at 1 and 2 threads). Bit for bit integrate_system()'s general
/// path, where eval() adds each row's pair acceleration to the same local sum once. Adds h to
/// each age (s) when age_particles. Returns true on a non-finite or diverging value.
bool semi_implicit_pair_blocks(ParticleStore& s, std::size_t begin, std::size_t end, double t0,
                               double h, Dynamics& dyn, IntegratorWorkspace& w, bool par,
                               bool age_particles) {
  constexpr std::size_t B = Dynamics::kBlock;
  const std::size_t n = end - begin, blocks = (n + B - 1) / B;
  // One mass and one charge (an emitter's default), told from the store's floats (equal bits
  // there give equal doubles): nothing is copied, the pair forces take mass0 and charge0 and the
  // blocks one row of mass0. Else double copies of both (bind_mass_charge()).
  const float* fm = s.mass.data() + begin;
  const float* fq = s.has_charge ? s.charge.data() + begin : nullptr;
  const bool one = n > 0 && one_value(fm, n) && one_value(fq, n);
  alignas(64) double mass_row[B];
  if (one) {
    dyn.n = n;
    dyn.mass = nullptr;
    dyn.charge = nullptr;
    dyn.one_mass_charge = true;
    dyn.mass0 = fm[0];
    dyn.charge0 = fq != nullptr ? double(fq[0]) : 0.0;
    std::fill(mass_row, mass_row + B, dyn.mass0);
  } else {
    bind_mass_charge(s, begin, n, dyn, w);
  }
  if (s.track_prev)
    std::memcpy(&s.prev_position[3 * begin], &s.position[3 * begin], 3 * n * sizeof(float));
  dyn.pose_fields(t0);
  dyn.compute_pair_forces(s.position.data() + 3 * begin);
  const bool linear = dyn.drag_quadratic == 0.0;
  const double* mass = one ? nullptr : w.m.data();
  const float hf = float(h);
  unsigned bad = 0;
#pragma omp parallel for schedule(static) num_threads(dyn.threads) reduction(| : bad) if (par)
  for (std::size_t blk = 0; blk < blocks; ++blk) {
    const std::size_t b = blk * B, len = std::min(n, b + B) - b;
    alignas(64) double x[3 * B], v[3 * B], a[3 * B];
    float* px = s.position.data() + 3 * (begin + b);
    float* pv = s.velocity.data() + 3 * (begin + b);
    // The pair accelerations lie in cell order, so a block's rows are reads at random: the next
    // block's are asked for now, to arrive while this block is integrated.
    for (std::size_t i = b + B; i < std::min(n, b + 2 * B); ++i) {
      const double* o = dyn.pair_acceleration(i);
      __builtin_prefetch(o);
      __builtin_prefetch(o + 2);
    }
    const double* mb = one ? mass_row : mass + b;
    widen_lanes(3 * len, px, pv, x, v);
    dyn.eval_block(t0, len, x, v, mb, a, false);
    for (std::size_t i = 0; i < len; ++i) {
      const double* o = dyn.pair_acceleration(b + i);
      a[3 * i] += o[0];
      a[3 * i + 1] += o[1];
      a[3 * i + 2] += o[2];
    }
    if (linear)
      semi_implicit_linear_rows(len, h, dyn.drag, dyn.gravity.x(), dyn.gravity.y(),
                                 dyn.gravity.z(), mb, x, v, a);
    else
      for (std::size_t i = 0; i < len; ++i)
        semi_implicit_particle(dyn, h, mb[i], x + 3 * i, v + 3 * i, a + 3 * i);
    bad |= unsigned(narrow_lanes(3 * len, x, v, dyn.max_distance, dyn.max_speed, px, pv));
    if (age_particles) {  // (here, not in a pass of its own over the ages)
      float* age = s.age.data() + begin + b;
      for (std::size_t i = 0; i < len; ++i) age[i] += hf;
    }
  }
  dyn.one_mass_charge = false;  // (mass and charge unbound: only this step's pair forces knew)
  return bad != 0;
}

}  // namespace

bool integrate_system(ParticleStore& s, std::size_t begin, std::size_t end, double t0, double h,
                      Dynamics& dyn, Integrator integrator, double tolerance,
                      IntegratorState& state, IntegratorWorkspace& w, bool age_particles) {
  if (begin >= end) return false;
  const std::size_t n = end - begin, m = 3 * n;
  const int th = dyn.threads;
  const bool par = n >= kParallelMin && th > 1;
  dyn.n = n;
  if (integrator == Integrator::semi_implicit_euler && dyn.local()) {
    if (s.track_prev)
      std::memcpy(&s.prev_position[3 * begin], &s.position[3 * begin], m * sizeof(float));
    dyn.charge = nullptr;  // only pair forces read it
    const bool bad = semi_implicit_blocks(s, begin, end, t0, h, dyn, par);
    ++state.substeps;
    if (age_particles) {
      const float hf = float(h);
      for (std::size_t i = begin; i < end; ++i) s.age[i] += hf;
    }
    return bad;
  }
  if (integrator == Integrator::semi_implicit_euler && dyn.pair.enabled() && dyn.springs.empty() &&
      dyn.pulls.empty() && dyn.pair_blocks) {
    const bool bad = semi_implicit_pair_blocks(s, begin, end, t0, h, dyn, w, par, age_particles);
    ++state.substeps;
    return bad;
  }
  // Only the stages this integrator reads are grown: resize() writes every element, and for a
  // million particles each array is 24 MB the first step would fault in for nothing.
  const auto grow = [m](std::initializer_list<Vec*> arrays) {
    for (Vec* a : arrays)
      if (a->size() < m) a->resize(m);
  };
  grow({&w.x, &w.v, &w.a1});
  if (integrator == Integrator::rk2) grow({&w.a2, &w.xt, &w.vt});
  if (integrator == Integrator::implicit_euler) grow({&w.a2, &w.a3});
  if (integrator == Integrator::rk4 || integrator == Integrator::adaptive)
    grow({&w.a2, &w.a3, &w.a4, &w.xt, &w.vt, &w.v2, &w.v3});
  {
    double* __restrict wx = w.x.data();
    double* __restrict wv = w.v.data();
    const float* __restrict px = s.position.data() + 3 * begin;
    const float* __restrict pv = s.velocity.data() + 3 * begin;
#pragma omp parallel for schedule(static) num_threads(th) if (par)
    for (std::size_t k = 0; k < m; ++k) {
      wx[k] = px[k];
      wv[k] = pv[k];
    }
  }
  bind_mass_charge(s, begin, n, dyn, w);
  if (s.track_prev)
    std::memcpy(&s.prev_position[3 * begin], &s.position[3 * begin], m * sizeof(float));
  double* x = w.x.data();
  double* v = w.v.data();

  switch (integrator) {
    case Integrator::explicit_euler: {
      dyn.eval(t0, x, v, w.a1.data(), true);
      for (std::size_t k = 0; k < m; ++k) {
        x[k] += h * v[k];
        v[k] += h * w.a1[k];
      }
      ++state.substeps;
      break;
    }
    case Integrator::semi_implicit_euler: {
      // Drag at the new velocity (see Integrator::semi_implicit_euler), the rest explicit; the
      // position takes -h²/2 (g - k_d v' / m) d², exact for a constant acceleration (the springs,
      // fields and pair forces stay symplectic Euler: their stability is unchanged).
      dyn.eval(t0, x, v, w.a1.data(), false);
      if (dyn.drag_quadratic == 0.0) {
        // (the lanes form: the same operations per particle, vectorised)
        constexpr std::size_t B = Dynamics::kBlock;
        const std::size_t blocks = (n + B - 1) / B;
#pragma omp parallel for schedule(static) num_threads(th) if (par)
        for (std::size_t blk = 0; blk < blocks; ++blk) {
          const std::size_t b = blk * B, len = std::min(n, b + B) - b;
          semi_implicit_linear_rows(len, h, dyn.drag, dyn.gravity.x(), dyn.gravity.y(),
                                     dyn.gravity.z(), w.m.data() + b, x + 3 * b, v + 3 * b,
                                     w.a1.data() + 3 * b);
        }
      } else {
#pragma omp parallel for schedule(static) num_threads(th) if (par)
        for (std::size_t i = 0; i < n; ++i)
          semi_implicit_particle(dyn, h, w.m[i], x + 3 * i, v + 3 * i, w.a1.data() + 3 * i);
      }
      ++state.substeps;
      break;
    }
    case Integrator::rk2: {
      dyn.eval(t0, x, v, w.a1.data(), true);
      axpy(m, w.xt.data(), x, 0.5 * h, v, th);
      axpy(m, w.vt.data(), v, 0.5 * h, w.a1.data(), th);
      dyn.eval(t0 + 0.5 * h, w.xt.data(), w.vt.data(), w.a2.data(), true);
      for (std::size_t k = 0; k < m; ++k) {
        x[k] += h * w.vt[k];
        v[k] += h * w.a2[k];
      }
      ++state.substeps;
      break;
    }
    case Integrator::rk4:
      rk4_step(dyn, t0, h, x, v, x, v, w);
      ++state.substeps;
      break;
    case Integrator::implicit_euler:
      implicit_euler_step(dyn, t0, h, x, v, w);
      ++state.substeps;
      break;
    case Integrator::adaptive: {
      for (Vec* a : {&w.x_full, &w.v_full, &w.x_half, &w.v_half})
        if (a->size() < m) a->resize(m);
      double t = t0;
      const double t1 = t0 + h;
      double hs = state.next_h > 0.0 ? std::min(state.next_h, h) : h;
      const double h_min = h * 1e-6;
      while (t < t1) {
        const bool last = t1 - t <= hs * (1.0 + 1e-12);
        const double step = last ? t1 - t : hs;
        rk4_step(dyn, t, step, x, v, w.x_full.data(), w.v_full.data(), w);
        rk4_step(dyn, t, 0.5 * step, x, v, w.x_half.data(), w.v_half.data(), w);
        rk4_step(dyn, t + 0.5 * step, 0.5 * step, w.x_half.data(), w.v_half.data(),
                 w.x_half.data(), w.v_half.data(), w);
        double err = 0.0;  // max is exact and order-free: thread-count independent
        for (std::size_t k = 0; k < m; ++k) err = std::max(err, std::abs(w.x_full[k] - w.x_half[k]));
        if (!std::isfinite(err)) err = 1e300;
        // Eq. B.31: h_d = h |δ_d / δ|^(1/p), RK4's local error ∝ h^5; 0.8 safety margin,
        // growth capped at 4x per step.
        const double factor = err > 0.0 ? 0.8 * std::pow(tolerance / err, 0.2) : 4.0;
        if (err <= tolerance || step <= h_min) {
          std::memcpy(x, w.x_half.data(), m * sizeof(double));
          std::memcpy(v, w.v_half.data(), m * sizeof(double));
          t = last ? t1 : t + step;
          ++state.substeps;
          hs = std::max(h_min, step * std::min(4.0, factor));
          if (!last) state.next_h = hs;
          else if (hs > step) state.next_h = hs;  // a short final piece must not shrink it
        } else {
          ++state.rejected;
          hs = std::max(h_min, step * std::max(0.1, std::min(0.8, factor)));
          state.next_h = hs;
        }
      }
      break;
    }
  }

  unsigned bad = 0;
  float* __restrict px = s.position.data() + 3 * begin;
  float* __restrict pv = s.velocity.data() + 3 * begin;
#pragma omp parallel for schedule(static) num_threads(th) reduction(| : bad) if (par)
  for (std::size_t k = 0; k < m; ++k) {
    bad |= unsigned(!(std::abs(x[k]) <= dyn.max_distance)) |
           unsigned(!(std::abs(v[k]) <= dyn.max_speed));
    px[k] = float(x[k]);
    pv[k] = float(v[k]);
  }
  if (age_particles) {
    const float hf = float(h);
    for (std::size_t i = begin; i < end; ++i) s.age[i] += hf;
  }
  return bad != 0;
}

}  // namespace simreel::sim::detail
