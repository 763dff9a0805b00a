// The particle contacts' solve (Coutinho §3.6.1–3.6.2): the sequential-impulse sweeps over the
// bands and the overlap projection. Their order (the bands of grid columns, the wavefront order,
// the lone contacts) is in particle_schedule.cpp, the contact search in particle_pairs.cpp, the
// step in particle_collisions.cpp.
#include <algorithm>
#include <cassert>
#include <cmath>
#include <type_traits>

#include <omp.h>
#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "collision/particle_collisions.hpp"
#include "core/run_claims.hpp"
#include "core/vector_clones.hpp"
#include "particles/forces.hpp"  // kParallelMin

namespace simreel::sim::detail {

namespace {

/// One contact's update (Coutinho §3.6.1–3.6.2): the normal impulse accumulated and clamped to
/// push only, then the friction impulse that cancels the relative sliding, within the Coulomb
/// bound mu P_n. W: ParticleCollider::SolverColumns; q: the contact's work_ position; vc: its
/// surface velocity where it is a collider contact (`wall`); b: the particles' velocities and
/// inverse masses.
template <bool wall, class W>
__attribute__((always_inline)) inline void update1(W& w, std::size_t q, const Vec3& vc, SolveBody* b) {
  const std::uint32_t i = w.i[q], j = w.j[q];
  const Vec3 n(w.n[0][q], w.n[1][q], w.n[2][q]);
  const double m_eff = w.m_eff[q], pn = w.pn[q];
  const Vec3 pt(w.pt[0][q], w.pt[1][q], w.pt[2][q]);
  const double wi = wall ? 0.0 : b[i].inv_mass, wj = b[j].inv_mass;
  Vec3 vi = wall ? vc : Vec3(b[i].v[0], b[i].v[1], b[i].v[2]);
  Vec3 vj(b[j].v[0], b[j].v[1], b[j].v[2]);
  Vec3 dv = vj - vi;
  const double vn = dv.dot(n);
  const double pn_new = std::max(0.0, pn + m_eff * (w.target[q] - vn));
  const double dpn = pn_new - pn;
  w.pn[q] = pn_new;
  if (!wall) vi -= (dpn * wi) * n;
  vj += (dpn * wj) * n;
  dv = vj - vi;
  const Vec3 vt = dv - dv.dot(n) * n;
  Vec3 pt_new = pt - m_eff * vt;
  const double bound = w.mu[q] * pn_new;
  const double len = pt_new.norm();
  // A minimum, not a branch: whether a contact slides is data, and a mispredicted branch
  // stops the overlap of independent contacts. bound / len < 1 exactly when the branch
  // "len > bound" would scale (a quotient rounded up to 1 scales by 1.0 either way; 0 / 0 and
  // b / 0 leave it at 1), and x * 1.0 == x: the bits are those of the branch.
  const double ratio = bound / len;
#if defined(__SSE2__)
  // gcc turns the ternary below into a branch; minsd returns its second operand on NaN.
  pt_new *= _mm_cvtsd_f64(_mm_min_sd(_mm_set_sd(ratio), _mm_set_sd(1.0)));
#else
  pt_new *= ratio < 1.0 ? ratio : 1.0;
#endif
  const Vec3 dpt = pt_new - pt;
  for (int k = 0; k < 3; ++k) w.pt[k][q] = pt_new[k];
  if (!wall) {
    vi -= wi * dpt;
    for (int k = 0; k < 3; ++k) b[i].v[k] = vi[k];
  }
  vj += wj * dpt;
  for (int k = 0; k < 3; ++k) b[j].v[k] = vj[k];
}

#if defined(__SSE2__)
/// a[0] b[0] + a[1] b[1] + a[2] b[2] lane by lane, in the scalar dot product's order.
__attribute__((always_inline)) inline __m128d dot2(const __m128d* a, const __m128d* b) {
  return _mm_add_pd(_mm_add_pd(_mm_mul_pd(a[0], b[0]), _mm_mul_pd(a[1], b[1])), _mm_mul_pd(a[2], b[2]));
}

/// update1() of contacts q and q + 1 of one wave (they share no particle), one in each lane of
/// the SSE2 registers, each lane performing the scalar update's operations in its order (no
/// FMA: -ffp-contract=off), so the bits are the scalar update's. vc: their surface velocities.
template <bool wall, class W>
__attribute__((always_inline)) inline void update2(W& w, std::size_t q, const Vec3* vc, SolveBody* b) {
  const std::uint32_t i0 = w.i[q], i1 = w.i[q + 1], j0 = w.j[q], j1 = w.j[q + 1];
  const auto pack = [](double a, double c) { return _mm_set_pd(c, a); };
  __m128d n[3], vi[3], vj[3], dv[3], pt[3];
  for (int k = 0; k < 3; ++k) {
    n[k] = _mm_loadu_pd(&w.n[k][q]);
    pt[k] = _mm_loadu_pd(&w.pt[k][q]);
    vi[k] = wall ? pack(vc[0][k], vc[1][k]) : _mm_loadh_pd(_mm_load_sd(&b[i0].v[k]), &b[i1].v[k]);
    vj[k] = _mm_loadh_pd(_mm_load_sd(&b[j0].v[k]), &b[j1].v[k]);
  }
  const __m128d wj = pack(b[j0].inv_mass, b[j1].inv_mass);
  const __m128d wi = wall ? _mm_setzero_pd() : pack(b[i0].inv_mass, b[i1].inv_mass);
  const __m128d m_eff = _mm_loadu_pd(&w.m_eff[q]), pn = _mm_loadu_pd(&w.pn[q]);
  for (int k = 0; k < 3; ++k) dv[k] = _mm_sub_pd(vj[k], vi[k]);
  const __m128d vn = dot2(dv, n);
  const __m128d pn_new = _mm_max_pd(
      _mm_add_pd(pn, _mm_mul_pd(m_eff, _mm_sub_pd(_mm_loadu_pd(&w.target[q]), vn))), _mm_setzero_pd());
  const __m128d dpn = _mm_sub_pd(pn_new, pn);
  _mm_storeu_pd(&w.pn[q], pn_new);
  const __m128d si = _mm_mul_pd(dpn, wi), sj = _mm_mul_pd(dpn, wj);
  for (int k = 0; k < 3; ++k) {
    if (!wall) vi[k] = _mm_sub_pd(vi[k], _mm_mul_pd(si, n[k]));
    vj[k] = _mm_add_pd(vj[k], _mm_mul_pd(sj, n[k]));
  }
  for (int k = 0; k < 3; ++k) dv[k] = _mm_sub_pd(vj[k], vi[k]);
  const __m128d dvn = dot2(dv, n);
  __m128d pt_new[3];
  for (int k = 0; k < 3; ++k) {
    const __m128d vt = _mm_sub_pd(dv[k], _mm_mul_pd(dvn, n[k]));
    pt_new[k] = _mm_sub_pd(pt[k], _mm_mul_pd(m_eff, vt));
  }
  const __m128d bound = _mm_mul_pd(_mm_loadu_pd(&w.mu[q]), pn_new);
  const __m128d len = _mm_sqrt_pd(dot2(pt_new, pt_new));
  // minpd's rule (its second operand on NaN) is the scalar update's min.
  const __m128d f = _mm_min_pd(_mm_div_pd(bound, len), _mm_set1_pd(1.0));
  for (int k = 0; k < 3; ++k) {
    pt_new[k] = _mm_mul_pd(pt_new[k], f);
    const __m128d dpt = _mm_sub_pd(pt_new[k], pt[k]);
    _mm_storeu_pd(&w.pt[k][q], pt_new[k]);
    if (!wall) {
      vi[k] = _mm_sub_pd(vi[k], _mm_mul_pd(wi, dpt));
      _mm_storel_pd(&b[i0].v[k], vi[k]);
      _mm_storeh_pd(&b[i1].v[k], vi[k]);
    }
    vj[k] = _mm_add_pd(vj[k], _mm_mul_pd(wj, dpt));
    _mm_storel_pd(&b[j0].v[k], vj[k]);
    _mm_storeh_pd(&b[j1].v[k], vj[k]);
  }
}
#endif

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define SIMREEL_SOLVE_WIDE 1
/// dot2() in four lanes.
__attribute__((target("avx2"), always_inline)) inline __m256d dot4(const __m256d* a, const __m256d* b) {
  return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(a[0], b[0]), _mm256_mul_pd(a[1], b[1])),
                       _mm256_mul_pd(a[2], b[2]));
}

/// The four particles' velocities (out[0..2]: x, y, z, one particle a lane) and inverse masses
/// (out[3]): four aligned rows of SolveBody transposed, row halves into register halves (halves())
/// and then unpacks; vperm2f128 is 8 micro-ops on AMD Zen 1 (docs/benchmarks.md, stop 86).
__attribute__((target("avx2"), always_inline)) inline __m256d halves(const double* lo, const double* hi) {
  return _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_load_pd(lo)), _mm_load_pd(hi), 1);
}
__attribute__((target("avx2"), always_inline)) inline void load_bodies(const SolveBody* b, const std::uint32_t* p,
                                                                      __m256d* out) {
  const __m256d t0 = halves(b[p[0]].v, b[p[2]].v), t1 = halves(b[p[1]].v, b[p[3]].v);  // (v0 v1)
  const __m256d t2 = halves(b[p[0]].v + 2, b[p[2]].v + 2), t3 = halves(b[p[1]].v + 2, b[p[3]].v + 2);  // (v2 w)
  out[0] = _mm256_unpacklo_pd(t0, t1), out[1] = _mm256_unpackhi_pd(t0, t1);
  out[2] = _mm256_unpacklo_pd(t2, t3), out[3] = _mm256_unpackhi_pd(t2, t3);
}

/// load_bodies() in reverse: velocities v[0..2] and inverse masses w, one particle a lane, back
/// to their four rows, each written whole (so a later load of it is forwarded) by 128-bit inserts.
__attribute__((target("avx2"), always_inline)) inline void store_bodies(SolveBody* b, const std::uint32_t* p,
                                                                       const __m256d* v, __m256d w) {
  const __m256d a = _mm256_unpacklo_pd(v[0], v[1]), c = _mm256_unpackhi_pd(v[0], v[1]);
  const __m256d d = _mm256_unpacklo_pd(v[2], w), e = _mm256_unpackhi_pd(v[2], w);
  _mm256_store_pd(b[p[0]].v, _mm256_insertf128_pd(a, _mm256_castpd256_pd128(d), 1));
  _mm256_store_pd(b[p[1]].v, _mm256_insertf128_pd(c, _mm256_castpd256_pd128(e), 1));
  _mm256_store_pd(b[p[2]].v, _mm256_insertf128_pd(d, _mm256_extractf128_pd(a, 1), 0));
  _mm256_store_pd(b[p[3]].v, _mm256_insertf128_pd(e, _mm256_extractf128_pd(c, 1), 0));
}

/// update2() for contacts q .. q + 4G - 1 of one wave, in the four lanes of AVX registers, G
/// groups of four. The contacts' fields are loaded whole from their columns; the particles'
/// velocities and inverse masses by transposing their rows. With G = 2 each step of the update
/// is taken for both groups before the next: the two chains of dependent operations (the
/// square root and the division among them) are then near each other in the instruction
/// stream, and the processor overlaps them, where one group's update alone spans more
/// instructions than it looks ahead.
template <bool wall, int G, class W>
__attribute__((target("avx2"), always_inline)) inline void update4(W& w, std::size_t q, const Vec3* vc,
                                                                   SolveBody* b) {
  __m256d n[G][3], vi[G][4], vj[G][4], dv[G][3], pt[G][3], pt_new[G][3];
  __m256d m_eff[G], pn[G], pn_new[G], wi[G], wj[G], f[G];
  for (int g = 0; g < G; ++g) {
    const std::size_t r = q + std::size_t(4 * g);
    load_bodies(b, &w.j[r], vj[g]);
    if (wall) {
      const Vec3* c = vc + 4 * g;
      for (int k = 0; k < 3; ++k) vi[g][k] = _mm256_setr_pd(c[0][k], c[1][k], c[2][k], c[3][k]);
      vi[g][3] = _mm256_setzero_pd();
    } else {
      load_bodies(b, &w.i[r], vi[g]);
    }
    for (int k = 0; k < 3; ++k) {
      n[g][k] = _mm256_loadu_pd(&w.n[k][r]);
      pt[g][k] = _mm256_loadu_pd(&w.pt[k][r]);
    }
    wj[g] = vj[g][3];
    wi[g] = vi[g][3];
    m_eff[g] = _mm256_loadu_pd(&w.m_eff[r]);
    pn[g] = _mm256_loadu_pd(&w.pn[r]);
  }
  for (int g = 0; g < G; ++g) {
    const std::size_t r = q + std::size_t(4 * g);
    for (int k = 0; k < 3; ++k) dv[g][k] = _mm256_sub_pd(vj[g][k], vi[g][k]);
    const __m256d vn = dot4(dv[g], n[g]);
    pn_new[g] = _mm256_max_pd(
        _mm256_add_pd(pn[g], _mm256_mul_pd(m_eff[g], _mm256_sub_pd(_mm256_loadu_pd(&w.target[r]), vn))),
        _mm256_setzero_pd());
    const __m256d dpn = _mm256_sub_pd(pn_new[g], pn[g]);
    _mm256_storeu_pd(&w.pn[r], pn_new[g]);
    const __m256d si = _mm256_mul_pd(dpn, wi[g]), sj = _mm256_mul_pd(dpn, wj[g]);
    for (int k = 0; k < 3; ++k) {
      if (!wall) vi[g][k] = _mm256_sub_pd(vi[g][k], _mm256_mul_pd(si, n[g][k]));
      vj[g][k] = _mm256_add_pd(vj[g][k], _mm256_mul_pd(sj, n[g][k]));
    }
  }
  for (int g = 0; g < G; ++g) {
    for (int k = 0; k < 3; ++k) dv[g][k] = _mm256_sub_pd(vj[g][k], vi[g][k]);
    const __m256d dvn = dot4(dv[g], n[g]);
    for (int k = 0; k < 3; ++k) {
      const __m256d vt = _mm256_sub_pd(dv[g][k], _mm256_mul_pd(dvn, n[g][k]));
      pt_new[g][k] = _mm256_sub_pd(pt[g][k], _mm256_mul_pd(m_eff[g], vt));
    }
  }
  for (int g = 0; g < G; ++g) {
    const std::size_t r = q + std::size_t(4 * g);
    const __m256d bound = _mm256_mul_pd(_mm256_loadu_pd(&w.mu[r]), pn_new[g]);
    const __m256d len = _mm256_sqrt_pd(dot4(pt_new[g], pt_new[g]));
    f[g] = _mm256_min_pd(_mm256_div_pd(bound, len), _mm256_set1_pd(1.0));
  }
  for (int g = 0; g < G; ++g) {
    const std::size_t r = q + std::size_t(4 * g);
    for (int k = 0; k < 3; ++k) {
      pt_new[g][k] = _mm256_mul_pd(pt_new[g][k], f[g]);
      const __m256d dpt = _mm256_sub_pd(pt_new[g][k], pt[g][k]);
      _mm256_storeu_pd(&w.pt[k][r], pt_new[g][k]);
      if (!wall) vi[g][k] = _mm256_sub_pd(vi[g][k], _mm256_mul_pd(wi[g], dpt));
      vj[g][k] = _mm256_add_pd(vj[g][k], _mm256_mul_pd(wj[g], dpt));
    }
    if (!wall) store_bodies(b, &w.i[r], vi[g], wi[g]);
    store_bodies(b, &w.j[r], vj[g], wj[g]);
  }
}

/// What the overlap projection's updates read and write (project_positions()).
struct ProjectColumns {
  Vec3* x;  ///< and x_before, radius, inv_mass: per particle
  const Vec3* x_before;
  const double *radius, *inv_mass;
  const std::uint32_t *i, *j;  ///< and found (its depth when found, negative: apart), n: per contact
  const double *found, *n[3];
  double position_fraction, slop_fraction;
};

/// Component c of the four particles p[0..3]'s positions, one a lane; then a[p[0..3]].
__attribute__((target("avx2"), always_inline)) inline __m256d lane_load(const Vec3* x, const std::uint32_t* p, int c) {
  return _mm256_setr_pd(x[p[0]][c], x[p[1]][c], x[p[2]][c], x[p[3]][c]);
}
__attribute__((target("avx2"), always_inline)) inline __m256d lane_load(const double* a, const std::uint32_t* p) {
  return _mm256_setr_pd(a[p[0]], a[p[1]], a[p[2]], a[p[3]]);
}

/// The projection's update (project_positions()) of contacts q .. q + 4G - 1 of one wave, in
/// the four lanes of AVX registers, G groups interleaved as update4()'s; each lane performs the
/// scalar update's operations in its order, and a lane whose contact does not push keeps its
/// particles' positions bit for bit.
template <bool wall, int G>
__attribute__((target("avx2"), always_inline)) inline void project4(const ProjectColumns& a, std::size_t q) {
  const __m256d zero = _mm256_setzero_pd();
  __m256d xi[G][3], xj[G][3], nn[G][3], depth[G], goal[G], wi[G], wj[G], push[G];
  for (int g = 0; g < G; ++g) {
    const std::size_t r = q + std::size_t(4 * g);
    const std::uint32_t* pj = a.j + r;
    const __m256d found = _mm256_loadu_pd(a.found + r);
    for (int c = 0; c < 3; ++c) xj[g][c] = lane_load(a.x, pj, c);
    wj[g] = lane_load(a.inv_mass, pj);
    if (wall) {
      __m256d d[3];
      for (int c = 0; c < 3; ++c) {
        nn[g][c] = _mm256_loadu_pd(a.n[c] + r);
        d[c] = _mm256_sub_pd(xj[g][c], lane_load(a.x_before, pj, c));
      }
      depth[g] = _mm256_sub_pd(found, dot4(nn[g], d));
      goal[g] = _mm256_blendv_pd(zero, _mm256_mul_pd(_mm256_set1_pd(1.0 - a.position_fraction), found),
                                 _mm256_cmp_pd(found, zero, _CMP_GT_OQ));
      wi[g] = zero;
      push[g] = _mm256_cmp_pd(depth[g], goal[g], _CMP_GT_OQ);
    } else {
      const std::uint32_t* pi = a.i + r;
      __m256d d[3];
      for (int c = 0; c < 3; ++c) {
        xi[g][c] = lane_load(a.x, pi, c);
        d[c] = _mm256_sub_pd(xj[g][c], xi[g][c]);
      }
      const __m256d dist = _mm256_sqrt_pd(dot4(d, d));
      for (int c = 0; c < 3; ++c) nn[g][c] = _mm256_div_pd(d[c], dist);
      const __m256d ri = lane_load(a.radius, pi), rj = lane_load(a.radius, pj);
      depth[g] = _mm256_sub_pd(_mm256_add_pd(ri, rj), dist);
      // min_pd(rj, ri) is std::min(ri, rj) (rj < ri ? rj : ri); max_pd(y, 0) std::max(0.0, y).
      const __m256d slop = _mm256_mul_pd(_mm256_set1_pd(a.slop_fraction), _mm256_min_pd(rj, ri));
      goal[g] = _mm256_max_pd(
          _mm256_sub_pd(found, _mm256_mul_pd(_mm256_set1_pd(a.position_fraction),
                                             _mm256_max_pd(_mm256_sub_pd(found, slop), zero))),
          zero);
      wi[g] = lane_load(a.inv_mass, pi);
      push[g] = _mm256_and_pd(_mm256_cmp_pd(dist, zero, _CMP_GT_OQ), _mm256_cmp_pd(depth[g], goal[g], _CMP_GT_OQ));
    }
  }
  for (int g = 0; g < G; ++g) {
    const std::size_t r = q + std::size_t(4 * g);
    const __m256d corr = _mm256_div_pd(_mm256_sub_pd(depth[g], goal[g]), _mm256_add_pd(wi[g], wj[g]));
    const __m256d si = _mm256_mul_pd(corr, wi[g]), sj = _mm256_mul_pd(corr, wj[g]);
    alignas(32) double oi[3][4], oj[3][4];
    for (int c = 0; c < 3; ++c) {
      _mm256_store_pd(oj[c], _mm256_blendv_pd(xj[g][c], _mm256_add_pd(xj[g][c], _mm256_mul_pd(sj, nn[g][c])), push[g]));
      if (!wall)
        _mm256_store_pd(oi[c], _mm256_blendv_pd(xi[g][c], _mm256_sub_pd(xi[g][c], _mm256_mul_pd(si, nn[g][c])), push[g]));
    }
    for (int l = 0; l < 4; ++l) {
      if (!wall) a.x[a.i[r + std::size_t(l)]] = Vec3(oi[0][l], oi[1][l], oi[2][l]);
      a.x[a.j[r + std::size_t(l)]] = Vec3(oj[0][l], oj[1][l], oj[2][l]);
    }
  }
}

/// One projection sweep over work positions [begin, end): the runs marked for four and eight
/// lanes in AVX registers, the others by `one` (the scalar update of work position k).
template <class F>
__attribute__((target("avx2"))) void project_wide(const ProjectColumns& a, const std::uint8_t* next,
                                                  std::size_t begin, std::size_t end, const F& one) {
  for (std::size_t q = begin; q < end;) {
    const bool wall = a.i[q] == ParticleCollider::kCollider;
    if (next[q] == 3) {
      wall ? project4<true, 2>(a, q) : project4<false, 2>(a, q);
      q += 8;
    } else if (next[q] == 2) {
      wall ? project4<true, 1>(a, q) : project4<false, 1>(a, q);
      q += 4;
    } else {
      one(q);
      ++q;
    }
  }
}

/// The widest update the CPU runs, up to `max_lanes` (checked once per CPU feature).
int widest_lanes(int max_lanes) {
  __builtin_cpu_init();
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (max_lanes >= 8 && avx2) return 8;
  if (max_lanes >= 4 && avx2) return 4;
  return std::min(max_lanes, 2);
}
#else
#define SIMREEL_SOLVE_WIDE 0
int widest_lanes(int max_lanes) {
#if defined(__SSE2__)
  return std::min(max_lanes, 2);
#else
  return 1;
#endif
}
#endif

/// The update of the run that starts at work position q, where schedule() marked it for two
/// lanes (next[q] == 1), else of contact q alone; returns the contacts it took.
template <class W>
__attribute__((always_inline)) inline std::size_t update_narrow(W& w, const std::uint8_t* next, const Vec3* vc,
                                                                SolveBody* b, std::size_t q) {
  const bool wall = w.i[q] == ParticleCollider::kCollider;  // a run is one wave's, so of one kind
#if defined(__SSE2__)
  if (next[q] == 1) {
    wall ? update2<true>(w, q, vc + q, b) : update2<false>(w, q, vc + q, b);
    return 2;
  }
#endif
  wall ? update1<true>(w, q, vc[q], b) : update1<false>(w, q, vc[q], b);
  return 1;
}

/// One sweep over work positions [begin, end), each marked run in SIMD lanes (at most two).
template <class W>
void sweep_narrow(W& w, const std::uint8_t* next, const Vec3* vc, SolveBody* b, std::size_t begin,
                  std::size_t end) {
  for (std::size_t q = begin; q < end;) q += update_narrow(w, next, vc, b, q);
}

#if SIMREEL_SOLVE_WIDE
/// sweep_narrow() with the runs marked for eight and four lanes in AVX registers (AVX2 CPUs
/// only), the updates inlined into the loop.
template <class W>
__attribute__((target("avx2"), always_inline)) inline void sweep_wide_loop(W& w, const std::uint8_t* next,
                                                                           const Vec3* vc, SolveBody* b,
                                                                           std::size_t begin, std::size_t end) {
  for (std::size_t q = begin; q < end;) {
    if (next[q] == 3) {
      w.i[q] == ParticleCollider::kCollider ? update4<true, 2>(w, q, vc + q, b) : update4<false, 2>(w, q, vc + q, b);
      q += 8;
    } else if (next[q] == 2) {
      w.i[q] == ParticleCollider::kCollider ? update4<true, 1>(w, q, vc + q, b) : update4<false, 1>(w, q, vc + q, b);
      q += 4;
    } else {
      q += update_narrow(w, next, vc, b, q);
    }
  }
}
template <class W>
__attribute__((target("avx2"))) void sweep_wide(W& w, const std::uint8_t* next, const Vec3* vc, SolveBody* b,
                                                std::size_t begin, std::size_t end) {
  sweep_wide_loop(w, next, vc, b, begin, end);
}
/// sweep_wide() where the CPU has AVX-512VL: the same instructions on 256-bit registers (the
/// same bits), but 32 of them instead of 16, so two groups' updates fit without spilling.
template <class W>
__attribute__((target("avx2,avx512f,avx512vl"))) void sweep_wide_evex(W& w, const std::uint8_t* next, const Vec3* vc,
                                                                      SolveBody* b, std::size_t begin, std::size_t end) {
  sweep_wide_loop(w, next, vc, b, begin, end);
}
/// The CPU runs sweep_wide_evex() (the pair search's test: SIMREEL_NO_VECTOR_CLONES is off for both).
bool has_evex() {
#if SIMREEL_HAS_VECTOR_CLONES
  static const bool evex = cpu_has_avx512vl();
  return evex;
#endif
  return false;
}
#endif

}  // namespace

int solve_lanes(int max_lanes) { return widest_lanes(max_lanes); }

template <class F>
void ParticleCollider::sweep_bands(int sweeps, const F& over, bool skip_lone) {
  // With skip_lone, the first sweep visits every contact and the later ones leave out the lone
  // contacts at the end of each range (work_ positions: schedule(); none when lone_contacts is
  // false).
  const auto later = [&](int it) { return skip_lone && it > 0; };
  if (bands_.empty()) {
    for (int it = 0; it < sweeps; ++it) over(std::size_t(0), later(it) ? std::size_t(lone_begin_) : contacts.size());
    return;
  }
  const std::size_t nb = bands_.size();
  // Phases: the pairs of the even bands, of the odd bands, then every collider contact (one
  // particle each: the bands' are independent of each other). A phase's bands share no
  // particle, so they may go in any order and on any thread, and which thread solves a band
  // changes nothing in the result.
  const int parts = threads > 1 && x.size() >= kParallelMin ? threads : 1;
  // A phase's bands: first, first + step, ... (the even, the odd, then all of them).
  const auto first_of = [](int phase) { return phase == 1 ? std::size_t(1) : std::size_t(0); };
  const auto step_of = [](int phase) { return phase == 2 ? std::size_t(1) : std::size_t(2); };
  const auto solve_band = [&](int it, int phase, std::size_t b) {
    const Band& band = bands_[b];
    if (phase < 2) {
      over(std::size_t(band.pair_begin), std::size_t(later(it) ? band.pair_lone : band.pair_end));
    } else {
      over(std::size_t(band.wall_begin), std::size_t(later(it) ? band.wall_lone : band.wall_end));
    }
  };
  if (parts == 1) {
    for (int it = 0; it < sweeps; ++it)
      for (int phase = 0; phase < 3; ++phase)
        for (std::size_t b = first_of(phase); b < nb; b += step_of(phase)) solve_band(it, phase, b);
    return;
  }
  // For a large system one parallel region holds all the sweeps (a barrier after each phase).
  // Each thread owns a run of a phase's bands about even in contacts, the same run every sweep
  // (so its particles stay in its core's cache), and solves it from the front; a thread done
  // with its own run takes bands from the back of the others'. A thread on a slower or busier
  // core then holds the others at the barrier no longer than one band (on a 2-core VM, one core
  // ran the 100k-particle cloud 1.3-1.6x slower than the other). Handing out single bands to
  // whichever thread came next was slower than the fixed split (27.8 against 23.0 ms a step):
  // neighbouring bands then sit on different cores every phase.
  const auto size = [&](int phase, std::size_t b) {
    const Band& band = bands_[b];
    return phase < 2 ? std::size_t(band.pair_end - band.pair_begin) : std::size_t(band.wall_end - band.wall_begin);
  };
  // run_[(3 sweep + phase) parts + t]: thread t's run of that phase's bands, counted in the
  // phase's own bands (band first + step k).
  const std::size_t p = std::size_t(parts);
  run_.resize(std::size_t(3 * sweeps) * p);
  for (int phase = 0; phase < 3; ++phase) {
    const std::size_t first = first_of(phase), step = step_of(phase);
    const std::size_t count = nb > first ? (nb - first + step - 1) / step : 0;
    std::size_t total = 0;
    for (std::size_t k = 0; k < count; ++k) total += size(phase, first + step * k);
    std::size_t k = 0, sum = 0, front = 0;
    for (std::size_t t = 0; t < p; ++t) {
      std::size_t back = count;
      if (t + 1 < p) {
        const std::size_t goal = total * (t + 1) / p;
        while (k < count && sum + size(phase, first + step * k) / 2 < goal) {  // ends nearest the goal
          sum += size(phase, first + step * k);
          ++k;
        }
        back = k;
      }
      for (int it = 0; it < sweeps; ++it)
        run_[(std::size_t(3 * it + phase)) * p + t] = claim_run(front, back);
      front = back;
    }
  }
#pragma omp parallel num_threads(parts)
  {
    const std::size_t t = std::size_t(omp_get_thread_num());
    for (int it = 0; it < sweeps; ++it) {
      for (int phase = 0; phase < 3; ++phase) {
        const std::size_t first = first_of(phase), step = step_of(phase);
        drain_runs(&run_[std::size_t(3 * it + phase) * p], p, t,
                   [&](std::size_t k) { solve_band(it, phase, first + step * k); });
#pragma omp barrier
      }
    }
  }
}

void ParticleCollider::apply_impulses(int parts) {
  // The impulse on the second particle, p = pn n + pt (the first takes -p), once per contact.
  const auto impulse = [](const Contact& c) { return Vec3(c.pn * c.n + c.pt); };
  // Particle q's row takes +p or -p: b.v + m p and b.v - m p componentwise, the bits of
  // v += m p and v -= m p.
  SolveBody* b = body_.data();
  const auto gets = [&](std::uint32_t q, const Vec3& p) {
    for (int k = 0; k < 3; ++k) b[q].v[k] = b[q].v[k] + inv_mass[q] * p[k];
  };
  const auto gives = [&](std::uint32_t q, const Vec3& p) {
    for (int k = 0; k < 3; ++k) b[q].v[k] = b[q].v[k] - inv_mass[q] * p[k];
  };
  if (parts <= 1 || bands_.size() < 2) {
    for (const Contact& c : contacts) {
      const Vec3 p = impulse(c);
      if (c.i != kCollider) gives(c.i, p);
      gets(c.j, p);
    }
    return;
  }
  // A particle of band b takes impulses from the pairs of band b - 1 (as their second particle),
  // then from those of band b, then from its collider contacts: the order of one pass, kept by
  // each thread for the particles of its bands.
  cut_bands(parts, band_cut_);
#pragma omp parallel num_threads(parts)
  {
    const std::size_t t = std::size_t(omp_get_thread_num());
    const std::size_t b0 = band_cut_[t], b1 = band_cut_[t + 1];
    if (b0 < b1) {
      const std::uint32_t p1 = band_first_[b1];
      if (b0 > 0)
        for (std::uint32_t q = bands_[b0 - 1].pair_begin; q < bands_[b0 - 1].pair_end; ++q) {
          const Contact& c = contacts[q];
          if (c.j >= band_first_[b0]) gets(c.j, impulse(c));
        }
      for (std::uint32_t q = bands_[b0].pair_begin; q < bands_[b1 - 1].pair_end; ++q) {
        const Contact& c = contacts[q];
        const Vec3 p = impulse(c);
        gives(c.i, p);
        if (c.j < p1) gets(c.j, p);
      }
      for (std::uint32_t q = bands_[b0].wall_begin; q < bands_[b1 - 1].wall_end; ++q) {
        const Contact& c = contacts[q];
        gets(c.j, impulse(c));
      }
    }
  }
}

void ParticleCollider::SolverColumns::resize(std::size_t m) {
  i.resize(m);
  j.resize(m);
  for (auto* col : {&n[0], &n[1], &n[2], &m_eff, &target, &mu, &pn, &pt[0], &pt[1], &pt[2]}) col->resize(m);
}

void ParticleCollider::solve() {
  solve_rows();
  const std::ptrdiff_t np = std::ptrdiff_t(x.size());
  const int par = threads > 1 && x.size() >= kParallelMin ? threads : 1;
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
  for (std::ptrdiff_t pp = 0; pp < np; ++pp) {
    const std::size_t p = std::size_t(pp);
    v[p] = Vec3(body_[p].v[0], body_[p].v[1], body_[p].v[2]);
  }
}

void ParticleCollider::solve_rows() {
  // The sweeps run over the contacts in wavefront order (schedule()), which is the same
  // Gauss-Seidel sweep to the bit; the impulses go back to `contacts` at the end. Each run of a
  // wave's contacts that schedule() marked goes to the SIMD update of its width.
  schedule();
  // The sweeps read each particle's velocity and inverse mass as one aligned row (body_), which
  // the four-lane update loads and stores whole.
  const std::ptrdiff_t np = std::ptrdiff_t(x.size());
  const int par = threads > 1 && x.size() >= kParallelMin ? threads : 1;
  body_.resize(x.size());
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
  for (std::ptrdiff_t pp = 0; pp < np; ++pp) {
    const std::size_t p = std::size_t(pp);
    body_[p] = SolveBody{{v[p][0], v[p][1], v[p][2]}, inv_mass[p]};
  }
  apply_impulses(par);
  SolveBody* bp = body_.data();
  const std::uint8_t* next = pair_next_.data();
  const Vec3* vc = work_vc_.data();
#if SIMREEL_SOLVE_WIDE
  const bool wide = wavefront && solve_lanes(max_lanes) >= 4;  // runs of four or eight marked
  const bool evex = wide && avx512_registers && has_evex();
#endif
  const auto sweep = [&](std::size_t begin, std::size_t end) {
#if SIMREEL_SOLVE_WIDE
    if (wide) {
      evex ? sweep_wide_evex(work_, next, vc, bp, begin, end) : sweep_wide(work_, next, vc, bp, begin, end);
      return;
    }
#endif
    sweep_narrow(work_, next, vc, bp, begin, end);
  };
  const auto give_back = [&] {
    const std::ptrdiff_t m = std::ptrdiff_t(sched_.size());
#pragma omp parallel for schedule(static) num_threads(par) if (par > 1)
    for (std::ptrdiff_t kk = 0; kk < m; ++kk) {
      const std::size_t k = std::size_t(kk);
      Contact& c = contacts[sched_[k]];
      c.pn = work_.pn[k];
      c.pt = Vec3(work_.pt[0][k], work_.pt[1][k], work_.pt[2][k]);
    }
  };
  sweep_bands(iterations, sweep, true);
  give_back();
}

void ParticleCollider::project_positions() { project_positions(false); }

void ParticleCollider::project_positions(bool work_order) {
  if (x_before.size() != x.size()) x_before = x;
  // The update of a contact between particles i and j (i == kCollider: j against a collider,
  // n its normal) found at depth `found` (negative: apart).
  const auto update = [&](std::uint32_t i, std::uint32_t j, double found, const Vec3& n) {
    const bool wall = i == kCollider;
    double slop = 0.0, depth = 0.0;
    Vec3 nn = n;
    if (wall) {
      // The surface as the plane of its closest feature at the start of the projection.
      depth = found - n.dot(x[j] - x_before[j]);
    } else {
      const Vec3 d = x[j] - x[i];
      const double dist = d.norm();
      if (!(dist > 0.0)) return;
      nn = d / dist;
      depth = radius[i] + radius[j] - dist;
      slop = slop_fraction * std::min(radius[i], radius[j]);
    }
    // Each contact aims at the same end depth in every sweep, so the sweeps converge to it.
    // A speculative contact (found apart) may close its gap (goal 0) but not go deeper, a
    // collider's as a pair's. Holding a pair at the gap it was found with instead undid, every
    // step, what the solve let gravity close (it allows an approach of gap / h): a settled pile
    // kept beads whose velocity read 1-9 cm/s while the projection put them back where they
    // were, so they never fell asleep (201 of 5,000 in the bowl at 10 s).
    const double goal = wall ? (found > 0.0 ? (1.0 - position_fraction) * found : 0.0)
                             : std::max(0.0, found - position_fraction * std::max(0.0, found - slop));
    if (!(depth > goal)) return;
    const double wi = wall ? 0.0 : inv_mass[i], wj = inv_mass[j];
    const double corr = (depth - goal) / (wi + wj);
    if (!wall) x[i] -= corr * wi * nn;
    x[j] += corr * wj * nn;
  };
  // In work order (solve_rows()'s schedule, its columns and work_depth_) the same sweep to the
  // bit: each update moves only its two particles and the schedule keeps each particle's
  // contacts in their order. Consecutive updates then share no particle, where in contact order
  // consecutive pairs mostly share their first one and each waited on the one before (its
  // square root and two divisions).
  if (work_order) {
    const auto one = [&](std::size_t k) {
      const std::uint32_t i = work_.i[k];
      const Vec3 n = i == kCollider ? Vec3(work_.n[0][k], work_.n[1][k], work_.n[2][k]) : Vec3::Zero();
      update(i, work_.j[k], work_depth_[k], n);
    };
#if SIMREEL_SOLVE_WIDE
    // The runs of one wave the schedule marked for the SIMD lanes: the same bits, four updates
    // at a time.
    if (wavefront && solve_lanes(max_lanes) >= 4) {
      const ProjectColumns cols{x.data(),       x_before.data(),   radius.data(),
                                inv_mass.data(), work_.i.data(),    work_.j.data(),
                                work_depth_.data(), {work_.n[0].data(), work_.n[1].data(), work_.n[2].data()},
                                position_fraction, slop_fraction};
      const std::uint8_t* next = pair_next_.data();
      const auto project = [&](std::size_t begin, std::size_t end) { project_wide(cols, next, begin, end, one); };
      sweep_bands(position_iterations, project, false);
      return;
    }
#endif
    const auto project = [&](std::size_t begin, std::size_t end) {
      for (std::size_t k = begin; k < end; ++k) one(k);
    };
    sweep_bands(position_iterations, project, false);
    return;
  }
  const auto project = [&](std::size_t begin, std::size_t end) {
    for (std::size_t q = begin; q < end; ++q) {
      const Contact& c = contacts[q];
      update(c.i, c.j, c.depth, c.n);
    }
  };
  // A large system's sweeps go like the solve's, the same order at any thread count.
  sweep_bands(position_iterations, project, false);
}

}  // namespace simreel::sim::detail
