// polyheal — regularizing a self-overlapping closed mesh: Jung, Shin & Choi,
// "Self-intersection Removal in Triangular Mesh Offsetting" (CAD&A 2004).
//
// `polyheal regularize`, stage by stage (the paper's Fig. 3):
//   1. detect     the input must be a closed, consistently oriented triangle
//                 mesh (several components, overlapping each other, are the
//                 point): every edge used as often in each direction, so that
//                 the winding number is defined. Where one-sided walls or
//                 faces doubled in one direction are all that stop that (a
//                 convex decomposition's pieces glued with a cap left between
//                 them), those sheets are left out first and reported; an
//                 open surface is refused. Exactly zero-area faces are left out (§3.1): they
//                 bound nothing, and the neighbour across one that closes a
//                 T-junction meets its middle corner, an intersection the
//                 sub-triangulation splits it at. Which faces intersect is
//                 decided by the oracle's global pass (exact predicates on the
//                 doubles, cheap); the intersection *segments* are constructed
//                 before the growth (below).
//   2. grow       the valid region (§3.4) from seed triangles (§3.3) through
//                 intersection-free neighbours. A partially valid triangle is
//                 sub-triangulated (§3.5): its intersection segments with
//                 every triangle it meets are constructed exactly (rationals
//                 from the doubles, exact_meet.h), and a constrained Delaunay
//                 triangulation in its own plane (dropping the dominant normal
//                 axis, an exact projection) splits its edges at the segments'
//                 ends and the segments at their mutual crossings. The wave
//                 crosses the river (§3.6) into the counterpart's sub-triangles.
//   3. stitch     the valid triangles and sub-triangles, with the points where
//                 intersection curves meet merged by exact equality (§3.7).
//   4. certify    the file as written (doubles) is checked exactly.
//
// Where the paper is generalised (its §5 open problems):
// - Seeds. The paper takes a valid triangle touching the bounding box, which
//   gives one seed for one outward offset. Here any unclassified triangle or
//   sub-triangle can be a seed: its winding number is decided exactly by
//   casting a line along the dominant axis of its normal through a point of
//   it with double coordinates and signing the crossings with the input
//   triangles (a line through an edge or a vertex is replaced by another).
//   A (sub-)triangle is valid when the winding number on its outer side is 0
//   (and so 1 on its inner side): the output bounds { winding >= 1 }, the
//   union of the solids the input encloses. So every component gets a seed,
//   components inside another are removed (reported), and cavities (inward
//   facing shells inside a solid) are kept. The wave carries the winding
//   number, not only the verdict: across an edge with two (sub-)triangles it
//   is the same, across an intersection curve each (sub-)triangle around
//   the edge gets its own from the sorted order below, valid or not. So one
//   line classifies a whole connected input (one seed on every raw offset
//   measured, where a line per invalid region cut off by intersection curves
//   took ~10% of the time on dense ones).
// - Crossing the river (§3.6: "by considering the normal orientation
//   compatibility"). At an edge where more than two (sub-)triangles meet,
//   they are sorted around the edge exactly, and the wave leaving a valid one
//   rotates from it through its outer side, tracking the winding number of
//   each wedge; the continuation is the first (sub-)triangle it meets that
//   separates a wedge of winding <= 0 from one of winding >= 1 and faces the
//   first. In the paper's case (two triangles crossing) this is the
//   orientation-compatible sub-triangle of the counterpart.
// - Laziness (§5 suggestion), measured and dropped. The paper grows from one
//   seed and never needs what its wave does not reach; with a seed in every
//   component, every intersecting triangle is sub-triangulated in the end
//   (the growth computed them lazily until 2026-12-05, and split the ones it
//   had not reached afterwards). So the segments and their crossings are
//   constructed up front (sequentially: they get their point ids there),
//   the sub-triangulations are built in parallel, and the growth turns them
//   into pieces in its own order.
//
// Coplanar overlaps (and duplicate faces): the triangles overlapping in one
// plane are sub-triangulated together, and a piece covered by several of them
// stands for all of them, weighted by their net orientation count (opposite
// sheets cancel: two solids touching face to face lose the shared wall).
//
// Rounding (ARCHITECTURE.md, certify after rounding): input vertices keep
// their doubles bit for bit; points on intersection curves are exact and are
// rounded to the nearest double on output. The written file is read back and
// certified. Distinct points that round to the same double merge, and the
// faces thinner than a double step between them go (snap rounding). A
// self-intersection that rounding re-created is repaired before that with the
// local operations of `deintersect` (vertex moves in doubles); what they
// leave is regularized again, exactly, on the rounded coordinates (up to
// max_passes: iterated snap rounding); what is still left is reported, with
// exit code 1.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "polyheal/inspect/report.h"
#include "polyheal/mesh/soup.h"
#include "polyheal/observer.h"

namespace polyheal {

struct RegularizeOptions {
  bool certify = true;  // certify the rounded result (callers that certify the written file say false)
  int max_passes = 3;   // regularizations of the rounded result while rounding leaves crossings
  /// Round the result to floats, not doubles (the output is STL, which
  /// holds float32 only): every point to its nearest float, and the
  /// crossings that rounding makes regularized again on the floats.
  bool float_coordinates = false;
  Observer* observer = nullptr;
  /// Every intersecting pair of the input, as inspect() reports them, when
  /// the caller has them already (InspectOptions::self_intersections).
  const std::vector<FacePair>* known_pairs = nullptr;
};

struct RegularizeReport {
  // input
  std::size_t faces = 0, vertices = 0, components_in = 0;
  std::size_t zero_area_faces = 0;     // left out (§3.1): they bound nothing
  std::size_t polygons_fanned = 0;     // input faces with more than 3 corners, fanned into triangles
  std::size_t walls_left_out = 0;      // faces left out first so that the surface bounds a volume (walls, doubled faces)
  std::size_t intersecting_pairs_in = 0, intersecting_faces_in = 0;
  double bbox_diagonal = 0;
  // growing (the paper's Table 1 and Fig. 2 groups, counted over input triangles)
  std::size_t segments = 0;            // intersection segments constructed (pairs, exactly)
  std::size_t triangles_split = 0;     // triangles sub-triangulated
  std::size_t split_unreached = 0;     // of those, none of whose sub-triangles a wave from an
                                       // intersection-free seed classified (lines of their own did)
  std::size_t sub_triangles = 0;       // sub-triangles they were split into
  std::size_t valid = 0, partially_valid = 0, invalid = 0;
  std::size_t seeds = 0, line_casts = 0;  // seeds tried (valid or not), winding-number lines cast
  std::size_t unclassified = 0;        // (sub-)triangles no line could classify (reported, not output)
  std::size_t orientation_conflicts = 0;  // river crossings that found no compatible continuation
  std::size_t components_removed = 0;  // input components with no face in the output (enclosed or inverted)
  // output
  std::size_t faces_out = 0, vertices_out = 0, new_vertices = 0;
  std::size_t faces_kept = 0;          // output faces that are input faces, bit for bit
  double seconds_detect = 0, seconds_intersections = 0, seconds_grow = 0, seconds_stitch = 0,
         seconds_certify = 0;
  std::size_t rounding_merged = 0;     // distinct exact points that rounded to one double, or float (merged)
  std::size_t rounding_collapsed = 0;  // faces that lost a corner to such a merge (thinner than a double step)
  std::size_t pinches_split = 0;       // vertices where the union's boundary pinched (split into one per cone)
  std::size_t pinched_edges_split = 0; // ... and edges whose ends could not part it: split at their midpoint, a pinch
  double pinch_displacement = 0;       // largest move of a pinch copy into its cone
  std::size_t rounding_pairs = 0;      // intersecting pairs rounding created (before their repair)
  std::size_t rounding_moves = 0;      // vertices deintersect moved to repair them
  int rounding_passes = 1;             // regularizations run (more than 1: crossings rounding left were regularized again)
  std::size_t float_rounded = 0;       // with float_coordinates: vertices rounded to floats (each rounding counted)
  std::size_t float_pairs = 0;         // ... intersecting pairs that rounding made (before their repair)
  std::size_t float_moves = 0;         // ... vertices deintersect moved to repair them
  // certificate, on the soup as written (certify())
  Report out;                          // the exact inspection of the written file
  std::size_t certificate_searched = 0;  // written faces its self-intersection search covered (certify())
  double max_distance_to_input = 0;    // output -> input (each output triangle to the input triangle it lies on)
  double hausdorff = 0, hausdorff_error_bound = 0;  // symmetric, to the input (-1: not measured)
  bool certified = false;              // out.certified_clean()
};

/// A surface searched whole for self-intersections, exactly, with every
/// intersecting pair of it as inspect() reports them (sorted; for a soup
/// with identical points, those of the soup welded): a base from which
/// certify() finds the pairs of a written file that keeps most of its
/// triangles, searching only the others (inspect_from()).
struct ScannedSurface {
  Soup soup;
  std::vector<FacePair> pairs;
};

struct RegularizeResult {
  Soup soup;
  RegularizeReport report;
  /// Per output face, the input face it lies on (provenance).
  std::vector<std::size_t> source_face;
  /// certify()'s base: the rounded surface as the last check of what
  /// rounding broke searched it whole (before that check's repairs), when it
  /// did — most of its faces had a rounded corner — and it had no identical
  /// points; else the input (welded) as the detect stage searched it, unless
  /// the caller gave its pairs (RegularizeOptions::known_pairs: then none).
  std::optional<ScannedSurface> scanned;
};

/// Stages 1-3, the repair of what rounding broke, and, with
/// options.certify, stage 4 on the rounded result. Throws UnsupportedInput
/// for an input that is not a closed, consistently oriented triangle mesh
/// (every edge used as often in each direction) once walls and doubled faces
/// are left out (report.walls_left_out). An input facing inwards everywhere,
/// or a double-sided sheet, encloses nothing: the output is empty.
RegularizeResult regularize(const Soup& input, const RegularizeOptions& options = {});

/// Is output face f its source face (face source_face[f] of `input`),
/// corner for corner, bit for bit?
bool kept_as_input(const Soup& input, const Soup& output, const std::vector<std::size_t>& source_face, std::size_t f);

/// Stage 4 on `written` (the output as read back; `input` as given): fills the
/// certificate half of `report` (out, distances, certified). `source_face`
/// is RegularizeResult::source_face. With `scanned` (RegularizeResult::
/// scanned), the self-intersection search covers only the written faces
/// that are not triangles of that surface (by their corners' positions,
/// compared here); the pairs among the others are the scanned surface's.
void certify(const Soup& input, const Soup& written, const std::vector<std::size_t>& source_face,
             RegularizeReport& report, const std::optional<ScannedSurface>& scanned = std::nullopt);

}  // namespace polyheal
