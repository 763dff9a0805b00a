// Uniform grid over a mesh's triangles (Coutinho §2.3.1), built by a counting sort of
// (cell, rank) entries.
#include "collision/mesh_grid.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <utility>

namespace simreel::sim::detail {

namespace {
/// A convex polygon of at most 9 corners (a triangle clipped by four lines has at most seven).
struct Polygon {
  Vec3 p[9];
  int n = 0;
};

/// out = the part of polygon a on the inner side of coordinate `axis` = bound (sign 1: above,
/// -1: below), by Sutherland–Hodgman: the other coordinates interpolated along the edges (exact
/// up to rounding, as they are linear over a triangle's plane).
void clip_side(const Polygon& a, int axis, double bound, double sign, Polygon& out) {
  out.n = 0;
  for (int k = 0; k < a.n; ++k) {
    const Vec3& p = a.p[k];
    const Vec3& q = a.p[k + 1 < a.n ? k + 1 : 0];
    const double dp = sign * (p[axis] - bound), dq = sign * (q[axis] - bound);  // >= 0: inside
    if (dp >= 0.0) out.p[out.n++] = p;
    if ((dp >= 0.0) != (dq >= 0.0)) out.p[out.n++] = p + (dp / (dp - dq)) * (q - p);
  }
}

/// out = the part of polygon a with lo <= coordinate `axis` <= hi (m; either may be infinite);
/// tmp: scratch.
void clip_slab(const Polygon& a, int axis, double lo, double hi, Polygon& tmp, Polygon& out) {
  const Polygon* from = &a;
  if (!std::isinf(lo)) {
    clip_side(a, axis, lo, 1.0, tmp);
    from = &tmp;
  }
  if (!std::isinf(hi)) {
    clip_side(*from, axis, hi, -1.0, out);
    return;
  }
  out.n = from->n;
  for (int k = 0; k < out.n; ++k) out.p[k] = from->p[k];
}
}  // namespace

MeshGrid::MeshGrid(const std::vector<Triangle>& tris, const std::vector<std::uint32_t>& visit) {
  const std::size_t n = tris.size();
  if (n == 0 || visit.size() != n) return;
  std::vector<double> box(6 * n);  // by rank: lo x, y, z, hi x, y, z
  Aabb all;
  double extent = 0.0;  // mean of the triangles' largest box side
  for (std::size_t r = 0; r < n; ++r) {
    const Aabb b = triangle_box(tris[visit[r]]);
    all.grow(b);
    for (int k = 0; k < 3; ++k) {
      box[6 * r + std::size_t(k)] = b.lo[k];
      box[6 * r + 3 + std::size_t(k)] = b.hi[k];
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
  cell_size_ = cell;
  for (int k = 0; k < 3; ++k) {
    dim_[k] = std::int64_t(std::floor(size[k] * inv_cell_)) + 1;
    last_[k] = double(dim_[k] - 1);
  }
  fill_cells(box, 0.0, cell_, blocks_);
  // The halo lists (see query()), within their budget. The triangles' boxes grow by the halo
  // and a little more (far more than the rounding of the cell arithmetic here and in query(),
  // and of the boxes to floats), so every triangle whose box overlaps a query box that lies
  // within a cell's halo is on that cell's list.
  const double halo = kHaloCells * cell;
  const double grow = halo + 1e-6 * cell + 1e-6 * (lo_.cwiseAbs().maxCoeff() + hi_.cwiseAbs().maxCoeff());
  const std::size_t halo_entries = entries(box, grow);
  if (halo_entries <= kHaloBudget * entries(box, 0.0) && halo_entries <= kHaloMaxEntries) {
    fill_cells(box, grow, halo_cell_, halo_blocks_);
    halo_ = halo;
  }
  // The columns' z extents: over each column its box spans, the part of each triangle that lies
  // over the column (the triangle clipped to the column's rectangle, widened by far more than
  // the rounding of the column arithmetic, so that every point of the triangle whose column indices
  // are the column's lies in it; the first and last columns reach to infinity, as the clamped
  // indices do), its lowest and highest z; rounded outward to floats and one ulp further, then
  // to levels, one more level outward (the rounding of the clip and the level arithmetic is far
  // below a level and an ulp). A triangle's box would give the z extent of the whole triangle:
  // on a bumpy terrain several times the height that the surface spans over one column, and
  // each drop in that slab is swept against the triangles for nothing.
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const double column = cell / kColumnsPerCell;
  inv_column_ = 1.0 / column;
  for (int k = 0; k < 2; ++k) {
    column_dim_[k] = std::int64_t(std::floor(size[k] * inv_column_)) + 1;
    column_last_[k] = double(column_dim_[k] - 1);
  }
  const std::size_t columns = std::size_t(column_dim_[0] * column_dim_[1]);
  std::vector<float> zcol(2 * columns);
  for (std::size_t col = 0; col < columns; ++col) {
    zcol[2 * col] = kInf;
    zcol[2 * col + 1] = -kInf;
  }
  const double widen =
      1e-7 * column + 1e-12 * (lo_.cwiseAbs().maxCoeff() + hi_.cwiseAbs().maxCoeff());
  const auto edge = [&](int k, std::int64_t c) {  // (m) where column c's span on axis k begins
    return c <= 0 ? -std::numeric_limits<double>::infinity() : lo_[k] + double(c) * column - widen;
  };
  const auto edge_end = [&](int k, std::int64_t c) {
    return c >= column_dim_[k] - 1 ? std::numeric_limits<double>::infinity()
                                   : lo_[k] + double(c + 1) * column + widen;
  };
  for (std::size_t r = 0; r < n; ++r) {
    const Triangle& t = tris[visit[r]];
    std::int64_t c0[2], c1[2];
    for (int k = 0; k < 2; ++k) {
      const double a = (box[6 * r + std::size_t(k)] - lo_[k]) * inv_column_;
      const double b = (box[6 * r + 3 + std::size_t(k)] - lo_[k]) * inv_column_;
      c0[k] = std::clamp(std::int64_t(a), std::int64_t(0), column_dim_[k] - 1);
      c1[k] = std::clamp(std::int64_t(b), std::int64_t(0), column_dim_[k] - 1);
    }
    Polygon tri;
    tri.p[0] = t.a;
    tri.p[1] = t.b;
    tri.p[2] = t.c;
    tri.n = 3;
    Polygon row, part, tmp;
    for (std::int64_t y = c0[1]; y <= c1[1]; ++y) {
      clip_slab(tri, 1, edge(1, y), edge_end(1, y), tmp, row);
      for (std::int64_t x = c0[0]; x <= c1[0] && row.n > 0; ++x) {
        // The part over column (x, y); none where only the triangle's box spans it.
        clip_slab(row, 0, edge(0, x), edge_end(0, x), tmp, part);
        if (part.n == 0) continue;
        double lo_z = part.p[0].z(), hi_z = lo_z;  // (z is linear: its extremes are corners)
        for (int k = 1; k < part.n; ++k) {
          lo_z = std::min(lo_z, part.p[k].z());
          hi_z = std::max(hi_z, part.p[k].z());
        }
        float zlo = float(lo_z), zhi = float(hi_z);
        if (double(zlo) > lo_z) zlo = std::nextafter(zlo, -kInf);
        if (double(zhi) < hi_z) zhi = std::nextafter(zhi, kInf);
        zlo = std::nextafter(zlo, -kInf);
        zhi = std::nextafter(zhi, kInf);
        const std::size_t col = std::size_t(y * column_dim_[0] + x);
        zcol[2 * col] = std::min(zcol[2 * col], zlo);
        zcol[2 * col + 1] = std::max(zcol[2 * col + 1], zhi);
      }
    }
  }
  const double z0 = lo_[2], step = std::max(hi_[2] - lo_[2], 1e-9) / 254.0;
  level_[0] = -std::numeric_limits<double>::infinity();
  level_[255] = std::numeric_limits<double>::infinity();
  for (int q = 1; q < 255; ++q) level_[q] = z0 + q * step;
  level_z0_ = z0;
  level_step_ = step;
  static std::atomic<std::uint64_t> built{0};
  serial_ = ++built;
  // Two bytes past the last column: a 32-bit gather at a column's two bytes (ColumnTable) may
  // read them.
  column_.assign(2 * columns + 2, 0);
  for (std::size_t col = 0; col < columns; ++col) {
    if (!(zcol[2 * col] <= zcol[2 * col + 1])) {  // no triangle over it
      column_[2 * col] = 255;
      column_[2 * col + 1] = 0;
      continue;
    }
    const double lo = std::floor((double(zcol[2 * col]) - z0) / step) - 1.0;
    const double hi = std::ceil((double(zcol[2 * col + 1]) - z0) / step) + 1.0;
    column_[2 * col] = std::uint8_t(std::clamp(lo, 0.0, 253.0));
    column_[2 * col + 1] = std::uint8_t(std::clamp(hi, 1.0, 255.0));
  }
  visit_ = visit;
  tris_.reserve(n);
  for (std::size_t r = 0; r < n; ++r) tris_.emplace_back(tris[visit[r]]);
}

void MeshGrid::cell_range(const std::vector<double>& box, double grow, std::size_t r, int k,
                          std::int64_t& c0, std::int64_t& c1) const {
  const double a = (box[6 * r + std::size_t(k)] - grow - lo_[k]) * inv_cell_;
  const double b = (box[6 * r + 3 + std::size_t(k)] + grow - lo_[k]) * inv_cell_;
  c0 = std::clamp(std::int64_t(std::floor(a)), std::int64_t(0), dim_[k] - 1);
  c1 = std::clamp(std::int64_t(std::floor(b)), std::int64_t(0), dim_[k] - 1);
}

std::size_t MeshGrid::entries(const std::vector<double>& box, double grow) const {
  std::size_t total = 0;
  for (std::size_t r = 0; r < box.size() / 6; ++r) {
    std::size_t cells = 1;
    for (int k = 0; k < 3; ++k) {
      std::int64_t c0, c1;
      cell_range(box, grow, r, k, c0, c1);
      cells *= std::size_t(c1 - c0 + 1);
    }
    total += cells;
  }
  return total;
}

void MeshGrid::fill_cells(const std::vector<double>& box, double grow, std::vector<Cell>& cell_of,
                          std::vector<Block>& blocks) const {
  const std::size_t n = box.size() / 6;
  const std::size_t cells = std::size_t(dim_[0] * dim_[1] * dim_[2]);
  // Two passes of a counting sort: counts per cell, then ranks in increasing order per cell.
  // The cells' runs lie in Z-order (Morton) of the cells, not in row order: particles are
  // resolved in Z-order of where they are (particle_response.cpp), so the runs they read next
  // lie next in memory.
  std::vector<std::uint32_t> count(cells, 0);
  const auto each_cell = [&](std::size_t r, auto&& g) {
    std::int64_t c0[3], c1[3];
    for (int k = 0; k < 3; ++k) cell_range(box, grow, r, k, c0[k], c1[k]);
    for (std::int64_t z = c0[2]; z <= c1[2]; ++z)
      for (std::int64_t y = c0[1]; y <= c1[1]; ++y)
        for (std::int64_t x = c0[0]; x <= c1[0]; ++x)
          g(std::size_t((z * dim_[1] + y) * dim_[0] + x));
  };
  for (std::size_t r = 0; r < n; ++r) each_cell(r, [&](std::size_t c) { ++count[c]; });
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order;  // (Morton code, cell)
  for (std::int64_t z = 0; z < dim_[2]; ++z)
    for (std::int64_t y = 0; y < dim_[1]; ++y)
      for (std::int64_t x = 0; x < dim_[0]; ++x) {
        const std::size_t c = std::size_t((z * dim_[1] + y) * dim_[0] + x);
        if (count[c] == 0) continue;
        std::uint64_t code = 0;
        for (int bit = 0; bit < 21; ++bit)
          code |= ((std::uint64_t(x) >> bit & 1) << (3 * bit)) |
                  ((std::uint64_t(y) >> bit & 1) << (3 * bit + 1)) |
                  ((std::uint64_t(z) >> bit & 1) << (3 * bit + 2));
        order.emplace_back(code, std::uint32_t(c));
      }
  std::sort(order.begin(), order.end());
  cell_of.assign(cells, Cell{0, 0});
  std::uint32_t next = 0;
  for (const auto& [code, c] : order) {
    cell_of[c].begin = next;
    next += (count[c] + kLanes - 1) / kLanes;
    cell_of[c].end = next;
  }
  Block empty;
  for (int l = 0; l < kLanes; ++l) {
    for (int k = 0; k < 3; ++k) {
      empty.lo[k][l] = std::numeric_limits<float>::infinity();
      empty.hi[k][l] = -std::numeric_limits<float>::infinity();
    }
    empty.rank[l] = 0;
  }
  blocks.assign(next, empty);
  std::fill(count.begin(), count.end(), 0u);  // now: entries placed per cell
  for (std::size_t r = 0; r < n; ++r)
    each_cell(r, [&](std::size_t c) {
      Block& b = blocks[cell_of[c].begin + count[c] / kLanes];
      const std::uint32_t l = count[c]++ % kLanes;
      for (int k = 0; k < 3; ++k) {
        b.lo[k][l] = float(box[6 * r + std::size_t(k)]);
        b.hi[k][l] = float(box[6 * r + 3 + std::size_t(k)]);
      }
      b.rank[l] = std::uint32_t(r);
    });
}

}  // namespace simreel::sim::detail
