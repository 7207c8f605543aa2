#include "polyheal/mesh/weld.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "polyheal/mesh/hash.h"
#include "polyheal/mesh/union_find.h"

namespace polyheal {

Weld weld_identical_points(const std::vector<Point3d>& points) {
  Weld w;
  w.representative.resize(points.size());
  std::vector<Index> table = empty_table(points.size());  // first point of each value (== on doubles: both zeros weld)
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::size_t slot =
        probe(table, hash_points(&points[i], 1), [&](std::size_t s) { return points[table[s]] == points[i]; });
    if (table[slot] == kEmptySlot) {
      table[slot] = static_cast<Index>(i);
      w.representative[i] = static_cast<Index>(i);
    } else {
      w.representative[i] = table[slot];
      ++w.merged;
    }
  }
  return w;
}

Soup apply_weld(const Soup& soup, const Weld& weld) {
  Soup out = soup;
  for (Index& i : out.indices) i = weld.representative[i];
  return out;
}

std::vector<Index> weld_near_points(const std::vector<Point3d>& pts, const std::vector<Index>& identical, double d,
                             std::size_t& merged, double& max_move) {
  UnionFind uf(pts.size());
  auto cell = [&](double x) { return std::int64_t(std::floor(x / d)); };
  auto key = [](std::int64_t i, std::int64_t j, std::int64_t k) {
    return (std::uint64_t(i & 0x1FFFFF) << 42) | (std::uint64_t(j & 0x1FFFFF) << 21) | std::uint64_t(k & 0x1FFFFF);
  };
  // The grid's occupied cells in a flat table, each the head of a list of
  // its points through `next`: with d far below the point spacing nearly
  // every point has a cell of its own, and a node-based map allocated one
  // list per point (1.2 s of a 1M-face scan's repair).
  std::vector<Index> head = empty_table(pts.size()), next(pts.size(), kEmptySlot);
  std::vector<std::uint64_t> cell_key(head.size());
  auto slot_of = [&](std::uint64_t k) {  // k's slot, or the free one where it would go
    std::uint64_t h = k;  // splitmix64's finalizer: the keys' bits are fields
    h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ull;
    h = (h ^ (h >> 27)) * 0x94D049BB133111EBull;
    return probe(head, h ^ (h >> 31), [&](std::size_t s) { return cell_key[s] == k; });
  };
  for (Index v = 0; v < pts.size(); ++v) {
    if (identical[v] != v) continue;
    const std::int64_t ci = cell(pts[v][0]), cj = cell(pts[v][1]), ck = cell(pts[v][2]);
    for (std::int64_t i = ci - 1; i <= ci + 1; ++i)
      for (std::int64_t j = cj - 1; j <= cj + 1; ++j)
        for (std::int64_t k = ck - 1; k <= ck + 1; ++k)
          for (Index w = head[slot_of(key(i, j, k))]; w != kEmptySlot; w = next[w]) {
            double s = 0;
            for (int c = 0; c < 3; ++c) s += (pts[v][c] - pts[w][c]) * (pts[v][c] - pts[w][c]);
            if (s <= d * d) uf.unite(v, w);
          }
    const std::uint64_t own = key(ci, cj, ck);
    const std::size_t slot = slot_of(own);
    cell_key[slot] = own;
    next[v] = head[slot];
    head[slot] = v;
  }
  std::vector<Index> first(pts.size(), Index(-1)), rep(pts.size());
  for (Index v = 0; v < pts.size(); ++v) {
    const Index root = Index(uf.find(identical[v]));
    if (first[root] == Index(-1)) first[root] = identical[v];
    rep[v] = first[root];
  }
  merged = 0;
  max_move = 0;
  for (Index v = 0; v < pts.size(); ++v) {
    if (identical[v] != v || rep[v] == v) continue;
    ++merged;
    double s = 0;
    for (int c = 0; c < 3; ++c) s += (pts[v][c] - pts[rep[v]][c]) * (pts[v][c] - pts[rep[v]][c]);
    max_move = std::max(max_move, std::sqrt(s));
  }
  return rep;
}


}  // namespace polyheal
