// polyheal — disjoint sets (union-find with path halving): components of
// faces, corners or vertices wherever a mesh is grouped. No CGAL here.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstddef>
#include <numeric>
#include <vector>

namespace polyheal {

struct UnionFind {
  std::vector<std::size_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), std::size_t(0)); }
  /// The representative of x's set (the smallest element of it).
  std::size_t find(std::size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::size_t a, std::size_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

/// Disjoint sets that threads may join at once (lock-free): a root is
/// linked to the lesser root by compare-and-swap, retried when another
/// thread linked it first; finds halve paths as they go (each write points
/// a node at one of its ancestors, whatever else changed meanwhile). As in
/// UnionFind, a set's representative is its smallest element, once every
/// unite() has returned.
struct ConcurrentUnionFind {
  std::vector<std::atomic<std::uint32_t>> parent;
  explicit ConcurrentUnionFind(std::size_t n) : parent(n) {
    for (std::size_t i = 0; i < n; ++i) parent[i].store(std::uint32_t(i), std::memory_order_relaxed);
  }
  std::uint32_t find(std::uint32_t x) {
    for (;;) {
      std::uint32_t p = parent[x].load(std::memory_order_relaxed);
      if (p == x) return x;
      const std::uint32_t g = parent[p].load(std::memory_order_relaxed);
      if (g != p) parent[x].compare_exchange_weak(p, g, std::memory_order_relaxed);
      x = g;
    }
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    for (;;) {
      a = find(a);
      b = find(b);
      if (a == b) return;
      if (a < b) std::swap(a, b);
      std::uint32_t expected = a;  // a still a root: link it under the lesser b
      if (parent[a].compare_exchange_strong(expected, b)) return;
    }
  }
};

}  // namespace polyheal
