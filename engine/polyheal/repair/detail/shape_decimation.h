// polyheal — removing needles (and what slicing left) by local operations
// (Botsch & Kobbelt §5: "a suitable mesh decimation algorithm ... that stays
// within a prescribed approximation error and controls the decimation process
// to optimize for well shaped triangles").
//
// Operations, each decided before it is made:
//   halfedge collapse u -> v   u's faces are re-attached to v, which keeps its
//                              exact position (no new coordinates: input
//                              vertices stay as read)
//   edge flip                  the diagonal of two faces' quad is swapped
//                              (the fix for exactly collinear faces)
// An operation is made only if, exactly on the Epeck points,
//   - the link condition holds and no boundary vertex leaves the boundary
//     (manifoldness, genus and boundary count unchanged);
//   - no new triangle is degenerate or a cap, and none turns against the
//     face it replaces (normals keep a positive dot product);
//   - no new triangle intersects another face (LocalIndex::would_intersect);
// and, measured in doubles against the input surface (distance.h):
//   - samples of every new triangle lie within `tolerance` of the input;
//   - the input surface it takes away stays within `tolerance` of the new
//     faces: samples of replaced faces that still lay in the input surface
//     (kFaceOnInput), and the removed vertex, are attached to the nearest new
//     face and re-checked whenever that face is replaced in turn (as in
//     Kobbelt, Campagna & Seidel's decimation framework, the paper's [11]);
//     sampling decides at 70% of the tolerance, and the pipeline reports the
//     Hausdorff distance measured on the result;
// and it strictly raises the worst angle quality of the faces it replaces
// (or, for a collapse — or with fold_angle, a flip —, leaves fewer bad faces).
// With fold_angle, no new triangle folds onto a neighbour (new or kept)
// below it, and a folded face gets every collapse and flip of its edges as
// candidates: a fold is usually a spike vertex, gone with a collapse; and
// a point the operation takes away may be covered by a face it keeps
// around it (the spike lies on the face it is folded onto).
// Among the valid operations for a bad face the one leaving the best worst
// triangle wins; bad faces are treated worst first.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

#include "polyheal/mesh/mesh.h"

namespace polyheal {
class LocalIndex;
}

namespace polyheal::detail {

class SurfaceDistance;

struct DecimationOptions {
  double cap_angle = 175.0;    // degrees
  double needle_angle = 5.0;   // degrees
  double tolerance = 0.0;      // model units: distance to the input surface
  /// Degrees; > 0: a face folded onto a neighbour below this angle is bad
  /// too, and no operation may fold two faces that far (TetGen's "nearly
  /// self-intersecting facets", 0.1 degrees by default).
  double fold_angle = 0.0;
  /// Degrees; > 0: no operation may fold a new triangle onto a neighbour
  /// below it (folded faces are not bad for it). Where points were rounded
  /// to doubles early, a region that was exactly planar is lifted by an
  /// ulp, and a triangle folded back onto its neighbour no longer overlaps
  /// it exactly (no intersection stops it) — a spike TetGen refuses.
  double fold_guard_angle = 0.0;
};

struct DecimationStats {
  std::size_t collapses = 0;
  std::size_t flips = 0;
  std::size_t removals = 0;  // vertices removed with their hole triangulated anew (set_retriangulate())
};

/// A new triangulation of a disc of faces: the star of an interior vertex
/// (detail/apex_fan.h plans one for a cone's tip), or a fan of coplanar
/// faces around a boundary corner of their polygon (given a centre inside).
/// Vertex ids of `triangles`: 0 is the centre (a new vertex at `centre`),
/// 1 + i is link[i], 1 + n + k a new vertex at points[k] (n = link.size()).
struct StarReplacement {
  /// The disc's boundary, in its faces' orientation: edge i runs from
  /// link[i] to link[i + 1 mod n].
  std::vector<vertex_descriptor> link;
  /// The faces replaced; with a centre vertex, exactly its star, and that
  /// vertex goes (its position is a displaced point, like a collapse's).
  std::vector<face_descriptor> faces;
  std::optional<vertex_descriptor> centre_vertex;
  std::vector<face_descriptor> sector_faces;  // per boundary edge i, its face in the disc
  Point centre;
  std::vector<Point> points;
  std::vector<std::array<std::size_t, 3>> triangles;  // oriented as the disc's faces
  std::vector<std::array<std::size_t, 2>> sectors;    // per triangle: the boundary edges it spans, first to last
};

class ShapeDecimator {
 public:
  /// `index` must index every face of `mesh` and is kept up to date.
  ShapeDecimator(Mesh& mesh, LocalIndex& index, const SurfaceDistance& input, const DecimationOptions& options);
  ~ShapeDecimator();

  /// Removes the needles, caps and zero-area faces among `faces`, and those
  /// its own operations create. Faces it cannot fix stay (is_bad()).
  /// `fresh` (a slice's split points) may merge with each other, but are
  /// collapsed into older vertices only where that leaves only fine faces —
  /// otherwise decimation would undo the slice that was made for it.
  void run(const std::vector<face_descriptor>& faces, const std::vector<vertex_descriptor>& fresh = {});

  /// Collapses away each of `vertices` (a slice's split points) where that
  /// leaves only fine faces within the tolerance (paper §7: "decimating along
  /// the intersection curve after each slicing"); with set_retriangulate(),
  /// also by removing it with its hole triangulated anew.
  void simplify(const std::vector<vertex_descriptor>& vertices);

  /// After a slice cut each of `parents` into the faces beside it in
  /// `faces` (a face may be its own parent): the points attached to a parent
  /// are re-attached to the nearest of its pieces.
  void reattach(const std::vector<face_descriptor>& faces, const std::vector<face_descriptor>& parents);

  /// Whether run() and simplify() may also remove a vertex with its hole
  /// triangulated anew for the best worst shape (off by default).
  void set_retriangulate(bool on);

  /// Replaces the disc by `r.triangles` if, exactly, every one is fine (no
  /// needle, cap or zero area), none turns against the faces in the middle
  /// of the boundary edges it spans,
  /// none folds or intersects another face, and the tolerance holds both
  /// ways (the disc's surface and its centre vertex near the new faces). Returns
  /// the new faces (and appends the new vertices, the centre's first, to
  /// `made`); nothing, the mesh unchanged, when refused.
  std::vector<face_descriptor> replace_star(const StarReplacement& r, std::vector<vertex_descriptor>& made);

  bool is_bad(face_descriptor f) const;
  const DecimationStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Moves vertex v to the nearest doubles of its exact coordinates when that
/// changes nothing the oracle checks around it, decided exactly: no face
/// around it turns over (normals keep a positive dot product), none becomes
/// degenerate, a cap or a needle unless it was one already (cos_cap,
/// cos_needle: classify_triangle's thresholds), and none meets another face
/// (`index`, which is updated). Returns whether it moved (false too when v
/// is a double point already).
bool round_if_unchanged(Mesh& mesh, LocalIndex& index, vertex_descriptor v, double cos_cap, double cos_needle);

/// round_if_unchanged() for all of `points` at once: every one that is not
/// a double point moves to its nearest doubles, and the faces round them are
/// checked once, together, the same way (each against its shape with all
/// its corners as they were; round_if_unchanged is this for one point).
/// Returns how many moved, or nothing (and nothing moved) when a check
/// fails: then round them one by one. Checked
/// together, a slice's faces are pairs of double triangles; one by one, a
/// point's neighbours along the slice are still rational (exact tests on
/// rationals where CAD faces are coplanar).
std::optional<std::size_t> round_all_if_unchanged(Mesh& mesh, LocalIndex& index,
                                                  const std::vector<vertex_descriptor>& points, double cos_cap,
                                                  double cos_needle);

}  // namespace polyheal::detail
