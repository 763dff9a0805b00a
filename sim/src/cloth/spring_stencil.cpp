#include "cloth/spring_stencil.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/vector_clones.hpp"

namespace simreel::sim::detail {

namespace {

/// Spring state for a in [i0, i1), one class of offset o (arrays at the class's entries; x, v:
/// vectors, components `st` apart): length, direction (a to a + o) and the force on a.
SIMREEL_VECTOR_CLONES
void spring_state(std::ptrdiff_t i0, std::ptrdiff_t i1, std::ptrdiff_t o, std::ptrdiff_t st,
                  const double* __restrict x, const double* __restrict v,
                  const double* __restrict rest, const double* __restrict ks,
                  const double* __restrict kds, double* __restrict len, double* __restrict u,
                  double* __restrict F) {
  for (std::ptrdiff_t i = i0; i < i1; ++i) {
    const double dx = x[i + o] - x[i], dy = x[st + i + o] - x[st + i],
                 dz = x[2 * st + i + o] - x[2 * st + i];
    const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
    // l = 0 only where d = 0: u = 0 then, and so is the force (no division by zero to mask).
    const double il = 1.0 / (l > 0.0 ? l : 1.0);
    const double ux = dx * il, uy = dy * il, uz = dz * il;
    const double vrel = (v[i + o] - v[i]) * ux + (v[st + i + o] - v[st + i]) * uy +
                        (v[2 * st + i + o] - v[2 * st + i]) * uz;
    const double mag = ks[i] * (l - rest[i]) + kds[i] * vrel;
    len[i] = l;
    u[i] = ux;
    u[st + i] = uy;
    u[2 * st + i] = uz;
    F[i] = mag * ux;
    F[st + i] = mag * uy;
    F[2 * st + i] = mag * uz;
  }
}

/// f_i = m (g - c v_i) + Σ_c (F_c[i] - F_c[i - o_c]) for i in [i0, i1) (F: per class 3 arrays,
/// `st` apart).
SIMREEL_VECTOR_CLONES
void gather_spring_forces(std::ptrdiff_t i0, std::ptrdiff_t i1, std::ptrdiff_t st,
                          const double* __restrict v, double m, double gx, double gy, double gz,
                          double c, const double* __restrict F, const std::size_t* offsets,
                          std::size_t classes, double* __restrict f) {
  for (std::ptrdiff_t i = i0; i < i1; ++i) {
    f[i] = m * (gx - c * v[i]);
    f[st + i] = m * (gy - c * v[st + i]);
    f[2 * st + i] = m * (gz - c * v[2 * st + i]);
  }
  for (std::size_t k = 0; k < classes; ++k) {
    const auto o = std::ptrdiff_t(offsets[k]);
    const double* Fc = F + std::ptrdiff_t(3 * k) * st;
    for (std::ptrdiff_t i = i0; i < i1; ++i)
      for (std::ptrdiff_t d = 0; d < 3; ++d)
        f[d * st + i] = (f[d * st + i] + Fc[d * st + i]) - Fc[d * st + i - o];
  }
}

/// Blocks and right-hand-side terms for a in [i0, i1), one class of offset o (see blocks()):
/// q, β into B (4 arrays) and w = h² K (v_{a+o} - v_a) into W (3 arrays).
SIMREEL_VECTOR_CLONES
void spring_blocks(std::ptrdiff_t i0, std::ptrdiff_t i1, std::ptrdiff_t o, std::ptrdiff_t st,
                   double h, const double* __restrict v, const double* __restrict rest,
                   const double* __restrict ks, const double* __restrict kds,
                   const double* __restrict len, const double* __restrict u,
                   double* __restrict B, double* __restrict W) {
  const double h2 = h * h;
  for (std::ptrdiff_t i = i0; i < i1; ++i) {
    const double l = len[i], k = ks[i];
    const double live = l > 0.0 ? 1.0 : 0.0;
    const double transverse = live * k * std::max(0.0, 1.0 - rest[i] / (l > 0.0 ? l : 1.0));
    const double along = h2 * (k - transverse) * live, beta = h2 * transverse;
    const double sq = std::sqrt(std::max(0.0, along + h * kds[i] * live));
    const double ux = u[i], uy = u[st + i], uz = u[2 * st + i];
    B[i] = sq * ux;
    B[st + i] = sq * uy;
    B[2 * st + i] = sq * uz;
    B[3 * st + i] = beta;
    const double dx = v[i + o] - v[i], dy = v[st + i + o] - v[st + i],
                 dz = v[2 * st + i + o] - v[2 * st + i];
    const double a = along * (ux * dx + uy * dy + uz * dz);
    W[i] = a * ux + beta * dx;
    W[st + i] = a * uy + beta * dy;
    W[2 * st + i] = a * uz + beta * dz;
  }
}

/// The springs' forces W_c[a] = S_c[a] (y_a - y_{a+o_c}) = q (q · d) + β d for a in [i0, i1),
/// every class (vectors in the stencil's layout: components `stride` apart, padded; blocks: per
/// class 4 arrays q, β).
SIMREEL_VECTOR_CLONES
void spring_forces(std::ptrdiff_t i0, std::ptrdiff_t i1, const double* __restrict y,
                   const double* __restrict blocks, const std::size_t* offsets,
                   std::size_t classes, std::ptrdiff_t stride, double* __restrict w) {
  const double* yx = y;
  const double* yy = yx + stride;
  const double* yz = yy + stride;
  for (std::size_t c = 0; c < classes; ++c) {
    const auto o = std::ptrdiff_t(offsets[c]);
    const double* qx = blocks + std::ptrdiff_t(4 * c) * stride;
    const double* qy = qx + stride;
    const double* qz = qy + stride;
    const double* bt = qz + stride;
    double* wx = w + std::ptrdiff_t(3 * c) * stride;
    double* wy = wx + stride;
    double* wz = wy + stride;
    for (std::ptrdiff_t i = i0; i < i1; ++i) {
      const double dx = yx[i] - yx[i + o], dy = yy[i] - yy[i + o], dz = yz[i] - yz[i + o];
      const double p = qx[i] * dx + qy[i] * dy + qz[i] * dz;
      wx[i] = qx[i] * p + bt[i] * dx;
      wy[i] = qy[i] * p + bt[i] * dy;
      wz[i] = qz[i] * p + bt[i] * dz;
    }
  }
}

/// out_i = mask_i (D_i y_i + Σ_c (W_c[i] - W_c[i - o_c])) and yAy_i = y_i · out_i for i in
/// [i0, i1): each spring's force counted at both of its ends (layout as spring_forces; D: 6
/// arrays xx xy xz yy yz zz).
SIMREEL_VECTOR_CLONES
void gather_forces(std::ptrdiff_t i0, std::ptrdiff_t i1, const double* __restrict D,
                   const double* __restrict y,
                   const double* __restrict w, const std::size_t* offsets, std::size_t classes,
                   std::ptrdiff_t stride, const double* __restrict mask, double* __restrict out,
                   double* __restrict yAy) {
  const double* yx = y;
  const double* yy = yx + stride;
  const double* yz = yy + stride;
  double* ox = out;
  double* oy = out + stride;
  double* oz = oy + stride;
  for (std::ptrdiff_t i = i0; i < i1; ++i) {
    const double dxx = D[i], dxy = D[stride + i], dxz = D[2 * stride + i],
                 dyy = D[3 * stride + i], dyz = D[4 * stride + i], dzz = D[5 * stride + i];
    ox[i] = dxx * yx[i] + dxy * yy[i] + dxz * yz[i];
    oy[i] = dxy * yx[i] + dyy * yy[i] + dyz * yz[i];
    oz[i] = dxz * yx[i] + dyz * yy[i] + dzz * yz[i];
  }
  for (std::size_t c = 0; c < classes; ++c) {
    const auto o = std::ptrdiff_t(offsets[c]);
    const double* wx = w + std::ptrdiff_t(3 * c) * stride;
    const double* wy = wx + stride;
    const double* wz = wy + stride;
    // One read and one write of each sum (ox, oy, oz share `out`, so the compiler may not keep
    // them in registers across statements).
    for (std::ptrdiff_t i = i0; i < i1; ++i) {
      ox[i] = (ox[i] + wx[i]) - wx[i - o];
      oy[i] = (oy[i] + wy[i]) - wy[i - o];
      oz[i] = (oz[i] + wz[i]) - wz[i - o];
    }
  }
  for (std::ptrdiff_t i = i0; i < i1; ++i) {
    ox[i] *= mask[i];
    oy[i] *= mask[i];
    oz[i] *= mask[i];
    yAy[i] = yx[i] * ox[i] + yy[i] * oy[i] + yz[i] * oz[i];
  }
}

/// For i in [i0, i1): pc_i = mask_i (D_i + Σ_c (S_c[i] + S_c[i - o_c]))⁻¹ and b_i = mask_i
/// (h f_i + Σ_c (W_c[i] - W_c[i - o_c])) (layout as spring_forces; D, pc: 6 arrays; f: a vector).
SIMREEL_VECTOR_CLONES
void assemble_rows(std::ptrdiff_t i0, std::ptrdiff_t i1, const double* __restrict D,
                   const double* __restrict blocks, const double* __restrict w,
                   const std::size_t* offsets, std::size_t classes, std::ptrdiff_t stride,
                   const double* __restrict mask, double h, const double* __restrict f,
                   double* __restrict pc, double* __restrict b) {
  const std::ptrdiff_t st = stride;
  for (std::ptrdiff_t i = i0; i < i1; ++i) {
    for (std::ptrdiff_t k = 0; k < 6; ++k) pc[k * st + i] = D[k * st + i];
    for (std::ptrdiff_t k = 0; k < 3; ++k) b[k * st + i] = h * f[k * st + i];
  }
  for (std::size_t c = 0; c < classes; ++c) {
    const auto o = std::ptrdiff_t(offsets[c]);
    const double* qx = blocks + std::ptrdiff_t(4 * c) * st;
    const double* qy = qx + st;
    const double* qz = qy + st;
    const double* bt = qz + st;
    const double* wc = w + std::ptrdiff_t(3 * c) * st;
    for (std::ptrdiff_t i = i0; i < i1; ++i) {
      // The blocks q qᵀ + β I of the spring from i and of the spring into i.
      const double ax = qx[i], ay = qy[i], az = qz[i], ab = bt[i];
      const double cx = qx[i - o], cy = qy[i - o], cz = qz[i - o], cb = bt[i - o];
      pc[i] = (pc[i] + (ax * ax + ab)) + (cx * cx + cb);
      pc[st + i] = (pc[st + i] + ax * ay) + cx * cy;
      pc[2 * st + i] = (pc[2 * st + i] + ax * az) + cx * cz;
      pc[3 * st + i] = (pc[3 * st + i] + (ay * ay + ab)) + (cy * cy + cb);
      pc[4 * st + i] = (pc[4 * st + i] + ay * az) + cy * cz;
      pc[5 * st + i] = (pc[5 * st + i] + (az * az + ab)) + (cz * cz + cb);
      for (std::ptrdiff_t k = 0; k < 3; ++k)
        b[k * st + i] = (b[k * st + i] + wc[k * st + i]) - wc[k * st + i - o];
    }
  }
  for (std::ptrdiff_t i = i0; i < i1; ++i) {  // the adjugate over the determinant
    const double xx = pc[i], xy = pc[st + i], xz = pc[2 * st + i], yy = pc[3 * st + i],
                 yz = pc[4 * st + i], zz = pc[5 * st + i];
    const double c_xx = yy * zz - yz * yz, c_xy = xz * yz - xy * zz, c_xz = xy * yz - xz * yy;
    const double id = mask[i] / (xx * c_xx + xy * c_xy + xz * c_xz);
    pc[i] = c_xx * id;
    pc[st + i] = c_xy * id;
    pc[2 * st + i] = c_xz * id;
    pc[3 * st + i] = (xx * zz - xz * xz) * id;
    pc[4 * st + i] = (xz * xy - xx * yz) * id;
    pc[5 * st + i] = (xx * yy - xy * xy) * id;
    for (std::ptrdiff_t k = 0; k < 3; ++k) b[k * st + i] *= mask[i];
  }
}

constexpr std::ptrdiff_t kChunk = 512;  // vertices per task (a multiple of the vector width)

}  // namespace

void SpringStencil::build(const ClothTopology& topo, const std::vector<double>& ks,
                          const std::vector<double>& kds) {
  *this = SpringStencil{};
  const std::size_t ns = topo.spring_count();
  n_ = topo.local_rest.size();
  stride_ = n_;
  std::vector<std::uint32_t> first(ns), class_of(ns);
  std::vector<std::size_t> offsets;
  for (std::size_t s = 0; s < ns; ++s) {
    const std::uint32_t a = std::min(topo.spring_a[s], topo.spring_b[s]);
    const std::uint32_t b = std::max(topo.spring_a[s], topo.spring_b[s]);
    if (a == b) return;
    const std::size_t o = b - a;
    auto it = std::find(offsets.begin(), offsets.end(), o);
    if (it == offsets.end()) {
      if (offsets.size() == kMaxClasses) return;
      offsets.push_back(o);
      it = offsets.end() - 1;
    }
    class_of[s] = std::uint32_t(it - offsets.begin());
    first[s] = a;
  }
  if (offsets.empty()) return;
  // One spring per (class, first vertex): a second would join the same pair of vertices.
  std::vector<std::uint8_t> taken(offsets.size() * n_, 0);
  for (std::size_t s = 0; s < ns; ++s) {
    std::uint8_t& t = taken[class_of[s] * n_ + first[s]];
    if (t != 0) return;
    t = 1;
  }
  classes_ = offsets.size();
  offset_ = offsets;
  pad_ = *std::max_element(offsets.begin(), offsets.end());
  // Component arrays an odd multiple of 64 bytes apart: the product's ~20 streams then sit at
  // different offsets modulo 4 KiB (a load that aliases an earlier store there waits for it).
  stride_ = (2 * pad_ + n_ + 7) / 8 * 8;
  if ((stride_ / 8) % 2 == 0) stride_ += 8;
  class_ = std::move(class_of);
  first_ = std::move(first);
  for (auto* a : {&rest_, &ks_, &kds_, &len_}) a->assign(classes_ * stride_, 0.0);
  dir_.assign(3 * classes_ * stride_, 0.0);
  blocks_.assign(4 * classes_ * stride_, 0.0);
  forces_.assign(3 * classes_ * stride_, 0.0);
  for (std::size_t s = 0; s < ns; ++s) {
    rest_[at(s, 1, 0)] = topo.rest_length[s];
    ks_[at(s, 1, 0)] = ks.empty() ? 0.0 : ks[s];
    kds_[at(s, 1, 0)] = kds.empty() ? 0.0 : kds[s];
  }
}

Sym3 SpringStencil::block(std::size_t s) const {
  const Vec3 q(blocks_[at(s, 4, 0)], blocks_[at(s, 4, 1)], blocks_[at(s, 4, 2)]);
  Sym3 b = Sym3::outer(q, 1.0);
  b.add_diagonal(blocks_[at(s, 4, 3)]);
  return b;
}

void SpringStencil::set(std::size_t s, const Vec3& q, double beta) {
  for (std::size_t k = 0; k < 3; ++k) blocks_[at(s, 4, k)] = q[Eigen::Index(k)];
  blocks_[at(s, 4, 3)] = beta;
}

void SpringStencil::set_rhs(std::size_t s, const Vec3& w) {
  for (std::size_t k = 0; k < 3; ++k) forces_[at(s, 3, k)] = w[Eigen::Index(k)];
}

void SpringStencil::forces(const double* x, const double* v, double m, const Vec3& g, double c,
                           double* f, int threads) {
  const auto n = std::ptrdiff_t(n_), st = std::ptrdiff_t(stride_), pad = std::ptrdiff_t(pad_);
  const std::ptrdiff_t chunks = (n + kChunk - 1) / kChunk;
  const auto cls = std::ptrdiff_t(classes_);
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
#pragma omp for schedule(static) collapse(2)
    for (std::ptrdiff_t k = 0; k < cls; ++k)
      for (std::ptrdiff_t j = 0; j < chunks; ++j)
        spring_state(j * kChunk, std::min(n, (j + 1) * kChunk), std::ptrdiff_t(offset_[k]), st, x,
                     v, rest_.data() + k * st + pad, ks_.data() + k * st + pad,
                     kds_.data() + k * st + pad, len_.data() + k * st + pad,
                     dir_.data() + 3 * k * st + pad, forces_.data() + 3 * k * st + pad);
#pragma omp for schedule(static)
    for (std::ptrdiff_t j = 0; j < chunks; ++j)
      gather_spring_forces(j * kChunk, std::min(n, (j + 1) * kChunk), st, v, m, g.x(), g.y(),
                           g.z(), c, forces_.data() + pad, offset_.data(), classes_, f);
  }
}

void SpringStencil::blocks(double h, const double* v, int threads) {
  const auto n = std::ptrdiff_t(n_), st = std::ptrdiff_t(stride_), pad = std::ptrdiff_t(pad_);
  const std::ptrdiff_t chunks = (n + kChunk - 1) / kChunk;
  const auto cls = std::ptrdiff_t(classes_);
#pragma omp parallel for schedule(static) collapse(2) num_threads(threads) if (threads > 1)
  for (std::ptrdiff_t k = 0; k < cls; ++k)
    for (std::ptrdiff_t j = 0; j < chunks; ++j)
      spring_blocks(j * kChunk, std::min(n, (j + 1) * kChunk), std::ptrdiff_t(offset_[k]), st, h,
                    v, rest_.data() + k * st + pad, ks_.data() + k * st + pad,
                    kds_.data() + k * st + pad, len_.data() + k * st + pad,
                    dir_.data() + 3 * k * st + pad, blocks_.data() + 4 * k * st + pad,
                    forces_.data() + 3 * k * st + pad);
}

void SpringStencil::assemble(const double* diag, const double* mask, double h, const double* f,
                             double* pc, double* b, int threads) {
  const auto n = std::ptrdiff_t(n_), stride = std::ptrdiff_t(stride_);
  const std::ptrdiff_t chunks = (n + kChunk - 1) / kChunk;
#pragma omp parallel for schedule(static) num_threads(threads) if (threads > 1)
  for (std::ptrdiff_t k = 0; k < chunks; ++k)
    assemble_rows(k * kChunk, std::min(n, (k + 1) * kChunk), diag, blocks_.data() + pad_,
                  forces_.data() + pad_, offset_.data(), classes_, stride, mask, h, f, pc, b);
}

void SpringStencil::apply(const double* y, const double* diag, const double* mask, double* out,
                          double* yAy, int threads) {
  const auto n = std::ptrdiff_t(n_), stride = std::ptrdiff_t(stride_);
  const std::ptrdiff_t chunks = (n + kChunk - 1) / kChunk;
  const double* blocks = blocks_.data() + pad_;
  double* w = forces_.data() + pad_;
  if (threads <= 1) {
    // Chunk by chunk, forces then sums: a chunk's sums read forces of this chunk and of the
    // chunks before it (i - o_c < i), the nearest ones still in cache (the 64 x 64 grid's
    // forces, 0.6 MB, do not fit in this machine's 512 KB L2).
    for (std::ptrdiff_t k = 0; k < chunks; ++k) {
      const std::ptrdiff_t i0 = k * kChunk, i1 = std::min(n, i0 + kChunk);
      spring_forces(i0, i1, y, blocks, offset_.data(), classes_, stride, w);
      gather_forces(i0, i1, diag, y, w, offset_.data(), classes_, stride, mask, out, yAy);
    }
    return;
  }
  // Every force before any sum: a vertex's sum reads forces of other threads' chunks. The same
  // operations as above, so the same bits.
#pragma omp parallel num_threads(threads)
  {
#pragma omp for schedule(static)
    for (std::ptrdiff_t k = 0; k < chunks; ++k)
      spring_forces(k * kChunk, std::min(n, (k + 1) * kChunk), y, blocks, offset_.data(),
                    classes_, stride, w);
#pragma omp for schedule(static)
    for (std::ptrdiff_t k = 0; k < chunks; ++k)
      gather_forces(k * kChunk, std::min(n, (k + 1) * kChunk), diag, y, w, offset_.data(),
                    classes_, stride, mask, out, yAy);
  }
}

}  // namespace simreel::sim::detail
