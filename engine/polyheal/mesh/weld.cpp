#include "polyheal/mesh/weld.h"

#include <cstring>
#include <unordered_map>

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
  std::unordered_map<PointKey, Index, PointKeyHash> first;
  first.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    auto [it, inserted] = first.emplace(key_of(points[i]), static_cast<Index>(i));
    w.representative[i] = it->second;
    if (!inserted) ++w.merged;
  }
  return w;
}

Soup apply_weld(const Soup& soup, const Weld& weld) {
  Soup out = soup;
  for (Index& i : out.indices) i = weld.representative[i];
  return out;
}

}  // namespace polyheal
