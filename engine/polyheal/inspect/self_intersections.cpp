#include "polyheal/inspect/self_intersections.h"

#include <algorithm>
#include <atomic>

#include <CGAL/box_intersection_d.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "polyheal/inspect/detail/triangle_pair.h"

namespace polyheal {
namespace {

using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::uint32_t, CGAL::Box_intersection_d::ID_EXPLICIT>;
// As in PMP::self_intersections: below this many boxes the segment tree scans
// (much faster than the default 10 on surface meshes).
constexpr std::ptrdiff_t kCutoff = 2000;
using Traits = CGAL::Box_intersection_d::Box_traits_d<const Box*>;
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

InputKernel::Point_3 point(const Soup& s, Index i) {
  const Point3d& p = s.points[i];
  return {p[0], p[1], p[2]};
}

Tri exact_triangle(const Soup& s, const FanTriangle& t, bool degenerate) {
  return Tri{{point(s, t.v[0]), point(s, t.v[1]), point(s, t.v[2])}, {t.v[0], t.v[1], t.v[2]}, degenerate};
}

/// Degeneracy (exact collinearity) of each triangle, decided once, in parallel.
std::vector<char> degenerate_flags(const Soup& s, const std::vector<FanTriangle>& tris, bool parallel) {
  std::vector<char> out(tris.size());
  auto decide = [&](std::size_t i) {
    const FanTriangle& t = tris[i];
    out[i] = CGAL::collinear(point(s, t.v[0]), point(s, t.v[1]), point(s, t.v[2]));
  };
  if (parallel)
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tris.size(), 8192), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) decide(i);
    });
  else
    for (std::size_t i = 0; i < tris.size(); ++i) decide(i);
  return out;
}

/// Runs the broad phase and calls `found(a, b)` for each intersecting pair of
/// fan triangles (from any thread). `stop` ends the search early.
template <class Found>
void scan(const Soup& s, const std::vector<FanTriangle>& tris, const SelfIntersectionOptions& o, Found found,
          const std::atomic<bool>& stop) {
  const std::vector<char> degenerate = degenerate_flags(s, tris, o.parallel);
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
  // The algorithm copies and reorders its input: give it pointers, not boxes.
  std::vector<const Box*> pointers(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) pointers[i] = &boxes[i];
  auto callback = [&](const Box* px, const Box* py) {
    const Box &x = *px, &y = *py;
    if (stop.load(std::memory_order_relaxed)) return;
    const FanTriangle &a = tris[x.info()], &b = tris[y.info()];
    if (a.face == b.face) return;  // two fan triangles of one polygon
    if (detail::faces_intersect<InputKernel>(exact_triangle(s, a, degenerate[x.info()]),
                                             exact_triangle(s, b, degenerate[y.info()])))
      found(a.face, b.face);
  };
  if (o.parallel)
    CGAL::box_self_intersection_d<CGAL::Parallel_if_available_tag>(pointers.begin(), pointers.end(), callback,
                                                                   Traits(), kCutoff);
  else
    CGAL::box_self_intersection_d<CGAL::Sequential_tag>(pointers.begin(), pointers.end(), callback, Traits(),
                                                        kCutoff);
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
