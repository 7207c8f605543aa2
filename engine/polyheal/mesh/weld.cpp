#include "polyheal/mesh/weld.h"

#include <cstring>

namespace polyheal {
namespace {

struct PointKey {
  std::uint64_t b[3];
  bool operator==(const PointKey& o) const { return b[0] == o.b[0] && b[1] == o.b[1] && b[2] == o.b[2]; }
};
struct PointKeyHash {
  std::size_t operator()(const PointKey& k) const {
    std::uint64_t h = 0x9E3779B97F4A7C15ull;
    for (std::uint64_t v : k.b) {
      h ^= v + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
      h *= 0xBF58476D1CE4E5B9ull;
    }
    return static_cast<std::size_t>(h ^ (h >> 31));
  }
};

PointKey key_of(const Point3d& p) {
  PointKey k;
  for (int i = 0; i < 3; ++i) {
    double v = p[i] + 0.0;  // -0.0 + 0.0 == +0.0: both zeros weld
    std::memcpy(&k.b[i], &v, sizeof v);
  }
  return k;
}

}  // namespace

Weld weld_identical_points(const std::vector<Point3d>& points) {
  Weld w;
  w.representative.resize(points.size());
  // Open addressing (linear probing) over point indices: a flat table twice
  // the point count, no node allocation.
  std::size_t capacity = 16;
  while (capacity < 2 * points.size()) capacity *= 2;
  const std::size_t mask = capacity - 1;
  constexpr Index kEmpty = ~Index(0);
  std::vector<Index> table(capacity, kEmpty);
  std::vector<PointKey> keys(points.size());
  const PointKeyHash hash;
  for (std::size_t i = 0; i < points.size(); ++i) {
    keys[i] = key_of(points[i]);
    std::size_t slot = hash(keys[i]) & mask;
    for (;;) {
      const Index j = table[slot];
      if (j == kEmpty) {
        table[slot] = static_cast<Index>(i);
        w.representative[i] = static_cast<Index>(i);
        break;
      }
      if (keys[j] == keys[i]) {
        w.representative[i] = j;
        ++w.merged;
        break;
      }
      slot = (slot + 1) & mask;
    }
  }
  return w;
}

Soup apply_weld(const Soup& soup, const Weld& weld) {
  Soup out = soup;
  for (Index& i : out.indices) i = weld.representative[i];
  return out;
}

}  // namespace polyheal
