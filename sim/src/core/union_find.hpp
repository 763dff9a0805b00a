#pragma once
// Union–find over rigid entries (private to core/): islands of sleeping bodies (sleep.cpp) and
// articulations touching something (stage_bodies.cpp). The smaller index is always the root, so
// the result does not depend on the order the links are visited in (deterministic island ids).

#include <cstdint>
#include <utility>
#include <vector>

namespace simreel::sim::detail {

inline std::uint32_t uf_find(std::vector<std::uint32_t>& parent, std::uint32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];  // path halving
    i = parent[i];
  }
  return i;
}

inline void uf_unite(std::vector<std::uint32_t>& parent, std::uint32_t a, std::uint32_t b) {
  a = uf_find(parent, a);
  b = uf_find(parent, b);
  if (a == b) return;
  if (b < a) std::swap(a, b);
  parent[b] = a;
}

}  // namespace simreel::sim::detail
