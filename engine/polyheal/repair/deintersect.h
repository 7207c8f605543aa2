// polyheal — removing self-intersections: Yamakawa & Shimada, "Removing
// Self Intersections of a Triangular Mesh by Edge Swapping, Edge Hammering,
// and Face Lifting" (IMR 2009).
//
// `polyheal deintersect`, stage by stage:
//   1. detect     build the working mesh (an oriented 2-manifold, open or
//                 closed, pinch vertices allowed: each fan gets a pinned copy
//                 of the vertex; anything else is refused) and find every
//                 intersecting pair with the oracle's local index.
//   2. repair     rounds of the paper's two-phase scheme (§4.5). The cost
//                 phase tries every applicable operation on the faces that
//                 intersect now — edge swap (§4.2) on their edges, edge
//                 hammer (§4.3) on their vertices, face lift (§4.4) on the
//                 faces themselves, plus our group move (a connected set of
//                 vertices poking through faces, moved back at once) and,
//                 when nothing else applies, our push (the nodes on one
//                 side of a face moved past it, a group move too) and pair
//                 move (a corner of each of two crossing faces smoothed at
//                 once) — measures the volume it sweeps and retracts it;
//                 the implementation phase applies them in ascending
//                 cost, each re-validated on the current mesh.
//                 Rounds repeat until nothing applies.
//   3. certify    the mesh as written (doubles) is checked exactly: the
//                 intersecting faces left, degenerate faces, topology, the
//                 displacement and the Hausdorff distance to the input.
//
// An operation is accepted only under the improvement criteria of §4.1,
// decided exactly by the oracle's local query (inspect/local_index.h): the
// number of intersecting faces strictly decreases and no face that was
// intersection-free becomes intersecting. It is also refused when a face it
// changes becomes degenerate (exactly collinear), turns its normal around
// (unless it was folded against a neighbour before: an inverted sliver may
// turn back), or folds against a neighbour it did not fold against before;
// when it moves a vertex further than the displacement limit or moves a
// pinch-point copy; a swap is refused when it would duplicate an edge. A refused operation is undone
// exactly (the previous exact coordinates and connectivity come back).
//
// Rounding policy (ARCHITECTURE.md, certify after rounding): candidate
// positions are exact constructions (Epeck: intersection points, midpoints,
// averages); the position proposed for a vertex is that point rounded to
// the nearest double, and the criteria are decided on the rounded position.
// So the mesh only ever holds double coordinates, every decision was taken on
// the coordinates that will be written, and rounding the output is the
// identity. The written file is still read back and checked; the CLI runs
// another repair on it if that check ever finds more than the exact mesh had.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "polyheal/inspect/report.h"
#include "polyheal/mesh/soup.h"
#include "polyheal/observer.h"

namespace polyheal {

/// How the face-lifting clearance ε (§4.4) is chosen for a lifted face T.
enum class ClearanceMode {
  edge_relative,    // ε = clearance x the longest edge of T (default 0.02)
  absolute,         // ε = clearance, model units (--clearance D)
  local_thickness,  // §5.2: rays from T's corners along -n; median of the hits
  tet_aspect,       // §5.2: ε = longest edge of T / γ, γ = clearance (--tet-aspect G)
};

struct DeintersectOptions {
  ClearanceMode clearance_mode = ClearanceMode::edge_relative;
  double clearance = 0.02;  // see ClearanceMode
  int max_rounds = 100;
  /// A work budget (0: none): no operation source is tried, and no round
  /// started, after this many trials (DeintersectReport::trials); the
  /// operations found by then are applied. What is left is reported as
  /// still intersecting, with out_of_trials. Deterministic, unlike a time
  /// limit. The repair pipeline sets one (pipeline.cpp: the union follows).
  std::size_t max_trials = 0;
  /// No vertex moves further than this from its input position (model
  /// units; negative: max_displacement_ratio x the bbox diagonal). Faces
  /// that would need more are left and reported.
  double max_displacement = -1.0;
  double max_displacement_ratio = 0.02;
  bool swap = true, hammer = true, lift = true;  // which operations to use (the paper's) ...
  bool group = true, pair = true;                // ... and ours: group and pair moves (deintersect.cpp)
  /// Rounds after the first skip what nothing has changed near since it
  /// was last tried (the same result; false: retry everything, to compare).
  bool skip_unchanged = true;
  bool certify = true;      // certify the rounded result (callers that certify the written file say false)
  /// Every intersecting pair of the input, sorted, when the caller has
  /// found them already (InspectOptions::self_intersections).
  const std::vector<FacePair>* known_pairs = nullptr;
  /// Per input point, whether it must not move (a region cut out of a
  /// larger surface: the corners it shares with the faces outside). The
  /// points must then be distinct (UnsupportedInput otherwise), so that the
  /// result's point i is input point i; pinch copies, which never move
  /// either, follow them.
  const std::vector<char>* fixed_points = nullptr;
  Observer* observer = nullptr;
};

const char* to_string(ClearanceMode mode);

struct DeintersectReport {
  // parameters as used
  ClearanceMode clearance_mode = ClearanceMode::edge_relative;
  double clearance = 0, bbox_diagonal = 0;
  double max_displacement_allowed = 0;
  // input
  std::size_t faces = 0, vertices = 0;
  std::size_t intersecting_faces_in = 0, intersecting_pairs_in = 0, degenerate_faces_in = 0;
  SurfaceTopology topology_in;
  // repair
  std::size_t swaps = 0, hammers = 0, lifts = 0, group_moves = 0, pair_moves = 0;
  std::size_t trials = 0;            // operations tried (cost phases and re-validations)
  std::size_t sources_skipped = 0;   // edges, vertices, faces, groups a cost phase did not retry: nothing near changed
  std::size_t stale = 0;             // cost-phase operations no longer valid when their turn came
  int rounds = 0;
  bool out_of_trials = false;  // stopped by max_trials with faces still intersecting
  std::size_t intersecting_faces_exact = 0;  // left in the working mesh, before writing
  std::size_t moved_vertices = 0;
  double max_displacement = 0, mean_displacement = 0;  // over the moved vertices, model units
  double seconds_detect = 0, seconds_repair = 0, seconds_certify = 0;
  // output, filled by certify() on the soup as written
  std::size_t intersecting_faces_out = 0, intersecting_pairs_out = 0, degenerate_faces_out = 0;
  std::vector<std::size_t> unfreed_faces;  // output face ids still intersecting
  SurfaceTopology topology_out;
  std::size_t faces_changed = 0;  // output faces whose corners differ from the input face's
  double hausdorff = 0;           // symmetric, to the input (-1: not measured)
  double hausdorff_error_bound = 0;
  bool certified = false;  // see certify()
};

struct DeintersectResult {
  Soup soup;  // the output: the input's faces in the input's order
  DeintersectReport report;
};

/// Stages 1-2 and, with options.certify, stage 3 on the rounded result.
/// Throws UnsupportedInput for a soup that is not an oriented 2-manifold
/// triangle mesh (pinch vertices allowed).
DeintersectResult remove_self_intersections(const Soup& input, const DeintersectOptions& options = {});

/// Stage 3 on `written` (the output as read back; `input` as given): fills
/// the output half of `report`. certified = no intersecting face, no more
/// degenerate faces than the input, the same topology.
void certify(const Soup& input, const Soup& written, DeintersectReport& report);

}  // namespace polyheal
