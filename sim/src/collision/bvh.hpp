#pragma once
// AABB tree over the triangles of a mesh collider, built once in the mesh's local frame at
// registration (Coutinho §2.2: bounding-volume hierarchies; §2.1: queries move into the body's
// frame instead of moving the body). Private.

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "simreel/sim/types.hpp"

namespace simreel::sim::detail {

/// One triangle in the mesh frame, with its unit face normal (right-hand order a, b, c).
struct Triangle {
  Vec3 a, b, c;
  Vec3 normal;
};

/// Axis-aligned box [lo, hi].
struct Aabb {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = Vec3::Constant(-std::numeric_limits<double>::infinity());
  void grow(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void grow(const Aabb& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  [[nodiscard]] bool overlaps(const Vec3& qlo, const Vec3& qhi) const {
    return (lo.array() <= qhi.array()).all() && (hi.array() >= qlo.array()).all();
  }
};

/// The box of a triangle's three corners.
inline Aabb triangle_box(const Triangle& t) {
  Aabb b;
  b.grow(t.a);
  b.grow(t.b);
  b.grow(t.c);
  return b;
}

/// Binary AABB tree: nodes in depth-first order, each leaf holding up to kLeafSize consecutive
/// entries of `order` (triangle indices). Split at the median of the longest axis of the
/// centroid bounds, so the depth is O(log n) whatever the mesh.
class Bvh {
 public:
  static constexpr int kLeafSize = 4;
  Bvh() = default;
  explicit Bvh(const std::vector<Triangle>& tris);

  /// Calls f(triangle index) for every triangle whose leaf box overlaps [lo, hi] (a superset of
  /// the triangles whose own box overlaps; the caller runs the exact test). Visiting order is
  /// fixed (depth first, left before right), so results are deterministic.
  template <class F>
  void query(const Vec3& lo, const Vec3& hi, F&& f) const {
    if (nodes_.empty()) return;
    std::uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (!n.box.overlaps(lo, hi)) continue;
      if (n.count > 0) {
        for (std::uint32_t k = 0; k < n.count; ++k) f(order_[n.first + k]);
      } else {
        stack[top++] = n.right;
        stack[top++] = n.first;  // left child: visited first
      }
    }
  }
  /// Calls f(triangle index) for every triangle whose leaf box, grown by `pad` on every side,
  /// the segment {p + t dir : 0 <= t <= len} meets (slab test, Kay & Kajiya 1986; a superset of
  /// the triangles the segment crosses, as long as `pad` covers the rounding of the caller's
  /// exact test). Unlike query() over the segment's box, a long oblique segment visits only the
  /// leaves along it, not every leaf in the box it spans. `dir` need not be unit; a zero
  /// component tests that axis as a point. Fixed visiting order (depth first, left first).
  template <class F>
  void ray_query(const Vec3& p, const Vec3& dir, double len, double pad, F&& f) const {
    if (nodes_.empty()) return;
    Vec3 inv;
    for (int k = 0; k < 3; ++k) inv[k] = dir[k] != 0.0 ? 1.0 / dir[k] : 0.0;
    const auto crosses = [&](const Aabb& b) {
      double t0 = 0.0, t1 = len;
      for (int k = 0; k < 3; ++k) {
        const double lo = b.lo[k] - pad, hi = b.hi[k] + pad;
        if (dir[k] == 0.0) {
          if (p[k] < lo || p[k] > hi) return false;
          continue;
        }
        double a = (lo - p[k]) * inv[k], c = (hi - p[k]) * inv[k];
        if (a > c) std::swap(a, c);
        t0 = std::max(t0, a);
        t1 = std::min(t1, c);
        if (t0 > t1) return false;
      }
      return true;
    };
    std::uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (!crosses(n.box)) continue;
      if (n.count > 0) {
        for (std::uint32_t k = 0; k < n.count; ++k) f(order_[n.first + k]);
      } else {
        stack[top++] = n.right;
        stack[top++] = n.first;
      }
    }
  }
  /// Calls f(i, j) once for every unordered pair of distinct triangles i, j whose leaves' boxes
  /// overlap (a superset of the pairs whose own boxes overlap; the caller runs the exact test):
  /// the tree against itself, O(n + pairs) instead of a query per triangle. Fixed order.
  template <class F>
  void self_pairs(F&& f) const {
    if (!nodes_.empty()) self_pairs_within(0, f);
  }
  /// Recomputes every node's box from `tris` (the same count and order as at construction),
  /// keeping the tree's structure: O(n), for boxes that moved a little since the build. The
  /// tree is then as valid as a new one (queries find the same triangles) but may be looser.
  void refit(const std::vector<Triangle>& tris);
  /// Triangles the tree was built over.
  [[nodiscard]] std::size_t size() const { return order_.size(); }
  /// Triangle indices in the order query() visits them (leaf by leaf, depth first).
  [[nodiscard]] const std::vector<std::uint32_t>& visit_order() const { return order_; }
  [[nodiscard]] const Aabb& bounds() const { return nodes_.front().box; }
  [[nodiscard]] std::size_t node_count() const { return nodes_.size(); }
  [[nodiscard]] int depth() const { return depth_; }

 private:
  struct Node {
    Aabb box;
    std::uint32_t first = 0;  ///< leaf: first entry in order_; inner: left child index
    std::uint32_t right = 0;  ///< inner: right child index
    std::uint32_t count = 0;  ///< leaf: entries; inner: 0
  };
  template <class F>
  void self_pairs_within(std::uint32_t a, F& f) const {
    const Node& n = nodes_[a];
    if (n.count > 0) {
      for (std::uint32_t i = 0; i < n.count; ++i)
        for (std::uint32_t j = i + 1; j < n.count; ++j) f(order_[n.first + i], order_[n.first + j]);
      return;
    }
    self_pairs_within(n.first, f);
    self_pairs_within(n.right, f);
    self_pairs_across(n.first, n.right, f);
  }
  template <class F>
  void self_pairs_across(std::uint32_t a, std::uint32_t b, F& f) const {
    const Node& A = nodes_[a];
    const Node& B = nodes_[b];
    if (!A.box.overlaps(B.box.lo, B.box.hi)) return;
    if (A.count > 0 && B.count > 0) {
      for (std::uint32_t i = 0; i < A.count; ++i)
        for (std::uint32_t j = 0; j < B.count; ++j) f(order_[A.first + i], order_[B.first + j]);
      return;
    }
    // Split the bigger inner node: the pairs' recursion then stays near the tree's depth.
    const bool split_a =
        B.count > 0 || (A.count == 0 && (A.box.hi - A.box.lo).sum() >= (B.box.hi - B.box.lo).sum());
    if (split_a) {
      self_pairs_across(A.first, b, f);
      self_pairs_across(A.right, b, f);
    } else {
      self_pairs_across(a, B.first, f);
      self_pairs_across(a, B.right, f);
    }
  }
  std::uint32_t build(std::vector<Aabb>& boxes, std::vector<Vec3>& centroids, std::uint32_t begin,
                      std::uint32_t end, int depth);
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> order_;
  int depth_ = 0;
};

}  // namespace simreel::sim::detail
