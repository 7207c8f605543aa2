// polyheal — hashing points consistently with their equality, the flat
// open-addressing table the welds and the distance measure look them up in,
// and a flat map from 64-bit keys (no node allocation: node-based maps of a
// million entries were seconds of a big scan's repair). No CGAL here.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>
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

/// A map from 64-bit keys (any but ~0) to values, flat: open addressing,
/// linear probing, a power of two slots kept at least twice the entries,
/// key and value side by side (a lookup is one cache line, where a
/// node-based map chases a bucket and a node: most of the regularizer's
/// growth was that). No erase. Growing moves the values: references
/// returned stay valid only until the next insertion.
template <class V>
class KeyMap {
 public:
  static constexpr std::uint64_t kFree = ~std::uint64_t(0);

  /// The value of `key`, nullptr when absent.
  V* find(std::uint64_t key) {
    if (slots_.empty()) return nullptr;
    Slot& s = slots_[slot_of(key)];
    return s.key == key ? &s.value : nullptr;
  }
  const V* find(std::uint64_t key) const { return const_cast<KeyMap*>(this)->find(key); }
  bool contains(std::uint64_t key) const { return find(key) != nullptr; }

  /// The value of `key`, value-initialised when absent.
  V& operator[](std::uint64_t key) {
    if (2 * (size_ + 1) > slots_.size()) grow();
    Slot& s = slots_[slot_of(key)];
    if (s.key != key) {
      s.key = key;
      ++size_;
    }
    return s.value;
  }

  std::size_t size() const { return size_; }

 private:
  struct Slot {
    std::uint64_t key = kFree;
    V value{};
  };

  /// Where the probe for `key` starts.
  std::size_t home(std::uint64_t key) const {
    const std::uint64_t h = key * 0x9E3779B97F4A7C15ull;  // Fibonacci hashing: the high bits mix every key bit
    return static_cast<std::size_t>(h >> 32 ^ h) & (slots_.size() - 1);
  }

  /// The slot holding `key`, or the free slot where it would go.
  std::size_t slot_of(std::uint64_t key) const {
    const std::size_t mask = slots_.size() - 1;
    std::size_t i = home(key);
    while (slots_[i].key != key && slots_[i].key != kFree) i = (i + 1) & mask;
    return i;
  }

  void grow() {
    std::vector<Slot> old(std::max<std::size_t>(16, 2 * slots_.size()));
    old.swap(slots_);
    for (Slot& s : old)
      if (s.key != kFree) {
        Slot& t = slots_[slot_of(s.key)];
        t.key = s.key;
        t.value = std::move(s.value);
      }
  }

  std::vector<Slot> slots_;
  std::size_t size_ = 0;
};

}  // namespace polyheal
