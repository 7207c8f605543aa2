// polyheal — disjoint sets (union-find with path halving): components of
// faces, corners or vertices wherever a mesh is grouped. No CGAL here.
#pragma once

#include <algorithm>
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

}  // namespace polyheal
