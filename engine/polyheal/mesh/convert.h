// polyheal — soup <-> Surface_mesh.
#pragma once

#include <string>
#include <vector>

#include "polyheal/mesh/mesh.h"
#include "polyheal/mesh/soup.h"

namespace polyheal {

/// Why a soup is not an oriented 2-manifold polygon mesh: one line per
/// problem, naming the edge, vertex or faces at fault. Empty when it is.
struct MeshBuildResult {
  bool ok = false;
  std::vector<std::string> problems;
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

/// p with each exact coordinate rounded to the nearest double (ties to even).
Point3d nearest_point3d(const Point& p);
/// One exact number rounded to the nearest double (ties to even).
double nearest_double(const Kernel::FT& x);

/// The mesh as a soup, each exact coordinate rounded to the nearest double
/// (ties to even; certify after rounding: check the result, not the mesh).
/// Vertices are renumbered densely.
Soup mesh_to_soup(const Mesh& mesh);

}  // namespace polyheal
