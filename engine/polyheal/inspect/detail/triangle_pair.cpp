#include "polyheal/inspect/detail/triangle_pair.h"

#include <variant>

#include <CGAL/intersections.h>

namespace polyheal::detail {
namespace {

/// What a (possibly degenerate) triangle is geometrically.
template <class K>
using Primitive = std::variant<typename K::Point_3, typename K::Segment_3, typename K::Triangle_3>;

template <class K>
Primitive<K> primitive(const Tri<K>& t) {
  const auto &a = t.p[0], &b = t.p[1], &c = t.p[2];
  if (!CGAL::collinear(a, b, c)) return typename K::Triangle_3(a, b, c);
  if (a == b && b == c) return a;
  // Collinear: the segment between the two extreme points.
  if (CGAL::collinear_are_ordered_along_line(a, b, c)) return typename K::Segment_3(a, c);
  if (CGAL::collinear_are_ordered_along_line(b, a, c)) return typename K::Segment_3(b, c);
  return typename K::Segment_3(a, b);
}

template <class K>
bool primitives_intersect(const Primitive<K>& x, const Primitive<K>& y) {
  return std::visit(
      [](const auto& u, const auto& v) -> bool {
        using U = std::decay_t<decltype(u)>;
        using V = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<U, typename K::Point_3> && std::is_same_v<V, typename K::Point_3>)
          return u == v;
        else
          return CGAL::do_intersect(u, v);
      },
      x, y);
}

/// Segment pq against non-degenerate triangle t. Most pairs of neighbours
/// are rejected by the first two tests: disjoint boxes, or p and q strictly
/// on one side of t's plane.
template <class K>
bool edge_meets_triangle(const typename K::Point_3& p, const typename K::Point_3& q, const Tri<K>& t) {
  // Bounding boxes first: exact for double points, conservative for Epeck's.
  if (!CGAL::do_overlap(p.bbox() + q.bbox(), t.p[0].bbox() + t.p[1].bbox() + t.p[2].bbox())) return false;
  const CGAL::Orientation op = CGAL::orientation(t.p[0], t.p[1], t.p[2], p);
  if (op != CGAL::COPLANAR && op == CGAL::orientation(t.p[0], t.p[1], t.p[2], q)) return false;
  return CGAL::do_intersect(typename K::Segment_3(p, q), typename K::Triangle_3(t.p[0], t.p[1], t.p[2]));
}

}  // namespace

template <class K>
bool faces_intersect(const Tri<K>& a, const Tri<K>& b) {
  int shared = 0, ia[3], ib[3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (a.id[i] == b.id[j]) {
        ia[shared] = i;
        ib[shared] = j;
        ++shared;
        break;
      }
  if (a.degenerate || b.degenerate) {
    if (shared > 0) return false;  // see the header: reported as degenerate instead
    return primitives_intersect<K>(primitive(a), primitive(b));
  }
  using Triangle = typename K::Triangle_3;
  switch (shared) {
    case 0:
      return CGAL::do_intersect(Triangle(a.p[0], a.p[1], a.p[2]), Triangle(b.p[0], b.p[1], b.p[2]));
    case 1: {
      const int i = ia[0], j = ib[0];
      return edge_meets_triangle<K>(a.p[(i + 1) % 3], a.p[(i + 2) % 3], b) ||
             edge_meets_triangle<K>(b.p[(j + 1) % 3], b.p[(j + 2) % 3], a);
    }
    case 2: {
      const auto& p = a.p[ia[0]];
      const auto& q = a.p[ia[1]];
      const auto& r = a.p[3 - ia[0] - ia[1]];
      const auto& s = b.p[3 - ib[0] - ib[1]];
      return CGAL::coplanar(p, q, r, s) && CGAL::coplanar_orientation(p, q, r, s) == CGAL::POSITIVE;
    }
    default:
      return true;  // the same three vertices: a duplicate face
  }
}

template bool faces_intersect<InputKernel>(const Tri<InputKernel>&, const Tri<InputKernel>&);
template bool faces_intersect<Kernel>(const Tri<Kernel>&, const Tri<Kernel>&);

}  // namespace polyheal::detail
