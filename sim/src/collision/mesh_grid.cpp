// Uniform grid over a mesh's triangles (Coutinho §2.3.1), built by a counting sort of
// (cell, rank) entries.
#include "collision/mesh_grid.hpp"

#include <algorithm>
#include <cmath>

namespace simreel::sim::detail {

MeshGrid::MeshGrid(const std::vector<Triangle>& tris, const std::vector<std::uint32_t>& visit) {
  const std::size_t n = tris.size();
  if (n == 0 || visit.size() != n) return;
  visit_ = visit;
  box_.resize(6 * n);
  Aabb all;
  double extent = 0.0;  // mean of the triangles' largest box side
  for (std::size_t r = 0; r < n; ++r) {
    const Aabb b = triangle_box(tris[visit[r]]);
    all.grow(b);
    for (int k = 0; k < 3; ++k) {
      box_[6 * r + std::size_t(k)] = b.lo[k];
      box_[6 * r + 3 + std::size_t(k)] = b.hi[k];
    }
    extent += (b.hi - b.lo).maxCoeff() / double(n);
  }
  lo_ = all.lo;
  hi_ = all.hi;
  // Cells about the size of a triangle, at most 4 per triangle in all.
  const Vec3 size = (hi_ - lo_).cwiseMax(1e-9);
  double cell = std::max(extent, 1e-9);
  for (;;) {
    double cells = 1.0;
    for (int k = 0; k < 3; ++k) cells *= std::floor(size[k] / cell) + 1.0;
    if (cells <= 4.0 * double(n) + 64.0) break;
    cell *= 1.25;
  }
  inv_cell_ = 1.0 / cell;
  for (int k = 0; k < 3; ++k) dim_[k] = std::int64_t(std::floor(size[k] * inv_cell_)) + 1;
  const std::size_t cells = std::size_t(dim_[0] * dim_[1] * dim_[2]);
  auto cell_range = [&](std::size_t r, int k, std::int64_t& c0, std::int64_t& c1) {
    const double a = (box_[6 * r + std::size_t(k)] - lo_[k]) * inv_cell_;
    const double b = (box_[6 * r + 3 + std::size_t(k)] - lo_[k]) * inv_cell_;
    c0 = std::clamp(std::int64_t(a), std::int64_t(0), dim_[k] - 1);
    c1 = std::clamp(std::int64_t(b), std::int64_t(0), dim_[k] - 1);
  };
  // Two passes of a counting sort: counts per cell, then ranks in increasing order per cell.
  start_.assign(cells + 1, 0);
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<std::uint32_t> fill;
    if (pass == 1) {
      for (std::size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
      rank_.resize(start_[cells]);
      fill.assign(start_.begin(), start_.end() - 1);
    }
    for (std::size_t r = 0; r < n; ++r) {
      std::int64_t c0[3], c1[3];
      for (int k = 0; k < 3; ++k) cell_range(r, k, c0[k], c1[k]);
      for (std::int64_t z = c0[2]; z <= c1[2]; ++z)
        for (std::int64_t y = c0[1]; y <= c1[1]; ++y)
          for (std::int64_t x = c0[0]; x <= c1[0]; ++x) {
            const std::size_t c = std::size_t((z * dim_[1] + y) * dim_[0] + x);
            if (pass == 0)
              ++start_[c + 1];
            else
              rank_[fill[c]++] = std::uint32_t(r);
          }
    }
  }
}

}  // namespace simreel::sim::detail
