// polyheal — rebuilding dirty faceted geometry into a watertight volume on an
// overlay grid, after Hu, Lee, Blacker & Zhu, "Overlay grid based geometry
// cleanup" (`polyheal rebuild`).
//
// Phase 1 (§3.1): an octree over the bounding box is refined only where its
// cells meet the facets (exact triangle-box tests on the file's doubles),
// down to one cell size (§3.1.3). Each cell is split into its six Kuhn
// tetrahedra, and — §5's "feature-based refinement" — tetrahedra that miss
// the surface (both sides of a part thinner than themselves, or of an acute
// edge: facets more than 120 degrees apart; with all corners outside, the
// rim of a hole) are bisected further, conforming (detail/kuhn_mesh.h), down
// to `refine` halvings of the cell. Tetrahedron
// edges are intersected with the facets exactly (orientation determinants;
// the crossing parameter is an Epeck number), and each crossing keeps its
// facet and group (§3.1.2).
//
// Phase 2 (§3.2) replaces the paper's heuristics for joining edge
// intersections (§3.2.1 Fig. 6-7, §3.2.2 Fig. 8, §3.2.3 Fig. 9, §3.2.5 hole
// loops) by one decision per grid corner: inside or outside the soup, by its
// generalised winding number (Jacobson et al. 2013; evaluated hierarchically,
// Barill et al. 2018). The winding number is ~1 inside and ~0 outside even
// where the soup has gaps, holes and overlaps: a gap or hole is spanned by
// the smooth 1/2 level, an overlap counts once. The surface is then the
// boundary of the inside corners in the grid's conforming tetrahedra (each
// cube's six Kuhn tetrahedra sharing its main diagonal, some bisected;
// marching tetrahedra), so it is closed, 2-manifold and oriented by
// construction — there are no ambiguous faces to resolve (§3.2.1), no
// single-intersection faces (§3.2.2) and no
// open loops (§3.2.3) — and, its vertices lying strictly inside distinct
// tetrahedron edges, free of self-intersections. A vertex sits at the facet
// crossing of its grid edge where there is one (the crossing leaving the
// inside, the outermost of several: overlapping facets count once), else —
// across a gap or hole — where the winding number interpolates to 1/2
// (Fig. 8's interpolation, and §3.2.5's virtual faces).
//
// Cells: --cell (absolute or relative to the diagonal); by default 1% of the
// bounding-box diagonal, raised to twice the largest gap found between
// boundary edges (§3.1.3: cells must be larger than the largest gap).
// Output faces are grouped (§3.2.4) by the input group their vertices'
// facets carry (OBJ groups, STL solids), or else by a feature angle.
// Planar regions are coarsened exactly: a vertex whose whole star lies in
// one plane is collapsed away when the fan that replaces it tiles the same
// polygon (the surface, as a point set, is unchanged). Vertices near sharp
// edges and corners of the input move onto them (§5 Fig. 15: the facet
// planes' exact intersection). The rest is decimated by halfedge collapses
// within a quarter cell of the extracted surface, each checked exactly for
// self-intersection by the oracle's local query (§5: fewer faces).
// Facets that bound no volume — the winding number is at most 1/2 on both
// sides: open sheets, double-sided sheets, stray triangles — are wrapped in a
// shell one cell thick on each side (`sheets`), so that no part of the input
// is dropped; with sheets off they are left out and reported lost (§3.2.7: a
// soup that encloses nothing then has no volume, and nothing is invented).
// Clean regions keep their facets exactly (beyond §5): facets far from every
// defect form patches zipped to the grid surface, each patch given up when
// the exact oracle finds the joined surface wanting (rebuild.cpp,
// keep_clean_regions). An input that is already certified clean comes out
// unchanged.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "polyheal/mesh/soup.h"
#include "polyheal/observer.h"

namespace polyheal {

struct RebuildOptions {
  double cell = -1;            // cell size, model units; <= 0: see cell_ratio
  double cell_ratio = -1;      // cell size as a fraction of the bbox diagonal; <= 0: the default rule
  int refine = 2;              // halvings of the cell where the grid misses the surface (0: uniform cells)
  double feature_angle = 30;   // degrees: grouping output faces when the input has no groups
  bool keep_clean = true;      // a certified clean input is returned unchanged, and one that the
                               // exact cleanup closes returned cleaned (RebuildReport::cleaned)
  bool keep_regions = true;    // keep input facets far from every defect, zipped to the grid surface
  // More defects, the caller's (repair --for tetgen: what TetGen's tolerances
  // stop on): no input facet within two cells of these triangles is kept.
  std::vector<std::array<Point3d, 3>> avoid;
  bool sheets = true;          // wrap facets that bound no volume in a shell (false: leave them out, reported lost)
  double sheet_shell = 0.9;    // the shell's half-thickness, in cells (above sqrt(3)/2: see rebuild())
  bool wrap_outlying = true;   // with sheets: wrap what is still 0.6 cell outside the surface in the shell too
  bool simplify = true;        // collapse vertices inside planar regions (exact, surface unchanged)
  bool decimate = true;        // then collapse vertices elsewhere, within decimate_tolerance (see below)
  double decimate_tolerance = 0.25;  // fraction of the cell: distance of new faces to the extracted surface
  /// Large surfaces are decimated in two halves at once (rebuild.cpp,
  /// sweep_in_halves()); false: the halves' sweeps one after the other on the
  /// whole surface — the same result, slower (for tests).
  bool halves_in_parallel = true;
  bool sharpen = true;         // move vertices near sharp edges and corners onto them (before decimating)
  bool certify = true;         // inspect the result and measure the Hausdorff distance
  std::size_t max_cells = 20'000'000;  // refuse a finer grid (UnsupportedInput)
  Observer* observer = nullptr;
};

/// Where something is: how many (edges of a loop, faces of a component)
/// and their bounding box.
struct Region {
  std::size_t count = 0;
  Point3d lo{}, hi{};
};

struct Topology;

/// Each connected component of `welded` (by topo.face_component): its face
/// count and bounding box.
std::vector<Region> component_regions(const Soup& welded, const Topology& topo);

struct RebuildReport {
  // input
  std::size_t faces = 0, vertices = 0, groups = 0;
  std::size_t zero_area_faces = 0;      // left out: they bound nothing
  std::size_t reoriented_faces = 0;     // flipped to agree with their component (inconsistent input)
  std::size_t inside_out_faces = 0;     // of components facing inwards (inside out; a cavity of one), turned
  std::size_t duplicate_faces = 0;      // copies of a face left out (resolve_duplicate_faces())
  std::size_t stitched_edges = 0;       // border edges joined to their match (cleanup only)
  std::size_t boundary_loops = 0;       // of the welded input
  std::vector<Region> open_loops;       // each of them: its edges and where
  std::size_t sheet_facets = 0;         // facets bounding no volume (winding <= 1/2 on both sides)
  std::size_t thin_facets = 0;          // facets of parts thinner than a cell, wrapped in the shell too
  std::size_t outlying_pieces = 0;      // pieces of facets still 0.6 cell outside the surface: shelled
  double shell = 0;                     // half-thickness of the shell they are wrapped in (0: none)
  double diagonal = 0;
  double largest_gap = 0;               // between boundary edges of different loops (estimate)
  // grid
  double cell = 0;
  std::string cell_rule;                // how `cell` was chosen
  int depth = 0;                        // octree levels below the root
  std::size_t octree_nodes = 0;         // cells visited while refining
  std::size_t boundary_cells = 0;       // leaf cells meeting the facets
  std::size_t closure_cells = 0;        // cells added where the 1/2 level leaves the facets (gaps, holes)
  int halvings = 0;                     // how far the cell may be halved (options.refine, within the lattice)
  std::size_t refined_tets = 0;         // tetrahedra found missing the surface, and bisected
  std::size_t bisections = 0;           // ... with those conformity needed
  std::size_t leaf_tets = 0;            // tetrahedra of the final grid
  int finest_level = 0;                 // deepest bisection level (3 levels halve the cell)
  std::size_t thickened_corners = 0;    // corners within a finest step of a part thinner than that: inside
  std::size_t corners = 0, inside_corners = 0;
  std::size_t crossed_edges = 0;        // grid edges whose corners differ
  std::size_t facet_crossings = 0;      // ... with a vertex on a facet
  std::size_t interpolated = 0;         // ... across a gap or hole
  // output
  bool unchanged = false;               // input was already clean
  bool cleaned = false;                 // closed by the exact cleanup alone (no grid; zero_area_faces,
                                        // duplicate_faces, reoriented_faces and stitched_edges tell what it did)
  bool volume = false;                  // some corner is inside
  std::size_t beads_dropped = 0;        // tiny extracted components another component already stands for
  std::size_t extracted_faces = 0;      // before simplification
  std::size_t kept_faces = 0;           // input facets kept as they are (clean regions)
  std::size_t kept_patches = 0;         // ... in this many patches, zipped to the grid surface
  std::size_t patches_given_up = 0;     // clean patches the zipper could not join (grid surface there)
  std::size_t collapses = 0;            // planar vertices removed
  std::size_t coarsening_retries = 0;   // coarsenings found folded (exactly) and done again, more held back
  std::size_t decimated = 0;            // vertices removed by decimation
  std::size_t sharpened = 0;            // vertices moved onto sharp edges and corners
  std::size_t faces_out = 0, vertices_out = 0, components_out = 0, face_groups = 0;
  // certification (of the result as rounded to doubles)
  bool certified = false;
  bool closed = false, manifold = false, oriented = false;
  std::size_t self_intersections = 0, degenerate = 0;
  double hausdorff = -1, hausdorff_error_bound = 0;  // symmetric, to the input (-1: not measured)
  double input_to_output = -1;   // one-sided: how far the input is from the output (detail lost)
  double output_to_input = -1;   // one-sided: how far the output is from the input (gap and hole fills)
  // Input the output does not represent (every corner farther than two cells
  // from it): open sheets and fins that enclose nothing. A component lost
  // whole is never certified: nothing is dropped silently.
  std::size_t lost_faces = 0, lost_components = 0;
  std::size_t absorbed_faces = 0;  // far from the output but inside it (inner walls, enclosed parts)
  double lost_area_fraction = 0;
  std::vector<Region> lost_regions;  // each component lost whole: its faces and where
  // seconds
  double seconds_prepare = 0, seconds_octree = 0, seconds_winding = 0, seconds_extract = 0, seconds_refine = 0,
         seconds_simplify = 0, seconds_certify = 0;
};

struct RebuildResult {
  Soup soup;
  RebuildReport report;
};

/// Rebuilds `input` (any soup: polygons are fanned). Throws UnsupportedInput
/// when the grid would exceed options.max_cells.
RebuildResult rebuild(const Soup& input, const RebuildOptions& options = {});

/// Certifies `written` (the result as read back from the file) against
/// `input`: fills the report's certification fields. Certified: closed,
/// 2-manifold, oriented, no degenerate face or self-intersection, some volume,
/// and no input component lost.
/// Input faces whose corners are all farther than `far` from `written`,
/// split by whether they lie outside the written surface's volume (lost) or
/// inside it (absorbed: inner walls, enclosed parts; generalised winding
/// number of the written faces); and the input components none of whose
/// faces is within `far`, split the same way (absorbed when some of their
/// faces are inside). A measurement in doubles, not a certificate.
struct Loss {
  std::size_t lost_faces = 0, absorbed_faces = 0;
  std::size_t lost_components = 0, absorbed_components = 0;
  double lost_area_fraction = 0;
  std::vector<Region> lost_regions;  // per component lost whole
  std::vector<char> absorbed;  // per input face
  double outside_distance = 0; // from the input outside the written volume to the written surface (error 5% of far)
};
/// `outside` asks for outside_distance too (the costly part; 0 otherwise). `certified`: the
/// written surface is closed, oriented, manifold and intersects nothing (a faster inside test).
Loss measure_loss(const Soup& input, const Soup& written, double far, bool outside = false, bool certified = false);

void certify_rebuild(const Soup& input, const Soup& written, RebuildReport& report);

}  // namespace polyheal
