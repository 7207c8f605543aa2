// polyheal — removing degenerate faces: Botsch & Kobbelt, "A Robust
// Procedure to Eliminate Degenerate Faces from Triangle Meshes" (VMV 2001).
//
// The pipeline (`polyheal degenerate`), stage by stage:
//   1. preprocess   weld identical points, and points closer than --weld
//                   (default 1e-9 of the bbox diagonal: a CAD export's
//                   rounding cracks) where that builds a manifold mesh with
//                   no more intersecting pairs; remove faces with a repeated
//                   vertex index topologically; build the exact working mesh
//                   (Surface_mesh<Epeck>). A non-manifold soup is refused.
//                   The topology kept is the welded input's.
//   2. zero-area    exactly collinear faces go by edge flip or collapse
//                   (detail/shape_decimation.h).
//   3. slicing      optional supersampling by three stacks of axis-aligned
//                   planes (§5, --slice-grid); then every cap is cut by the
//                   plane through its obtuse vertex perpendicular to its
//                   longest edge (§3-4, detail/plane_slice.h). Each slice's
//                   pieces are classified exactly before it is made, and a
//                   slice that would leave more caps is refused, so every
//                   accepted slice removes a cap and creates none. By default
//                   a slice is limited to the connected cut curve through the
//                   cap (local mode); --global-slices cuts the whole mesh as
//                   the paper does. By default the needles a slice leaves are
//                   decimated right after it (the paper's §7 future work:
//                   "decimating along the intersection curve after each
//                   slicing"). Right after a slice, its split points take
//                   their nearest doubles wherever that changes nothing the
//                   oracle checks around them (certify after rounding, early:
//                   the decimation then runs on doubles, not rationals); the
//                   others stay exact. No slice cuts a face that intersects another
//                   in the input (SliceOptions::frozen): nothing may touch an
//                   intersection, so its pieces would only add pairs and
//                   needles.
//   4. decimation   needles and whatever slicing could not remove go by
//                   collapses and flips within the tolerance (§5). A needle
//                   no operation can remove (the side of a thin strip) gets
//                   local supersampling: slices across its longest edge,
//                   into the fewest equal pieces that clear the needle angle
//                   (halves unless a strip needs more), then decimation
//                   again. Needles still stuck get the rounds again with
//                   vertex removal (the hole triangulated anew) added to the
//                   decimation; the last pass removes split points that way
//                   too wherever every face stays fine.
//   5. certify      the exact mesh is rounded to doubles; certify() checks
//                   the written soup with the oracle: shapes, topology,
//                   self-intersections, Hausdorff distance to the input.
//
// No input vertex moves (but by the weld): vertices keep their exact input coordinates; slicing
// adds points on the input surface (some rounded to doubles at once, an ulp
// away); collapses keep the surviving vertex in place.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "polyheal/inspect/report.h"
#include "polyheal/mesh/soup.h"
#include "polyheal/observer.h"

namespace polyheal {

struct DegenerateOptions {
  double cap_angle = 175.0;      // degrees: a face with a larger angle is a cap
  double needle_angle = 5.0;     // degrees: a face with a smaller angle is a needle
  double tolerance = -1.0;       // model units; negative: tolerance_ratio x bbox diagonal
  double tolerance_ratio = 1e-3;
  double weld = -1;              // model units: weld vertices closer than this first; negative: weld_ratio x diagonal; 0: identical only
  double weld_ratio = 1e-9;
  int slice_grid = 0;            // N: three stacks of N axis-aligned planes first (§5)
  bool global_slices = false;    // the paper's global slices instead of local ones
  bool interleave = true;        // decimate along each slice right after it
  bool slice = true;             // false: no slicing at all, only collapses, flips and vertex removals
  bool certify = true;           // certify the rounded result (callers that certify the written file say false)
  /// Degrees; > 0: faces folded onto a neighbour below this angle are bad as
  /// well and no operation makes such a fold (repair --for tetgen: TetGen's
  /// 0.1 degrees). Not part of the paper.
  double fold_angle = 0;
  Observer* observer = nullptr;
};

/// Zero-area faces, caps and needles of a soup (Botsch & Kobbelt §2).
struct ShapeCounts {
  std::size_t zero_area = 0, caps = 0, needles = 0;
  std::size_t total() const { return zero_area + caps + needles; }
};

/// A bad face left in the output, by its index in the output file.
struct Leftover {
  std::size_t face = 0;
  std::string shape;   // "zero-area", "cap", "needle"
  std::string reason;
};

struct DegenerateReport {
  // parameters as used
  double cap_angle = 0, needle_angle = 0, tolerance = 0, bbox_diagonal = 0;
  int slice_grid = 0;
  bool global_slices = false, interleave = true;
  // input
  std::size_t faces_in = 0, repeated_index_faces = 0;
  std::size_t pinched_vertices_split = 0;  // copies made for pinch points (welded again on output)
  ShapeCounts before;
  std::size_t self_intersections_in = 0;
  SurfaceTopology topology_unwelded;  // the input's, as read
  // the near weld (preprocess): vertices closer than weld_distance merged
  double weld_distance = 0;
  std::size_t near_vertices_welded = 0;
  double max_weld_move = 0;            // the farthest a welded vertex moved
  bool weld_refused = false;           // the welded surface was not manifold, or had more intersecting pairs
  std::size_t self_intersections_welded = 0;  // pairs of the surface worked on (after the weld)
  SurfaceTopology topology_in;        // ... and its topology, which the output must keep
  // stages
  std::size_t faces_after_zero_area = 0, faces_after_slicing = 0, faces_out = 0;
  std::size_t peak_faces = 0;  // the largest intermediate mesh
  std::size_t grid_slices = 0, grid_slices_refused = 0;
  std::size_t cap_slices = 0, cap_slices_refused = 0;
  std::size_t needle_slices = 0, needle_slices_refused = 0;
  std::size_t apex_fans = 0, apex_fan_points = 0;  // remesh_apex_fans(): cone tips graded anew, points made
  std::size_t planar_fans = 0;  // remesh_planar_fans(): planar faces fanned from a corner, graded anew
  std::size_t apexes_moved = 0;  // ... tips of cones too narrow for any fan there, moved inward along the axis
  double max_displacement = 0;   // the farthest any input vertex moved (only such tips, and welded vertices, move)
  std::size_t wedge_tips = 0, wedge_cuts = 0;  // cut_wedge(): tips given a series of cuts, cuts made
  std::size_t strips_staggered = 0, strip_points = 0;  // stagger_strips(): strips given side points, points
  std::size_t strip_zigzags = 0;  // ... strips retriangulated directly as the zigzag between them
  std::size_t collapses = 0, flips = 0;
  std::size_t removals = 0;  // split points (and, when stuck, any vertex) removed with the hole triangulated anew
  std::size_t split_points_rounded = 0;  // slices' split points given their doubles early (settle)
  double seconds_preprocess = 0, seconds_zero_area = 0, seconds_slicing = 0, seconds_decimation = 0,
         seconds_certify = 0;
  // output, filled by certify() on the soup as written
  ShapeCounts after;
  std::vector<Leftover> leftovers;
  std::size_t self_intersections_out = 0;
  SurfaceTopology topology_out;
  double hausdorff = 0;  // symmetric, to the input surface (-1: not measured)
  double hausdorff_error_bound = 0;  // the true distance is within this of `hausdorff`
  bool certified = false;  // see certify()

  /// Faces of the output (in order) that were bad already in the exact mesh,
  /// before rounding; certify() uses it to say why a face is left.
  std::vector<char> exact_bad;
};

struct DegenerateResult {
  Soup soup;  // the output, rounded to doubles
  DegenerateReport report;
};

/// Runs stages 1-4 and, with options.certify, certifies the rounded result
/// (stage 5).
/// Throws UnsupportedInput for a soup that is not an oriented 2-manifold.
DegenerateResult remove_degenerate_faces(const Soup& input, const DegenerateOptions& options = {});

/// Stage 5 on `written` (the output as read back from disk; `input` as given
/// to remove_degenerate_faces): fills the
/// output half of `report`. certified = no zero-area face, cap or needle;
/// the topology of the input (after the near weld); no more intersecting
/// pairs than the input had after the weld; Hausdorff distance to the input
/// as given (not welded) within the tolerance.
void certify(const Soup& input, const Soup& written, DegenerateReport& report);

}  // namespace polyheal
