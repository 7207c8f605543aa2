// polyheal — the exact inspection report: everything `polyheal check` says.
//
// inspect() welds identical points, then decides every geometric question
// exactly on the soup's double coordinates (predicates.h, triangle_pair.h).
// Degenerate, cap and needle faces follow Botsch & Kobbelt §2: a cap has an
// angle above cap_angle, a needle an angle below needle_angle and is not a
// cap; a degenerate face has a repeated vertex or exactly collinear corners
// and is neither.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "polyheal/inspect/self_intersections.h"
#include "polyheal/mesh/soup.h"
#include "polyheal/observer.h"

namespace polyheal {

struct InspectOptions {
  double cap_angle = 175.0;        // degrees; a face with a larger angle is a cap
  double needle_angle = 5.0;       // degrees; a face with a smaller angle is a needle (unless a cap)
  double tetgen_fold_angle = 0.1;  // degrees; TetGen's "nearly self-intersecting facets" bound
  double tetgen_epsilon = 1e-8;    // TetGen's relative tolerance (-T): near-collinear faces
  double tetgen_facet_angle = 179.9;  // degrees; TetGen -p merges adjacent faces flatter than this (facet_ang_tol)
  /// Also search for vertices nearly on an edge they are not on (TetGen's
  /// segment recovery stops on them): a spatial search over all edges and
  /// points, about half a second per million faces on 2 cores, so asked
  /// for; tetgen_ready() requires it.
  bool tetgen_segments = false;
  /// Intersecting pairs with corners closer than this times the bbox
  /// diagonal (but not identical) are counted as cracks (Report::crack_pairs);
  /// the same distance as `degenerate`'s and `repair`'s default weld.
  double crack_ratio = 1e-9;
  bool parallel = true;            // TBB in the self-intersection pass
  /// Every intersecting pair of the input, sorted, when the caller knows
  /// them already (found by find_self_intersections on the same soup): not
  /// searched for again. Ignored when the input has identical points (the
  /// report's pass runs on the welded soup).
  const std::vector<FacePair>* self_intersections = nullptr;
  Observer* observer = nullptr;
};

struct EdgeRef {
  Index a, b;                       // welded vertex ids, a < b
  std::vector<std::size_t> faces;   // faces using the edge
};

struct Report {
  // counts
  std::size_t vertices = 0;             // points in the file
  std::size_t faces = 0;
  std::size_t non_triangle_faces = 0;
  std::size_t components = 0;           // faces connected through shared edges
  std::size_t isolated_vertices = 0;    // points no face uses (after welding)
  std::size_t merged_identical_vertices = 0;
  // topology (after welding identical points)
  std::vector<EdgeRef> boundary_edges;
  std::size_t boundary_loops = 0;
  std::vector<EdgeRef> nonmanifold_edges;
  std::vector<Index> nonmanifold_vertices;
  std::vector<EdgeRef> misoriented_edges;
  std::vector<std::array<std::size_t, 2>> duplicate_faces;
  // geometry, decided exactly
  std::vector<std::size_t> degenerate_faces;
  std::vector<std::size_t> caps;
  std::vector<std::size_t> needles;
  std::vector<FacePair> self_intersections;
  /// Self-intersecting pairs (f, g) where a corner of f and a corner of g
  /// are closer than InspectOptions::crack_ratio x the bbox diagonal but
  /// not the same point: the cracks a CAD export's rounding leaves (its
  /// STL writes a shared vertex twice, 1e-16 apart), whose two sides meet
  /// exactly. A hint, not a verdict: such a pair is a self-intersection.
  std::size_t crack_pairs = 0;
  /// The distinct corner pairs that close among those faces' corners.
  std::size_t crack_vertex_pairs = 0;
  // TetGen's tolerances (not exact defects)
  std::vector<FacePair> sharp_folds;             // adjacent faces folded below tetgen_fold_angle
  std::vector<std::size_t> nearly_degenerate_faces;
  std::vector<VertexNearEdge> vertices_near_edges;  // welded ids; a vertex within tetgen_epsilon of an edge
  bool vertices_near_edges_checked = false;         // InspectOptions::tetgen_segments
  /// Adjacent faces TetGen merges into one facet (dihedral angle above
  /// tetgen_facet_angle, less a margin of 0.001 deg for its rounding) that
  /// are not coplanar, and whose flipped diagonal would cut another face
  /// (self_intersections.h find_flip_hazards). Searched for with
  /// vertices_near_edges.
  std::vector<FacePair> flip_hazards;
  /// Welded ids (a < b) closer than tetgen_epsilon x the bbox diagonal:
  /// TetGen merges them ("very short edge"), its faces then repeat a corner
  /// and it stops. Searched for with vertices_near_edges.
  std::vector<std::array<Index, 2>> close_vertices;
  /// Edges sharing no vertex closer than that (self_intersections.h
  /// find_edges_near_edges): TetGen's Steiner points on them would be.
  std::vector<EdgeNearEdge> edges_near_edges;
  /// Vertices closer than that to a face they are not a corner of
  /// (find_vertices_near_faces).
  std::vector<VertexNearFace> vertices_near_faces;
  /// Set by a caller that ran TetGen itself on this surface and saw it fail
  /// (repair --for tetgen); inspect() never sets it.
  bool tetgen_refused = false;
  // shape
  bool closed = false, manifold = false, oriented = false;
  double signed_volume = 0.0;  // double sum of tetrahedra; meaningful when closed and oriented
  // Closed and oriented only (0 otherwise), exact: the sign of the enclosed
  // volume, and the components whose own volume is negative (faces pointing
  // inwards: a cavity if inside another component, else inside out).
  int volume_sign = 0;
  std::size_t inward_components = 0;
  // Certified clean with inward components only (inspect/nesting.h, exact):
  // of those, inside no other component (inside out) or inside one (cavities).
  bool nesting_checked = false;
  std::size_t inside_out_components = 0, cavities = 0;
  std::array<double, 3> bbox_min{}, bbox_max{};
  // time per stage, seconds
  double seconds_topology = 0, seconds_shape = 0, seconds_self_intersections = 0;

  /// Closed, 2-manifold, consistently oriented, no degenerate face, no
  /// duplicate face, no self-intersection, at least one face.
  bool certified_clean() const;
  /// certified_clean() but for self-intersections (those not asked about).
  bool clean_but_for_crossings() const;
  /// certified_clean() and nothing TetGen's tolerances would trip over
  /// (false unless inspected with InspectOptions::tetgen_segments), and not
  /// refused by TetGen itself where it was run.
  bool tetgen_ready() const {
    return certified_clean() && sharp_folds.empty() && nearly_degenerate_faces.empty() &&
           vertices_near_edges_checked && vertices_near_edges.empty() && close_vertices.empty() &&
           edges_near_edges.empty() && vertices_near_faces.empty() && flip_hazards.empty() &&
           !tetgen_refused;
  }
};

Report inspect(const Soup& soup, const InspectOptions& options = {});

/// inspect(soup, options) for a soup made from `base`, whose intersecting
/// pairs are known (every one, as inspect(base) reports them): the
/// self-intersection search covers only the faces of soup that are not
/// triangles of base by their corners' coordinates
/// (find_self_intersections_from), and takes the pairs among the others
/// from base's — the same exact test on the same coordinates. The whole
/// soup is searched where more than an eighth of its faces differ, or it
/// has identical points. `searched`, when given, receives how many faces
/// the search covered. A certificate of a written file that keeps most of
/// a surface searched before (regularize: its input, or the rounded
/// surface).
Report inspect_from(const Soup& soup, const Soup& base, const std::vector<FacePair>& base_pairs,
                    InspectOptions options = {}, std::size_t* searched = nullptr);

/// Topological invariants compared between input and output.
struct SurfaceTopology {
  long euler = 0;                // V - E + F
  std::size_t components = 0, boundary_loops = 0;
  bool manifold = false;
  bool operator==(const SurfaceTopology& o) const {
    return euler == o.euler && components == o.components && boundary_loops == o.boundary_loops &&
           manifold == o.manifold;
  }
};

/// The invariants of an inspected triangle soup (Euler characteristic from
/// the welded vertices, faces and edges).
SurfaceTopology topology_of(const Report& report);

/// Length of the diagonal of the report's bounding box (the scale the
/// repairs' relative tolerances and reports refer to).
double bbox_diagonal(const Report& report);

}  // namespace polyheal
