// polyheal — the oracle's local query: an updatable spatial index over the
// faces of the working mesh, and "which faces do these faces intersect now?".
//
// Repairs (deintersect, degenerate, regularize) edit a few faces at a time;
// verifying an edit must cost time proportional to the edited region, not to
// the mesh. The index is a dynamic bounding-volume hierarchy over face
// bounding boxes (balanced when built; a changed face's leaf is removed and
// re-inserted), so it serves meshes mixing very small and very large faces;
// a query visits the boxes its faces meet, then runs the exact pair test of
// detail/triangle_pair.h on Epeck points. Same semantics as the global pass
// (self_intersections.h).
//
// Usage in a repair:
//   LocalIndex index(mesh);
//   ... move a vertex / flip an edge / add faces ...
//   index.update(changed_faces);            // re-box the changed and new faces
//   index.remove(deleted_face);             // before Surface_mesh::remove_face
//   if (index.intersections(changed_faces).empty()) accept();
#pragma once

#include <array>
#include <memory>
#include <utility>
#include <vector>

#include "polyheal/mesh/mesh.h"

namespace polyheal {

class LocalIndex {
 public:
  /// Indexes every face of `mesh`. The mesh must outlive the index.
  explicit LocalIndex(const Mesh& mesh);
  ~LocalIndex();
  LocalIndex(const LocalIndex&) = delete;
  LocalIndex& operator=(const LocalIndex&) = delete;

  /// (Re)indexes faces that are new or whose vertices moved.
  void update(const std::vector<face_descriptor>& faces);
  /// Drops a face from the index (call before removing it from the mesh).
  void remove(face_descriptor f);

  /// Every pair (f, g) with f in `faces` and g any indexed face such that f
  /// and g intersect now; a pair with both faces in `faces` appears once.
  std::vector<std::pair<face_descriptor, face_descriptor>> intersections(
      const std::vector<face_descriptor>& faces) const;
  /// Early-exit form.
  bool intersects(const std::vector<face_descriptor>& faces) const;

  /// A proposed edit, asked before making it: would triangles `proposed`
  /// (vertex triples of the mesh, in their current positions) intersect each
  /// other or an indexed face not listed in `replaced` (the faces the edit
  /// removes or reshapes)? Same semantics as intersections().
  bool would_intersect(const std::vector<std::array<vertex_descriptor, 3>>& proposed,
                       const std::vector<face_descriptor>& replaced) const;

  /// Indexed faces whose bounding boxes meet `box` (the boxes as last
  /// indexed: a face whose vertex moved since keeps its old box until
  /// update()).
  std::vector<face_descriptor> faces_meeting(const CGAL::Bbox_3& box) const;

  std::size_t size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace polyheal
