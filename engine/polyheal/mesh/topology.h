// polyheal — combinatorial structure of a soup: edges, fans, components.
//
// Pure combinatorics on vertex indices (no geometry, no CGAL). Call it on a
// welded soup (weld.h) so that faces share vertices by position. Used by the
// oracle's report and by the soup-to-mesh conversion to say exactly why a soup
// is not an oriented 2-manifold.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "polyheal/mesh/soup.h"

namespace polyheal {

/// A face corner: face f, position k in the face; `vertex` is its index.
struct EdgeUse {
  std::size_t face;
  Index from, to;  // the edge as the face traverses it
};

struct Edge {
  Index a, b;                  // a < b
  std::vector<EdgeUse> uses;   // faces traversing this edge
};

struct Topology {
  std::size_t edge_count = 0;
  std::vector<Edge> boundary_edges;       // one use
  std::vector<Edge> nonmanifold_edges;    // three or more uses
  std::vector<Edge> misoriented_edges;    // two uses in the same direction
  /// Exactly two uses in opposite directions (the good case; stored compactly).
  struct InteriorEdge {
    Index a, b;                 // a < b
    std::uint32_t face0, face1;
  };
  std::vector<InteriorEdge> interior_edges;
  std::vector<Index> nonmanifold_vertices;  // faces around it form more than one fan
  std::size_t boundary_loops = 0;         // connected components of the boundary-edge graph
  std::size_t components = 0;             // faces connected through shared edges
  std::vector<std::size_t> face_component;
  std::size_t isolated_vertices = 0;      // points used by no face
  std::vector<std::array<std::size_t, 2>> duplicate_faces;  // same vertex set, (first, later)
  std::vector<std::size_t> repeated_index_faces;            // a vertex index occurs twice
};

/// Analyses `soup` (indices as given: weld first for positional sharing).
Topology analyze_topology(const Soup& soup);

/// Whether a halfedge mesh can be built from the soup the topology is of,
/// faces as they are (for faces of three corners or more, what CGAL's
/// PMP::is_polygon_soup_a_polygon_mesh decides — with an ordered set of
/// directed edges and one per vertex, 1.2 s on a 1M-face scan): no face
/// repeats an index, every edge is used once or twice in opposite
/// directions, and the faces round each vertex form one fan.
inline bool is_polygon_mesh(const Topology& t) {
  return t.repeated_index_faces.empty() && t.nonmanifold_edges.empty() && t.misoriented_edges.empty() &&
         t.nonmanifold_vertices.empty();
}

/// The key of the edge {a, b}, either way round: (min << 32) | max.
inline std::uint64_t undirected_edge_key(Index a, Index b) {
  return a < b ? (std::uint64_t(a) << 32) | b : (std::uint64_t(b) << 32) | a;
}

/// The faces to leave out so that `soup` (welded) comes nearer to bounding a
/// volume — every edge used as often in each direction — when sheets that
/// hang off the rest are what stops it.
///
/// The surface is cut into sheets: faces joined across edges with exactly
/// two uses in opposite directions. A sheet's net use of its other (rim)
/// edges is what leaving it out changes. Smaller sheets are tried first (a
/// wall or a fin is a face or a few; the solids it hangs off are large), and
/// one is left out when that lowers the total imbalance (sum over edges of
/// |uses one way - uses the other|) and it hangs off what is kept: each rim
/// edge is used at least twice by kept faces outside the sheet (a wall
/// between two solids, meeting them along its whole rim) or, with `flaps`,
/// by none (a free edge: a fin or flap hanging off a solid along its other
/// rim edges, of which it needs one). So a hole stays a hole (its rim is
/// used once by the faces around it) and faces turned the wrong way stay
/// (two uses in one direction: an orientation defect).
///
/// `may_leave_out`, when given, is asked before a sheet is left out (its
/// faces, sorted); false keeps it, and it is not asked again. (Which of two
/// sheets that balance the same edges is the wall is geometry: a solid
/// sharing faces with the part nested in it has both the part's exposed
/// faces and its own around them hanging off the shared rim.)
struct SheetsLeftOut {
  std::vector<std::size_t> faces;  // sorted
  long imbalance = 0;              // of what is kept
  /// When imbalance > 0: the smallest edge (a < b) what is kept still uses
  /// more often one way than the other, and by how much.
  Index unbalanced_a = 0, unbalanced_b = 0;
  long unbalanced_by = 0;
};
SheetsLeftOut sheets_to_leave_out(const Soup& soup, bool flaps,
                                  const std::function<bool(const std::vector<std::size_t>&)>& may_leave_out = {});

}  // namespace polyheal
