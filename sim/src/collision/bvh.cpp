// AABB tree construction (Coutinho §2.2), median split on the longest centroid axis.
#include "collision/bvh.hpp"

#include <algorithm>
#include <numeric>

namespace simreel::sim::detail {

Bvh::Bvh(const std::vector<Triangle>& tris) {
  const auto n = std::uint32_t(tris.size());
  if (n == 0) return;
  std::vector<Aabb> boxes(n);
  std::vector<Vec3> centroids(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    boxes[i] = triangle_box(tris[i]);
    centroids[i] = (tris[i].a + tris[i].b + tris[i].c) / 3.0;
  }
  order_.resize(n);
  std::iota(order_.begin(), order_.end(), 0u);
  nodes_.reserve(2 * std::size_t(n) / kLeafSize + 2);
  build(boxes, centroids, 0, n, 1);
}

void Bvh::refit(const std::vector<Triangle>& tris) {
  // Nodes are in depth-first order, children after their parent: backwards, children first.
  for (std::size_t k = nodes_.size(); k-- > 0;) {
    Node& n = nodes_[k];
    Aabb box;
    if (n.count > 0) {
      for (std::uint32_t i = n.first; i < n.first + n.count; ++i) box.grow(triangle_box(tris[order_[i]]));
    } else {
      box = nodes_[n.first].box;
      box.grow(nodes_[n.right].box);
    }
    n.box = box;
  }
}

std::uint32_t Bvh::build(std::vector<Aabb>& boxes, std::vector<Vec3>& centroids,
                         std::uint32_t begin, std::uint32_t end, int depth) {
  depth_ = std::max(depth_, depth);
  const auto index = std::uint32_t(nodes_.size());
  nodes_.emplace_back();
  Aabb box, cbox;
  for (std::uint32_t i = begin; i < end; ++i) {
    box.grow(boxes[order_[i]]);
    cbox.grow(centroids[order_[i]]);
  }
  nodes_[index].box = box;
  if (end - begin <= std::uint32_t(kLeafSize)) {
    nodes_[index].first = begin;
    nodes_[index].count = end - begin;
    return index;
  }
  int axis = 0;
  (cbox.hi - cbox.lo).maxCoeff(&axis);
  const std::uint32_t mid = begin + (end - begin) / 2;
  // Ties broken by index so the tree does not depend on the sort implementation.
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](std::uint32_t x, std::uint32_t y) {
                     const double cx = centroids[x][axis], cy = centroids[y][axis];
                     return cx < cy || (cx == cy && x < y);
                   });
  const std::uint32_t left = build(boxes, centroids, begin, mid, depth + 1);
  const std::uint32_t right = build(boxes, centroids, mid, end, depth + 1);
  nodes_[index].first = left;
  nodes_[index].right = right;
  nodes_[index].count = 0;
  return index;
}

}  // namespace simreel::sim::detail
