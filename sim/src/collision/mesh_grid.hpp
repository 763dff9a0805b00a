#pragma once
// Uniform grid over the triangles of a mesh collider, in the mesh's local frame, built once at
// registration beside its AABB tree (Coutinho §2.3.1: a uniform grid finds the candidates of a
// small query in O(1) cells, where the tree walks O(log n) nodes scattered in memory). It
// answers the small boxes of swept particles; larger ones go to the tree. Private.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "collision/bvh.hpp"
#include "collision/narrow_phase.hpp"
#include "core/prefetch.hpp"

namespace simreel::sim::detail {

/// Cells of a fixed size over the mesh's bounds, each listing (as a contiguous run of blocks)
/// the triangles whose box overlaps it. Triangles are named by their rank in the tree's visiting
/// order, so a query can hand them out in that order: a first-hit search over them keeps the
/// tree's choice among equal times (and so its bits). The grid keeps its own copy of the
/// triangles by rank, with their edge data, so that the narrow phase reads them in the order
/// they lie in space and derives nothing from them per query. Where memory allows, each cell
/// also lists the triangles near it (its halo list), so that a box across a cell's side, as a
/// particle's box near a surface mostly is, is answered from one list instead of a merge of
/// several. (A bead's box in the pile_in_bowl benchmark spans 3.8 cells on average and meets
/// 1.3 triangles; boxes like it took half the time from a halo list.)
class MeshGrid {
 public:
  static constexpr int kMaxCells = 8;        ///< larger queries: the tree
  static constexpr int kMaxCandidates = 96;  ///< more entries in the cells: the tree
  static constexpr int kLanes = 4;           ///< entries per block (one SSE register)
  /// (cells) A cell's halo: how far past its sides a query box may reach and still be answered
  /// from the cell's halo list alone (see query()).
  static constexpr double kHaloCells = 0.35;
  /// The halo lists are built when they hold at most kHaloBudget times the entries of the
  /// cells' own lists and at most kHaloMaxEntries entries (about 60 MB; a large mesh, or one of
  /// triangles small against the cells, goes without them: the 100k-triangle terrain of the
  /// rain benchmarks would take 3.5 times its 0.43 M entries).
  static constexpr std::size_t kHaloBudget = 3;
  static constexpr std::size_t kHaloMaxEntries = std::size_t{1} << 21;

  MeshGrid() = default;
  /// Grid over tris (local frame); visit = the tree's triangle order (Bvh::visit_order()).
  MeshGrid(const std::vector<Triangle>& tris, const std::vector<std::uint32_t>& visit);

  /// (m) How far past a cell's sides a query box may reach and be answered from the cell's halo
  /// list: kHaloCells of a cell's side; 0 where the grid keeps no halo lists.
  [[nodiscard]] double halo() const { return halo_; }
  /// (m) The low side on axis k (local frame) of the cells that hold coordinate x there, the
  /// grid's first or last where x lies beyond it (for tests: boxes at a halo's sides).
  [[nodiscard]] double cell_side(double x, int k) const {
    const double c = std::min(std::max(std::floor((x - lo_[k]) * inv_cell_), 0.0), last_[k]);
    return lo_[k] + c * cell_size_;
  }
  /// Number of cells (cell_of() gives -1 or an index below it).
  [[nodiscard]] std::size_t cell_count() const { return cell_.size(); }
  /// The cell holding p (local frame, m) — the one a query() of a box around p reads — or -1
  /// where p lies outside the mesh's bounds (NaN too): for prefetch() only.
  [[nodiscard]] std::int64_t cell_of(const Vec3& p) const {
    if (cell_.empty()) return -1;
    int c[3];
    for (int k = 0; k < 3; ++k) {
      if (!(p[k] >= lo_[k] && p[k] <= hi_[k])) return -1;
      c[k] = int(std::min((p[k] - lo_[k]) * inv_cell_, last_[k]));
    }
    return std::int64_t(index(c));
  }
  /// Asks for the memory a query about p in `cell` (from cell_of; -1: nothing) reads, one link
  /// of the chain at a time, so that a caller walking a list of particles can ask for each link
  /// at its own distance ahead of its queries: stage 0 the cell's record, 1 its blocks (reading
  /// the record), 2 its triangles whose boxes hold p in x and y (reading the blocks). A hint: it
  /// changes no result. (The rain benchmark's first second: ~10 % faster on one thread.)
  void prefetch(std::int64_t cell, int stage, const Vec3& p) const {
    if (cell < 0) return;
    const Cell* rg = &cell_[std::size_t(cell)];
    if (stage == 0) {
      prefetch_line(rg);
      return;
    }
    const std::uint32_t end = std::min(rg->end, rg->begin + std::uint32_t(kMaxCandidates / kLanes));
    if (stage == 1) {
      for (std::uint32_t b = rg->begin; b < end; ++b) {
        prefetch_line(&blocks_[b]);
        prefetch_line(reinterpret_cast<const char*>(&blocks_[b]) + 64);
      }
      return;
    }
    const float x = float(p.x()), y = float(p.y());
    for (std::uint32_t b = rg->begin; b < end; ++b) {
      const Block& k = blocks_[b];
      for (int l = 0; l < kLanes; ++l)
        if (k.lo[0][l] <= x && k.hi[0][l] >= x && k.lo[1][l] <= y && k.hi[1][l] >= y) {
          const char* t = reinterpret_cast<const char*>(&tris_[k.rank[l]]);
          for (std::size_t o = 0; o < sizeof(SweepTriangle); o += 64) prefetch_line(t + o);
        }
    }
  }

  /// True when no point of any triangle lies in [lo, hi] (local frame, m), shown cheaply: the box
  /// lies outside the mesh's bounds, or above or below the part of every triangle that lies over
  /// the (at most 2 x 2) columns it spans in x and y (kColumnsPerCell to a cell's side). So no
  /// sweep whose segment grown by its radius lies in the box can meet a triangle (sweep_mesh()
  /// may still be handed triangles whose boxes reach into it, and would find no hit). The
  /// columns' bounds are the triangles clipped to each column, rounded outward to floats by one
  /// more ulp, then to a step of 1/254 of the bounds' height and one step further. False where it
  /// cannot tell. Two bytes per column, so the table stays in cache while particles visit it in
  /// no order: rain above a terrain is told from the columns alone, without reading its cells
  /// (collide()'s rejection test, §2.3.1).
  [[nodiscard]] bool clear_of(const Vec3& lo, const Vec3& hi) const {
    if (cell_.empty()) return false;
    for (int k = 0; k < 3; ++k)
      if (lo[k] > hi_[k] || hi[k] < lo_[k]) return true;
    if (!(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2])) return false;  // NaN or empty
    int c0[2], c1[2];
    for (int k = 0; k < 2; ++k) {
      c0[k] = int(std::min(std::max((lo[k] - lo_[k]) * inv_column_, 0.0), column_last_[k]));
      c1[k] = int(std::min(std::max((hi[k] - lo_[k]) * inv_column_, 0.0), column_last_[k]));
      if (c1[k] - c0[k] > 1) return false;
    }
    std::uint8_t qlo = 255, qhi = 0;
    for (int y = c0[1]; y <= c1[1]; ++y)
      for (int x = c0[0]; x <= c1[0]; ++x) {
        const std::size_t col = std::size_t(y) * std::size_t(column_dim_[0]) + std::size_t(x);
        qlo = std::min(qlo, column_[2 * col]);
        qhi = std::max(qhi, column_[2 * col + 1]);
      }
    return lo[2] > level_[qhi] || hi[2] < level_[qlo];
  }

  /// clear_of()'s data, for a form of it that answers several boxes at once
  /// (columns_clear_block()): the mesh's bounds (m), columns per metre, columns per row, the
  /// last column's index on x and y, the column table (2 bytes per column, row order, then 2
  /// bytes of padding), the levels (m), and their base z0 and step (m): level q for 1 <= q <= 254
  /// is z0 + q step, those very operations, so lanes can compute a level instead of reading it.
  /// `empty`: no cells (clear_of() answers false).
  struct ColumnTable {
    const double* lo;
    const double* hi;
    double inv_column;
    std::int64_t dim_x;
    const double* last;
    const std::uint8_t* column;
    const double* level;
    double level_z0;
    double level_step;
    bool empty;
  };
  /// A number no other grid built in this process has (copies share it, and their tables): what
  /// a cache of column answers (ColumnMemo) is valid for. 0 for an empty grid.
  [[nodiscard]] std::uint64_t serial() const { return serial_; }
  [[nodiscard]] ColumnTable column_table() const {
    return {lo_.data(), hi_.data(), inv_column_, column_dim_[0], column_last_, column_.data(),
            level_,     level_z0_,  level_step_, cell_.empty()};
  }

  /// Calls f(triangle with its edge data, its index in the mesh) for every triangle whose own
  /// box overlaps [lo, hi] (local frame, m) — and perhaps a few more within float rounding of
  /// it, which a swept-sphere test rejects exactly — each once, in the tree's visiting order,
  /// and returns true; or returns false (having called nothing) when the box spans more than
  /// kMaxCells cells or its cells hold more than kMaxCandidates entries, and no cell's halo
  /// list answers it.
  template <class F>
  bool query(const Vec3& lo, const Vec3& hi, F&& f) const {
    if (cell_.empty()) return false;
    int c0[3], c1[3];
    int cells = 1;
    for (int k = 0; k < 3; ++k) {
      if (!(lo[k] <= hi_[k] && hi[k] >= lo_[k])) return true;  // outside the mesh's bounds
      // Within the bounds, so neither is NaN: clamped to [0, dim - 1] and truncated.
      c0[k] = int(std::min(std::max((lo[k] - lo_[k]) * inv_cell_, 0.0), last_[k]));
      c1[k] = int(std::min(std::max((hi[k] - lo_[k]) * inv_cell_, 0.0), last_[k]));
      cells *= c1[k] - c0[k] + 1;
    }
    // One list holds every triangle the box may meet, its ranks increasing and each once: the
    // list of the one cell the box lies in, or else the halo list of the cell of the box's
    // centre where the box lies within that cell's halo (a particle's box across a cell's side,
    // most of the time; the halo list holds the triangles whose boxes overlap the cell grown by
    // the halo). Either needs no merging of lists.
    const auto scan = [&](const Cell& rg, const std::vector<Block>& blocks) {
      const Query q(lo, hi);
      for (std::uint32_t b = rg.begin; b < rg.end; ++b)
        for (unsigned mask = q.mask(blocks[b]); mask != 0; mask &= mask - 1) {
          const std::uint32_t rank = blocks[b].rank[std::countr_zero(mask)];
          f(tris_[rank], visit_[rank]);
        }
    };
    if (cells == 1) {
      const Cell& rg = cell_[index(c0)];
      if (kLanes * int(rg.end - rg.begin) > kMaxCandidates) return false;
      scan(rg, blocks_);
      return true;
    }
    if (halo_ > 0.0) {
      int c[3];
      bool within = true;
      for (int k = 0; k < 3 && within; ++k) {
        c[k] = int(std::min(std::max((0.5 * (lo[k] + hi[k]) - lo_[k]) * inv_cell_, 0.0), last_[k]));
        // The first and last cells reach out to infinity (their lists hold what lies beyond).
        within = (c[k] == 0 || lo[k] >= lo_[k] + double(c[k]) * cell_size_ - halo_) &&
                 (double(c[k]) == last_[k] || hi[k] <= lo_[k] + double(c[k] + 1) * cell_size_ + halo_);
      }
      if (within) {
        const Cell& rg = halo_cell_[index(c)];
        if (kLanes * int(rg.end - rg.begin) <= kMaxCandidates) {
          scan(rg, halo_blocks_);
          return true;
        }
      }
    }
    if (cells > kMaxCells) return false;
    // The query box and the entries' boxes to the nearest floats: rounding is monotonic
    // (a <= b gives float(a) <= float(b)), so no triangle whose box overlaps is missed; one
    // whose box misses by less than float rounding may come too.
    const Query q(lo, hi);
    std::uint32_t cand[kMaxCandidates + kLanes];
    int count = 0;
    for (int z = c0[2]; z <= c1[2]; ++z)
      for (int y = c0[1]; y <= c1[1]; ++y)
        for (int x = c0[0]; x <= c1[0]; ++x) {
          const int c[3] = {x, y, z};
          const Cell& rg = cell_[index(c)];
          if (count + kLanes * int(rg.end - rg.begin) > kMaxCandidates) return false;
          for (std::uint32_t b = rg.begin; b < rg.end; ++b) count += q.overlaps(blocks_[b], cand + count);
        }
    // Several cells: ranks in increasing order (insertion sort of a few), each once (a triangle
    // may sit in several cells). One cell lists its ranks in increasing order already.
    if (cells > 1)
      for (int i = 1; i < count; ++i) {
        const std::uint32_t v = cand[i];
        int j = i;
        for (; j > 0 && cand[j - 1] > v; --j) cand[j] = cand[j - 1];
        cand[j] = v;
      }
    for (int i = 0; i < count; ++i)
      if (i == 0 || cand[i] != cand[i - 1]) f(tris_[cand[i]], visit_[cand[i]]);
    return true;
  }

 private:
  /// kLanes entries side by side: boxes (local frame, m; nearest floats) and ranks. An
  /// unused lane has an empty box (lo = +inf, hi = -inf).
  struct alignas(16) Block {
    float lo[3][kLanes], hi[3][kLanes];
    std::uint32_t rank[kLanes];
  };
  struct Cell {
    std::uint32_t begin, end;  ///< the cell's blocks
  };

  /// A query box in floats, each bound in every lane.
  struct Query {
#if defined(__SSE2__)
    __m128 lo[3], hi[3];
    Query(const Vec3& l, const Vec3& h) {
      for (int k = 0; k < 3; ++k) {
        lo[k] = _mm_set1_ps(float(l[k]));
        hi[k] = _mm_set1_ps(float(h[k]));
      }
    }
#else
    float lo[3], hi[3];
    Query(const Vec3& l, const Vec3& h) {
      for (int k = 0; k < 3; ++k) {
        lo[k] = float(l[k]);
        hi[k] = float(h[k]);
      }
    }
#endif
    /// Bit l set: lane l of b overlaps this box.
    unsigned mask(const Block& b) const {
      unsigned mask;
#if defined(__SSE2__)
      __m128 m = _mm_and_ps(_mm_cmple_ps(_mm_load_ps(b.lo[0]), hi[0]),
                            _mm_cmpge_ps(_mm_load_ps(b.hi[0]), lo[0]));
      for (int k = 1; k < 3; ++k)
        m = _mm_and_ps(m, _mm_and_ps(_mm_cmple_ps(_mm_load_ps(b.lo[k]), hi[k]),
                                     _mm_cmpge_ps(_mm_load_ps(b.hi[k]), lo[k])));
      mask = unsigned(_mm_movemask_ps(m));
#else
      mask = 0;
      for (int l = 0; l < kLanes; ++l) {
        bool in = true;
        for (int k = 0; k < 3; ++k) in = in && b.lo[k][l] <= hi[k] && b.hi[k][l] >= lo[k];
        mask |= unsigned(in) << l;
      }
#endif
      return mask;
    }
    /// Writes the ranks of b's entries whose box overlaps this one to out, in lane order;
    /// returns how many.
    int overlaps(const Block& b, std::uint32_t* out) const {
      int n = 0;
      for (unsigned m = mask(b); m != 0; m &= m - 1) out[n++] = b.rank[std::countr_zero(m)];
      return n;
    }
  };

  /// The cells [c0, c1] on axis k of the triangle of rank r's box (`box`: lo x, y, z, hi x, y, z
  /// by rank) grown by `grow` (m), clamped to the grid.
  void cell_range(const std::vector<double>& box, double grow, std::size_t r, int k, std::int64_t& c0,
                  std::int64_t& c1) const;
  /// The entries of lists of the boxes grown by `grow`: one per triangle and cell.
  [[nodiscard]] std::size_t entries(const std::vector<double>& box, double grow) const;
  /// Each cell's list of the triangles whose box grown by `grow` overlaps it, into `cell_of`
  /// (by cell) and `blocks` (the runs, in Z-order of the cells).
  void fill_cells(const std::vector<double>& box, double grow, std::vector<Cell>& cell_of,
                  std::vector<Block>& blocks) const;

  [[nodiscard]] std::size_t index(const int* c) const {
    return (std::size_t(c[2]) * std::size_t(dim_[1]) + std::size_t(c[1])) * std::size_t(dim_[0]) +
           std::size_t(c[0]);
  }

  Vec3 lo_ = Vec3::Zero(), hi_ = Vec3::Zero();  ///< (m) bounds of the mesh, local frame
  double inv_cell_ = 0.0;                       ///< (1/m)
  std::int64_t dim_[3] = {0, 0, 0};             ///< cells per axis
  double last_[3] = {0.0, 0.0, 0.0};            ///< dim - 1, the last cell's index
  std::vector<Cell> cell_;                      ///< (cells) row order (x fastest)
  /// Columns per cell side: a column spans less of a sloping surface than a cell. (The rain
  /// benchmark, 1 / 2 / 4: 6.2 / 5.4–5.6 / 5.3 ms a step; the grid of its 100k-triangle terrain
  /// built in about 50 / 120 / 220 ms, its column table 100 / 400 / 1600 KB.)
  static constexpr int kColumnsPerCell = 2;
  double inv_column_ = 0.0;                     ///< (1/m) columns per metre in x and y
  std::int64_t column_dim_[2] = {0, 0};         ///< columns per axis (x, y)
  double column_last_[2] = {0.0, 0.0};          ///< column_dim - 1
  /// (2 x columns) per (x, y) column, row order: the z extent of the parts of the
  /// triangles over it as levels (below), rounded outward (empty: 255, 0). For clear_of().
  std::vector<std::uint8_t> column_;
  /// (m) level q's height: -inf for 0, lo_z + q (hi_z - lo_z) / 254 for 1..254, +inf for 255.
  double level_[256] = {};
  std::uint64_t serial_ = 0;  ///< see serial()
  double level_z0_ = 0.0;    ///< (m) lo_z, the levels' base
  double level_step_ = 0.0;  ///< (m) the levels' step, (hi_z - lo_z) / 254 (at least 1e-9 / 254)
  std::vector<Block> blocks_;                   ///< the cells' runs, in Z-order of the cells
  double halo_ = 0.0;                           ///< (m) kHaloCells cells; 0: no halo lists
  double cell_size_ = 0.0;                      ///< (m) a cell's side (0: no cells)
  std::vector<Cell> halo_cell_;                 ///< (cells) each cell's halo list
  std::vector<Block> halo_blocks_;              ///< the halo lists' runs
  std::vector<SweepTriangle> tris_;             ///< the triangles by rank
  std::vector<std::uint32_t> visit_;            ///< rank -> triangle index (the tree's order)
};

}  // namespace simreel::sim::detail
