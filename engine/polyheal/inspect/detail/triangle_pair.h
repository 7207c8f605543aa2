// polyheal — the one exact triangle-pair test (internal to inspect/).
//
// Semantics follow CGAL::Polygon_mesh_processing::self_intersections: two
// faces intersect when they share a point other than a common vertex or a
// common edge.
//
//   no shared vertex      any common point
//   one shared vertex v   the edge opposite v in one face meets the other face
//                         (complete: any extra common point implies this)
//   shared edge pq        the two opposite vertices r, s lie in one plane with
//                         pq and on the same side of it (fold-over):
//                              r   s
//                              |\ /|        coplanar, same side of pq
//                              p---q
//   same three vertices   a duplicate face: always intersecting
//
// Degenerate faces (collinear corners) are tested as the segment or point they
// are, against faces they share no vertex with; a degenerate face that shares
// a vertex is already a reported defect, and its contacts there are not
// counted as intersections.
//
// Vertex identity is by id: two distinct ids at the same position count as
// distinct points (so coincident unwelded vertices do intersect).
#pragma once

#include <array>

#include "polyheal/mesh/mesh.h"
#include "polyheal/mesh/soup.h"

namespace polyheal::detail {

template <class K>
struct Tri {
  std::array<typename K::Point_3, 3> p;
  std::array<std::uint64_t, 3> id;
  bool degenerate;  // CGAL::collinear(p[0], p[1], p[2]), computed once per face by the caller
};

/// Tri with its degeneracy flag computed.
template <class K>
Tri<K> make_tri(const typename K::Point_3& a, const typename K::Point_3& b, const typename K::Point_3& c,
                std::uint64_t ia, std::uint64_t ib, std::uint64_t ic) {
  return Tri<K>{{a, b, c}, {ia, ib, ic}, CGAL::collinear(a, b, c)};
}

/// Exact; instantiated for InputKernel (Epick, on file doubles) and Kernel (Epeck).
template <class K>
bool faces_intersect(const Tri<K>& a, const Tri<K>& b);

extern template bool faces_intersect<InputKernel>(const Tri<InputKernel>&, const Tri<InputKernel>&);
extern template bool faces_intersect<Kernel>(const Tri<Kernel>&, const Tri<Kernel>&);

}  // namespace polyheal::detail
