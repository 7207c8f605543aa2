// polyheal — cutting the working mesh by a plane (Botsch & Kobbelt §4).
//
// Vertices are classified above / below / on the plane exactly (Epeck), with
// two kinds of snapping onto the plane (classification only: no vertex moves):
//   - epsilon snapping: a vertex within `snap_distance` of the plane;
//   - the safeguard (§4): a crossing edge at an angle below 180° - cap_angle
//     to the plane would give its split point an angle above cap_angle, so
//     one endpoint of it (never a protected vertex) snaps onto the plane.
// Crossed edges are split at their exact intersection point and every cut
// triangle is split into two or three triangles:
//
//        a                      a            one vertex on each side:  (a, x, y) and
//       / \                    / \           the quad (x, b, c, y), split by the
//      x---y   <- plane       x---y          diagonal through its largest angle
//     /     \                / \   \
//    b-------c              b---`---c
//
// Why no cap is created: a crossing edge at angle alpha to the plane makes
// angles of at most 180° - alpha at its split point, and the safeguard keeps
// alpha >= 180° - cap_angle; angles at original vertices only shrink; a quad's
// diagonal runs through its largest angle, so every triangle angle is part of,
// or equal to, a quad angle that was bounded. Where a split runs to an
// epsilon-snapped vertex off the plane this bound is approximate, so callers
// verify with the oracle (exact_predicates.h) before accepting a slice.
//
// Precondition: a triangle mesh. Postcondition: a triangle mesh with the same
// surface point set (faces are subdivided, nothing moves), so no
// self-intersection is created; face provenance (kFaceOrigin) and the
// on-input flag (kFaceOnInput) are inherited.
#pragma once

#include <vector>

#include "polyheal/mesh/mesh.h"

namespace polyheal::detail {

struct SliceOptions {
  double snap_distance = 0.0;  // model units; vertices this close to the plane count as on it
  double cap_angle = 175.0;    // degrees; the safeguard keeps split points below this angle
  std::vector<vertex_descriptor> protected_vertices;  // never snapped (a cap's long-edge ends)
  /// Local mode: only the connected piece of the cut curve through this face
  /// (both faces of every split edge lie on it, so the mesh stays consistent).
  /// Null: the whole mesh (the paper's global slice).
  face_descriptor seed = Mesh::null_face();
  /// Local mode only, when positive: beyond this distance from the seed's
  /// corners the cut is ended at the next vertex — the crossed edge's
  /// endpoint nearer the plane is snapped onto it (classification only, as
  /// the safeguard does; nothing moves) instead of the edge being split. The
  /// verified plan still refuses a would-be cap.
  double radius = 0.0;
  /// Compute every piece first and refuse the slice (mesh untouched) when a
  /// face that is not a cap would leave a cap piece, a cap would leave two,
  /// or a piece would have zero area — possible only through snapping, whose
  /// vertices are off the plane by up to snap_distance or, for the
  /// safeguard, up to |e| sin(180° - cap_angle).
  bool verify = true;
  /// By input face id (kFaceOrigin), faces no slice may cut — those that
  /// intersect another face in the input: no repair may touch an
  /// intersection, so their pieces would only multiply the intersecting
  /// pairs and leave needles nothing can remove. A slice that would cut one
  /// is refused (mesh untouched). Null: none.
  const std::vector<char>* frozen = nullptr;
};

struct SliceResult {
  std::size_t vertices_snapped = 0;  // by epsilon or by the safeguard
  std::size_t edges_split = 0;
  std::size_t faces_cut = 0;
  bool rejected = false;  // verify found a would-be cap; nothing was changed
  std::vector<face_descriptor> faces;  // every face created or reshaped
  std::vector<face_descriptor> parents;  // for each of `faces`, the face it was cut from
  std::vector<vertex_descriptor> vertices;  // the split points
};

SliceResult slice_by_plane(Mesh& mesh, const Kernel::Plane_3& plane, const SliceOptions& options);

/// An edge (as a halfedge) and exact points strictly inside it, ordered
/// from its source.
struct EdgeSplit {
  halfedge_descriptor edge;
  std::vector<Point> points;
};

/// §5 supersampling at chosen points instead of along a plane: each edge is
/// split at its points and each face beside it is fanned from its opposite
/// corner. Nothing moves (the surface point set is the same), so no
/// self-intersection is created. Precondition: no face has two of the
/// edges, and the points lie on their edges. The fan pieces may be caps
/// (the split point of a needle's long side, seen from the far end of its
/// diagonal): the caller's decimation flips them away.
SliceResult split_edges(Mesh& mesh, const std::vector<EdgeSplit>& splits);

/// §3: the plane that eliminates cap `cap` — through its obtuse vertex A,
/// perpendicular to its longest edge BC — with B and C added to
/// `options.protected_vertices` so that the slice really splits BC:
///
///          A                  A on the plane, x = foot of A on BC:
///   B ------------- C         (B, x, A) and (x, C, A) have a right angle at x
///
Kernel::Plane_3 cap_plane(const Mesh& mesh, face_descriptor cap, SliceOptions& options);

}  // namespace polyheal::detail
