// polyheal — hashing points consistently with their equality, and the flat
// open-addressing table the welds and the distance measure look them up in
// (no node allocation: node-based maps of a million entries were seconds of
// a big scan's repair). No CGAL here.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "polyheal/mesh/soup.h"

namespace polyheal {

/// Mixes the coordinates of points p[0..n) into h, consistently with == on
/// doubles: -0.0 and 0.0 hash alike (readers reject NaN).
inline std::uint64_t hash_points(const Point3d* p, std::size_t n, std::uint64_t h = 0x9E3779B97F4A7C15ull) {
  for (std::size_t i = 0; i < n; ++i)
    for (double x : p[i]) {
      const double v = x + 0.0;  // -0.0 + 0.0 == +0.0
      std::uint64_t b;
      std::memcpy(&b, &v, sizeof b);
      h = (h ^ b) * 0xBF58476D1CE4E5B9ull;
      h ^= h >> 31;
    }
  return h;
}

/// A triangle's corners in a canonical order (sorted), the key of "the same
/// triangle" whatever its rotation or orientation (with hash_points).
inline std::array<Point3d, 3> sorted_corners(const Point3d& a, const Point3d& b, const Point3d& c) {
  std::array<Point3d, 3> t{a, b, c};
  std::sort(t.begin(), t.end());
  return t;
}

inline constexpr Index kEmptySlot = ~Index(0);

/// A flat table of a power of two slots, at least twice `n`, kEmptySlot
/// where free; its entries are indices of the caller's items.
inline std::vector<Index> empty_table(std::size_t n) {
  std::size_t capacity = 16;
  while (capacity < 2 * n) capacity *= 2;
  return std::vector<Index>(capacity, kEmptySlot);
}

/// Linear probing: the slot, from `hash` on, whose entry `holds(slot)` says
/// is the one sought, or the free slot where it would go.
template <class Holds>
std::size_t probe(const std::vector<Index>& table, std::uint64_t hash, Holds holds) {
  const std::size_t mask = table.size() - 1;
  std::size_t slot = static_cast<std::size_t>(hash) & mask;
  while (table[slot] != kEmptySlot && !holds(slot)) slot = (slot + 1) & mask;
  return slot;
}

}  // namespace polyheal
