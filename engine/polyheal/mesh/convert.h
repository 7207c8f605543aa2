// polyheal — soup <-> Surface_mesh.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "polyheal/mesh/mesh.h"
#include "polyheal/mesh/soup.h"

namespace polyheal {

/// Why a soup is not an oriented 2-manifold polygon mesh: one line per
/// problem, naming the edge, vertex or faces at fault. Empty when it is.
struct MeshBuildResult {
  bool ok = false;
  std::vector<std::string> problems;
  std::size_t welded = 0;  // points welded to an identical earlier one
};

/// Welds identical points, then builds `mesh` (cleared first) when the soup is
/// a valid oriented 2-manifold polygon mesh; otherwise leaves it empty and
/// lists every problem. Each face's input id goes to the kFaceOrigin property.
MeshBuildResult soup_to_mesh(const Soup& soup, Mesh& mesh);

/// The same, except that a vertex whose faces form several fans (a pinch
/// point, non-manifold) is not a problem: each fan gets its own copy of the
/// vertex, at the same position. Written out and read back, the copies weld
/// into one point again. `split` (if given) receives the number of copies
/// added.
MeshBuildResult soup_to_mesh_splitting_pinches(const Soup& soup, Mesh& mesh, std::size_t* split = nullptr);

/// After soup_to_mesh_splitting_pinches: the copies of each pinch point
/// (vertices at one position) get kVertexPinned (no repair may move or remove
/// one: that would tear the point apart) and one kVertexIdentity, so that
/// the oracle treats them as the single vertex they are in the file. Does
/// nothing when no point was split.
void mark_split_pinches(Mesh& mesh);

/// The copies of each split pinch point, by their kVertexIdentity; empty
/// when the mesh has none. Copies are pinned, so the lists stay valid while
/// repairs add and remove other vertices.
using PinchCopies = std::unordered_map<std::uint32_t, std::vector<vertex_descriptor>>;
PinchCopies pinch_copies(const Mesh& mesh);

/// Is there an edge, other than v-w itself, between a copy of v's point and
/// a copy of w's? In the file the copies of a pinch point are one vertex, so
/// a new edge v-w would duplicate that edge: welded, two boundary edges
/// become one interior edge (or a third face joins an edge), the point's
/// fans merge, and the written file's topology changes though the mesh's
/// does not (found on angle_block.STL by degenerate's collapses, on
/// shark_b.off by deintersect's swaps). False when nothing was split.
bool copies_share_edge(const Mesh& mesh, const std::optional<VertexIdentityMap>& identity,
                       const PinchCopies& copies, vertex_descriptor v, vertex_descriptor w);

/// p with each exact coordinate rounded to the nearest double (ties to even).
Point3d nearest_point3d(const Point& p);
/// The same, as an exact point (with double coordinates): the position a
/// vertex takes when it is rounded in the working mesh.
Point nearest_double_point(const Point& p);
/// One exact number rounded to the nearest double (ties to even).
double nearest_double(const Kernel::FT& x);
/// A rational rounded to the nearest double (ties to even), as above. `q`
/// may be left unreduced: MPFR divides its numerator by its denominator as
/// they are (exact points kept as homogeneous coordinates need no gcd).
double nearest_double_of(const mpq_class& q);

/// The mesh as a soup, each exact coordinate rounded to the nearest double
/// (ties to even; certify after rounding: check the result, not the mesh).
/// Vertices are renumbered densely.
Soup mesh_to_soup(const Mesh& mesh);

}  // namespace polyheal
