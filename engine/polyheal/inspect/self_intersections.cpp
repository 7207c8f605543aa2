#include "polyheal/inspect/self_intersections.h"

#include <algorithm>
#include <atomic>

#include <CGAL/box_intersection_d.h>
#include <tbb/enumerable_thread_specific.h>

#include "polyheal/inspect/detail/triangle_pair.h"

namespace polyheal {
namespace {

using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::uint32_t, CGAL::Box_intersection_d::ID_EXPLICIT>;
using Tri = detail::Tri<InputKernel>;

/// A triangle of the (fan-triangulated) soup and the face it came from.
struct FanTriangle {
  Index v[3];
  std::uint32_t face;
};

std::vector<FanTriangle> fan_triangles(const Soup& s) {
  std::vector<FanTriangle> t;
  t.reserve(s.indices.size() - 2 * s.face_count());
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    FaceView v = s.face(f);
    for (std::size_t k = 1; k + 1 < v.size(); ++k) t.push_back({{v[0], v[k], v[k + 1]}, static_cast<std::uint32_t>(f)});
  }
  return t;
}

Tri make_tri(const Soup& s, const FanTriangle& t) {
  Tri r;
  for (int k = 0; k < 3; ++k) {
    const Point3d& p = s.points[t.v[k]];
    r.p[k] = InputKernel::Point_3(p[0], p[1], p[2]);
    r.id[k] = t.v[k];
  }
  return r;
}

/// Runs the broad phase and calls `found(a, b)` for each intersecting pair of
/// fan triangles (from any thread). `stop` ends the search early.
template <class Found>
void scan(const Soup& s, const std::vector<FanTriangle>& tris, const SelfIntersectionOptions& o, Found found,
          const std::atomic<bool>& stop) {
  std::vector<Box> boxes;
  boxes.reserve(tris.size());
  for (std::size_t i = 0; i < tris.size(); ++i) {
    CGAL::Bbox_3 b;
    for (Index v : tris[i].v) {
      const Point3d& p = s.points[v];
      b += CGAL::Bbox_3(p[0], p[1], p[2], p[0], p[1], p[2]);
    }
    boxes.emplace_back(b, static_cast<std::uint32_t>(i));
  }
  if (o.observer) o.observer->stage("self-intersections");
  auto callback = [&](const Box& x, const Box& y) {
    if (stop.load(std::memory_order_relaxed)) return;
    const FanTriangle &a = tris[x.info()], &b = tris[y.info()];
    if (a.face == b.face) return;  // two fan triangles of one polygon
    if (detail::faces_intersect<InputKernel>(make_tri(s, a), make_tri(s, b))) found(a.face, b.face);
  };
  if (o.parallel)
    CGAL::box_self_intersection_d<CGAL::Parallel_if_available_tag>(boxes.begin(), boxes.end(), callback);
  else
    CGAL::box_self_intersection_d<CGAL::Sequential_tag>(boxes.begin(), boxes.end(), callback);
}

}  // namespace

std::vector<FacePair> find_self_intersections(const Soup& soup, const SelfIntersectionOptions& options) {
  const std::vector<FanTriangle> tris = fan_triangles(soup);
  tbb::enumerable_thread_specific<std::vector<FacePair>> local;
  std::atomic<bool> stop{false};
  scan(soup, tris, options,
       [&](std::size_t f, std::size_t g) { local.local().push_back({std::min(f, g), std::max(f, g)}); }, stop);
  std::vector<FacePair> pairs;
  for (auto& v : local) pairs.insert(pairs.end(), v.begin(), v.end());
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());  // polygons: several fan pairs
  return pairs;
}

bool does_self_intersect(const Soup& soup, const SelfIntersectionOptions& options) {
  const std::vector<FanTriangle> tris = fan_triangles(soup);
  std::atomic<bool> stop{false};
  scan(soup, tris, options, [&](std::size_t, std::size_t) { stop = true; }, stop);
  return stop.load();
}

}  // namespace polyheal
