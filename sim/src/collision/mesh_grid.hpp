#pragma once
// Uniform grid over the triangles of a mesh collider, in the mesh's local frame, built once at
// registration beside its AABB tree (Coutinho §2.3.1: a uniform grid finds the candidates of a
// small query in O(1) cells, where the tree walks O(log n) nodes scattered in memory). It
// answers the small boxes of swept particles; larger ones go to the tree. Private.

#include <cstdint>
#include <vector>

#include "collision/bvh.hpp"

namespace simreel::sim::detail {

/// Cells of a fixed size over the mesh's bounds, each listing (as a contiguous range) the
/// triangles whose box overlaps it. Triangles are named by their rank in the tree's visiting
/// order, so a query can hand them out in that order: a first-hit search over them keeps the
/// tree's choice among equal times (and so its bits).
class MeshGrid {
 public:
  static constexpr int kMaxCells = 8;       ///< larger queries: the tree
  static constexpr int kMaxCandidates = 96;  ///< more entries in the cells: the tree

  MeshGrid() = default;
  /// Grid over tris (local frame); visit = the tree's triangle order (Bvh::visit_order()).
  MeshGrid(const std::vector<Triangle>& tris, const std::vector<std::uint32_t>& visit);

  /// Calls f(triangle index) for every triangle whose own box overlaps [lo, hi], in the tree's
  /// visiting order, and returns true; or returns false (having called nothing) when the box
  /// spans more than kMaxCells cells or its cells hold more than kMaxCandidates entries.
  template <class F>
  bool query(const Vec3& lo, const Vec3& hi, F&& f) const {
    if (start_.empty()) return false;
    std::int64_t c0[3], c1[3];
    std::int64_t cells = 1;
    for (int k = 0; k < 3; ++k) {
      if (!(lo[k] <= hi_[k] && hi[k] >= lo_[k])) return true;  // outside the mesh's bounds
      const double a = (lo[k] - lo_[k]) * inv_cell_, b = (hi[k] - lo_[k]) * inv_cell_;
      c0[k] = a <= 0.0 ? 0 : std::int64_t(std::min(a, double(dim_[k] - 1)));
      c1[k] = b <= 0.0 ? 0 : std::int64_t(std::min(b, double(dim_[k] - 1)));
      cells *= c1[k] - c0[k] + 1;
    }
    if (cells > kMaxCells) return false;
    std::uint32_t cand[kMaxCandidates];
    int count = 0;
    for (std::int64_t z = c0[2]; z <= c1[2]; ++z)
      for (std::int64_t y = c0[1]; y <= c1[1]; ++y)
        for (std::int64_t x = c0[0]; x <= c1[0]; ++x) {
          const std::size_t c = std::size_t((z * dim_[1] + y) * dim_[0] + x);
          const std::uint32_t b = start_[c], e = start_[c + 1];
          if (count + int(e - b) > kMaxCandidates) return false;
          for (std::uint32_t q = b; q < e; ++q) {
            const std::uint32_t rank = rank_[q];
            const double* box = &box_[6 * std::size_t(rank)];
            if (box[0] <= hi[0] && box[1] <= hi[1] && box[2] <= hi[2] && box[3] >= lo[0] &&
                box[4] >= lo[1] && box[5] >= lo[2])
              cand[count++] = rank;
          }
        }
    // Few entries: insertion sort, then each rank once (a triangle may sit in several cells).
    for (int i = 1; i < count; ++i) {
      const std::uint32_t v = cand[i];
      int j = i;
      for (; j > 0 && cand[j - 1] > v; --j) cand[j] = cand[j - 1];
      cand[j] = v;
    }
    for (int i = 0; i < count; ++i)
      if (i == 0 || cand[i] != cand[i - 1]) f(visit_[cand[i]]);
    return true;
  }

 private:
  Vec3 lo_ = Vec3::Zero(), hi_ = Vec3::Zero();  ///< (m) bounds of the mesh, local frame
  double inv_cell_ = 0.0;                       ///< (1/m)
  std::int64_t dim_[3] = {0, 0, 0};             ///< cells per axis
  std::vector<std::uint32_t> start_;  ///< (cells + 1) first entry of each cell in rank_
  std::vector<std::uint32_t> rank_;   ///< entries: ranks of the triangles, increasing per cell
  std::vector<std::uint32_t> visit_;  ///< rank -> triangle index (the tree's order)
  std::vector<double> box_;           ///< (triangles x 6) by rank: lo x, y, z, hi x, y, z (m)
};

}  // namespace simreel::sim::detail
