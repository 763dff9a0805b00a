#include "cloth/spring_stencil.hpp"

#include <algorithm>

#include "core/vector_clones.hpp"

namespace simreel::sim::detail {

namespace {

/// The springs' forces W_c[a] = S_c[a] (y_a - y_{a+o_c}) for a in [i0, i1), every class
/// (vectors and blocks in the stencil's layout: components `stride` apart, padded).
SIMREEL_VECTOR_CLONES
void spring_forces(std::ptrdiff_t i0, std::ptrdiff_t i1, const double* __restrict y,
                   const double* __restrict blocks, const std::size_t* offsets,
                   std::size_t classes, std::ptrdiff_t stride, double* __restrict w) {
  const double* yx = y;
  const double* yy = yx + stride;
  const double* yz = yy + stride;
  for (std::size_t c = 0; c < classes; ++c) {
    const auto o = std::ptrdiff_t(offsets[c]);
    const double* bxx = blocks + std::ptrdiff_t(6 * c) * stride;
    const double* bxy = bxx + stride;
    const double* bxz = bxy + stride;
    const double* byy = bxz + stride;
    const double* byz = byy + stride;
    const double* bzz = byz + stride;
    double* wx = w + std::ptrdiff_t(3 * c) * stride;
    double* wy = wx + stride;
    double* wz = wy + stride;
    for (std::ptrdiff_t i = i0; i < i1; ++i) {
      const double dx = yx[i] - yx[i + o], dy = yy[i] - yy[i + o], dz = yz[i] - yz[i + o];
      wx[i] = bxx[i] * dx + bxy[i] * dy + bxz[i] * dz;
      wy[i] = bxy[i] * dx + byy[i] * dy + byz[i] * dz;
      wz[i] = bxz[i] * dx + byz[i] * dy + bzz[i] * dz;
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
/// (h f_i + Σ_c (W_c[i] - W_c[i - o_c])) (layout as spring_forces; D, pc: 6 arrays; f: AoS).
SIMREEL_VECTOR_CLONES
void assemble_rows(std::ptrdiff_t i0, std::ptrdiff_t i1, const double* __restrict D,
                   const double* __restrict blocks, const double* __restrict w,
                   const std::size_t* offsets, std::size_t classes, std::ptrdiff_t stride,
                   const double* __restrict mask, double h, const double* __restrict f,
                   double* __restrict pc, double* __restrict b) {
  const std::ptrdiff_t st = stride;
  for (std::ptrdiff_t i = i0; i < i1; ++i) {
    for (std::ptrdiff_t k = 0; k < 6; ++k) pc[k * st + i] = D[k * st + i];
    for (std::ptrdiff_t k = 0; k < 3; ++k) b[k * st + i] = h * f[3 * i + k];
  }
  for (std::size_t c = 0; c < classes; ++c) {
    const auto o = std::ptrdiff_t(offsets[c]);
    const double* bc = blocks + std::ptrdiff_t(6 * c) * st;
    const double* wc = w + std::ptrdiff_t(3 * c) * st;
    for (std::ptrdiff_t i = i0; i < i1; ++i) {
      for (std::ptrdiff_t k = 0; k < 6; ++k)
        pc[k * st + i] = (pc[k * st + i] + bc[k * st + i]) + bc[k * st + i - o];
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

void SpringStencil::build(const ClothTopology& topo) {
  *this = SpringStencil{};
  const std::size_t ns = topo.spring_count();
  n_ = topo.local_rest.size();
  stride_ = n_;
  std::vector<std::size_t> first(ns), class_of(ns), offsets;
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
    class_of[s] = std::size_t(it - offsets.begin());
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
  slot_.resize(ns);
  rhs_slot_.resize(ns);
  for (std::size_t s = 0; s < ns; ++s) {
    slot_[s] = 6 * class_of[s] * stride_ + pad_ + first[s];
    rhs_slot_[s] = 3 * class_of[s] * stride_ + pad_ + first[s];
  }
  blocks_.assign(6 * classes_ * stride_, 0.0);
  forces_.assign(3 * classes_ * stride_, 0.0);
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
