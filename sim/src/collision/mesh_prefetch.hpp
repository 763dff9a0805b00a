#pragma once
// The mesh prefetch of collide()'s Z-order pass (particle_response.cpp): a walker that asks for
// the memory the sweeps of particles further down the list will read. Private.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "collision/collider_impl.hpp"
#include "core/prefetch.hpp"

namespace simreel::sim::detail {

/// Walks `keys` (code << 32 | particle index, the Z-order pass's list) ahead of the sweeps of
/// its particles against the mesh colliders (the first kMeshes), asking for one link of each
/// grid's chain per distance (MeshGrid::prefetch): a particle's position 40 ahead, its cell 24
/// ahead, the cell's blocks 16 ahead and the triangles under it 8 ahead; each link's address
/// comes from the one fetched before. A hint: it changes no result. (The rain benchmark's first
/// second: ~20 % faster on one thread, stop 51.)
class MeshPrefetch {
 public:
  /// x: the particles' positions (3 floats each, world frame); keys and x must outlive the walk.
  MeshPrefetch(const std::vector<Collider>& colliders, const float* x,
               const std::vector<std::uint64_t>& keys)
      : x_(x), keys_(keys), n_(keys.size()) {
    for (const Collider& c : colliders)
      if (c.shape == Collider::Shape::mesh && meshes_ < kMeshes) mesh_[meshes_++] = &c;
    if (meshes_ == 0) return;
    for (std::size_t q = 0; q < std::min(n_, kPosAhead); ++q) prefetch_line(position(q));
    for (std::size_t q = 0; q < std::min(n_, kCellAhead); ++q) locate(q);
  }
  /// Call before the sweep of keys[q], for q = 0, 1, ... in turn.
  void before(std::size_t q) {
    if (meshes_ == 0) return;
    if (q + kPosAhead < n_) prefetch_line(position(q + kPosAhead));
    if (q + kCellAhead < n_) {
      locate(q + kCellAhead);
      ask(q + kCellAhead, 0);
    }
    if (q + kBlockAhead < n_) ask(q + kBlockAhead, 1);
    if (q + kTriAhead < n_) ask(q + kTriAhead, 2);
  }

 private:
  static constexpr std::size_t kPosAhead = 40, kCellAhead = 24, kBlockAhead = 16, kTriAhead = 8;
  static constexpr std::size_t kRing = 32;  // > kCellAhead - kTriAhead: a slot outlives its use
  static constexpr int kMeshes = 4;
  struct Ahead {
    Vec3 p;             // the particle's position, the mesh's frame
    std::int64_t cell;  // MeshGrid::cell_of(p)
  };

  const float* position(std::size_t q) const { return x_ + 3 * (keys_[q] & 0xffffffffu); }
  void locate(std::size_t q) {
    const float* pf = position(q);
    const Vec3 p(pf[0], pf[1], pf[2]);
    for (int m = 0; m < meshes_; ++m) {
      const Collider& c = *mesh_[m];
      Ahead& a = ring_[m][q % kRing];
      a.p = c.unposed ? p : Vec3(c.R.transpose() * (p - c.center));
      a.cell = c.mesh->grid.cell_of(a.p);
    }
  }
  void ask(std::size_t q, int stage) const {
    for (int m = 0; m < meshes_; ++m) {
      const Ahead& a = ring_[m][q % kRing];
      mesh_[m]->mesh->grid.prefetch(a.cell, stage, a.p);
    }
  }

  const float* x_;
  const std::vector<std::uint64_t>& keys_;
  std::size_t n_;
  const Collider* mesh_[kMeshes] = {};
  int meshes_ = 0;
  Ahead ring_[kMeshes][kRing];
};

}  // namespace simreel::sim::detail
