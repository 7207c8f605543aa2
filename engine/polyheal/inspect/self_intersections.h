// polyheal — global exact self-intersection detection on a soup.
//
// Broad phase: CGAL::box_self_intersection_d over face bounding boxes (exact
// for double input). Narrow phase: detail/triangle_pair.h, exact, with the
// shared-vertex semantics of PMP::self_intersections. Faces share a vertex when
// they share an index: pass a welded soup (mesh/weld.h) to share by position.
// Polygons are fan-triangulated; pairs are reported by face id.
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "polyheal/mesh/soup.h"
#include "polyheal/observer.h"

namespace polyheal {

struct FacePair {
  std::size_t first, second;  // first < second
  bool operator==(const FacePair& o) const { return first == o.first && second == o.second; }
  bool operator<(const FacePair& o) const { return first != o.first ? first < o.first : second < o.second; }
};

struct SelfIntersectionOptions {
  bool parallel = true;           // TBB broad + narrow phase (2 cores: measured ~1.7x, BENCHMARKS.md)
  /// When set (one flag per face): only pairs with at least one flagged
  /// face — the check of an edit that changed those faces.
  const std::vector<char>* only = nullptr;
  Observer* observer = nullptr;
};

/// Every intersecting pair of faces, sorted.
std::vector<FacePair> find_self_intersections(const Soup& soup, const SelfIntersectionOptions& options = {});

/// Every intersecting pair of `soup`, sorted, from those of `base` (all of
/// base's, as find_self_intersections gives them on base welded): pairs of
/// two triangles that have the corner positions of triangles of base are
/// base's pairs of those, renumbered (the pair test sees positions, and in
/// a soup without identical points a position is one vertex); only pairs
/// with another face are searched (`only`). For a repair that changed few
/// faces of a large surface: it costs a hash of both soups' faces and a
/// search of the changed ones (a 1M-face scan with 14 holes filled: 0.4 s
/// against 0.7 s). Not for soups with identical points (their reports pair
/// welded faces); empty when more than `most` of soup's faces changed (the
/// whole search is quicker then). Polygons (their fans depend on the first
/// corner) and triangles that appear twice in soup count as changed.
/// `changed_faces`, when given, receives the number of faces searched.
std::optional<std::vector<FacePair>> find_self_intersections_from(const Soup& soup, const Soup& base,
                                                                  const std::vector<FacePair>& base_pairs,
                                                                  double most = 0.125,
                                                                  std::size_t* changed_faces = nullptr);

/// Early-exit form: true at the first intersecting pair found.
bool does_self_intersect(const Soup& soup, const SelfIntersectionOptions& options = {});

/// A vertex within TetGen's relative tolerance of an edge it is not on (the
/// edge a-b, a < b): TetGen cannot recover that edge as a segment (it
/// stops while "Delaunizing segments"). Same broad phase as above: edge
/// boxes grown by the tolerance against points.
struct VertexNearEdge {
  Index vertex, a, b;
  bool operator<(const VertexNearEdge& o) const {
    return vertex != o.vertex ? vertex < o.vertex : a != o.a ? a < o.a : b < o.b;
  }
};

/// The broad phase of point-near-edge tests: calls near(v, i) for every
/// point v (of `candidates`, or all of `points` when null) inside edge i's
/// bounding box grown by grow(i) (rounded outward) that is not one of the
/// edge's ends. Edges are index pairs into `points`.
void for_each_point_near_edge(const std::vector<Point3d>& points, const std::vector<std::array<Index, 2>>& edges,
                              const std::vector<Index>* candidates, const std::function<double(std::size_t)>& grow,
                              const std::function<void(Index, std::size_t)>& near);

/// Every pair of distinct points of `soup` (a < b) closer than `tol`
/// (predicates.h is_closer_than), sorted: with tol TetGen's shortest edge
/// (its -T tolerance times the bbox diagonal), the points it would merge
/// into one ("Avoid creating a very short edge"), leaving faces with two
/// identical corners that stop it. Identical points are not pairs (weld
/// first).
std::vector<std::array<Index, 2>> find_close_points(const Soup& soup, double tol);

/// Two edges (index pairs into soup.points, a < b) sharing no vertex, closer
/// than TetGen's shortest edge without being the same: TetGen splits a
/// missing segment at a Steiner point, and on two segments that nearly cross
/// the points it puts land within its shortest edge of each other; it stops
/// ("very small input feature size", delaunizesegments). Seen: a rebuilt
/// surface where two faces sharing one corner had edges passing 1e-16 apart
/// (exactly apart; the four points coplanar to 2e-19).
struct EdgeNearEdge {
  std::array<Index, 2> e, f;  // e < f
  bool operator<(const EdgeNearEdge& o) const { return e != o.e ? e < o.e : f < o.f; }
  bool operator==(const EdgeNearEdge& o) const { return e == o.e && f == o.f; }
};

/// Every pair of `edges` sharing no vertex that are strictly closer than
/// `tol` (predicates.h segments_closer_than), sorted. `parallel`: TBB in the
/// broad phase. `only` (one flag per edge): only pairs with a flagged edge.
std::vector<EdgeNearEdge> find_edges_near_edges(const Soup& soup, const std::vector<std::array<Index, 2>>& edges,
                                                double tol, bool parallel = true,
                                                const std::vector<char>* only = nullptr);

/// A vertex closer than TetGen's shortest edge to a face it is not a corner
/// of. With EdgeNearEdge this is every pair of simplices sharing no vertex
/// that come that close (a segment's nearest approach to a triangle is at an
/// end or on an edge of the triangle). Seen: a rebuilt surface folded flat
/// on itself, one layer 1e-16 over the other, where TetGen aborts
/// recovering a facet (formcavity).
struct VertexNearFace {
  Index vertex;
  std::size_t face;
  bool operator<(const VertexNearFace& o) const { return vertex != o.vertex ? vertex < o.vertex : face < o.face; }
};

/// Every vertex of `soup` strictly closer than `tol` to a face it is not a
/// corner of (predicates.h point_closer_than_to_triangle), sorted. `only`
/// (one flag per face): only pairs whose face is flagged or whose vertex is
/// a corner of a flagged face (the check of an edit that changed those).
std::vector<VertexNearFace> find_vertices_near_faces(const Soup& soup, double tol,
                                                     const std::vector<char>* only = nullptr);

/// Faces (p, q, r) and (q, p, s) of a soup sharing the edge pq.
struct EdgeQuad {
  Index p, q, r, s;
  std::size_t face0, face1;
};

/// TetGen's facet merging (1.5.0, `-p`: meshsurface -> mergefacets ->
/// lawsonflip): adjacent faces whose dihedral angle is above its facet angle
/// tolerance (179.9 deg) become one facet, the edge between them is dissolved
/// and the merged facet made Delaunay by flipping edges. On coplanar faces a
/// flip changes nothing; on faces that are not, the flipped pair (r, s, p),
/// (s, r, q) is another surface, and where it cuts a third face TetGen's own
/// surface intersects itself and it stops recovering the facet (throws in
/// scoutcrossedge: a segment crossing the facet).
/// Returns, as face pairs, the quads of `quads` that are not exactly coplanar,
/// that TetGen may flip (not predicates.h tetgen_keeps_edge with its
/// tolerance eps), and whose flipped triangles intersect (exactly, the pair
/// test's semantics) a face of `soup` other than the quad's own two, sorted.
/// Single flips only: after a flip TetGen tests the quad's four other edges
/// and may flip on (cascades are not modelled).
std::vector<FacePair> find_flip_hazards(const Soup& soup, const std::vector<EdgeQuad>& quads, double eps,
                                        bool parallel = true);

/// Every point of `soup` nearly on (predicates.h is_nearly_on_segment, eps)
/// one of `edges` (index pairs into soup.points), sorted.
std::vector<VertexNearEdge> find_vertices_near_edges(const Soup& soup, const std::vector<std::array<Index, 2>>& edges,
                                                     double eps);

}  // namespace polyheal
