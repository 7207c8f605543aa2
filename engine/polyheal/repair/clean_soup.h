// polyheal — soup-level cleanup: the combinatorial defects of a triangle
// soup, fixed without moving a coordinate (except the optional near weld).
//
// The first stage of `polyheal repair` (issue 7): weld identical (and, on
// request, near-identical) vertices; drop faces that repeat a vertex index
// and duplicate faces (a pair of opposite copies cancels, as it does in the
// generalised winding number, unless one copy is a face the surface around
// needs and the other a stray copy; copies of one orientation keep one); orient
// each component consistently (CGAL's orient_polygon_soup, which also splits
// non-manifold vertices and edges); stitch matching borders; fill holes
// (CGAL's triangulate_hole: no new vertex). Before stitching, T-junction
// cracks close: a boundary vertex within `t_junction` of a boundary edge's
// interior splits that edge's face at the vertex (the crack a CAD export
// leaves where one side of a seam has the edge a-b and the other a-v-b),
// and vertices closer than `t_junction` weld (a crack of zero length).
// Faces keep their input corners bit for bit; hole fills and T-junction
// splits are new faces on existing vertices.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "polyheal/mesh/soup.h"

namespace polyheal {

struct CleanSoupOptions {
  double weld = 0;                // model units: also merge vertices closer than this (0: identical only)
  double t_junction = 0;          // model units: split a boundary edge at a boundary vertex this close
                                  // to its interior, and weld vertices this close (0: exactly on it only)
  bool orient = true;             // orient components consistently
  bool fill_holes = true;         // triangulate every boundary loop
  std::size_t max_hole_edges = 0; // leave loops with more edges open (0: no limit)
  bool only_if_closed = false;    // return an empty soup (before orienting) unless every edge has two
                                  // faces and every vertex one fan (holes are not filled then)
};

struct CleanSoupReport {
  std::size_t faces_in = 0, polygons_fanned = 0;
  std::size_t identical_vertices_welded = 0, near_vertices_welded = 0;
  double max_weld_move = 0;                  // model units: largest move of a near-welded vertex
  std::size_t repeated_index_faces = 0;      // dropped
  std::size_t t_junctions = 0;               // boundary vertices inserted into a boundary edge
  std::size_t duplicate_faces_dropped = 0;   // same-orientation copies beyond the first
  std::size_t cancelled_faces = 0;           // opposite copies removed in pairs
  std::size_t opposite_copies_kept = 0;      // cancelling groups given one copy back: the surface around needed it
  std::size_t reoriented_faces = 0;
  std::size_t split_vertices = 0;            // copies orient_polygon_soup made (non-manifold points)
  std::size_t stitched_edges = 0;
  std::size_t holes = 0, holes_filled = 0, hole_faces = 0;
  std::size_t holes_left = 0;                // over max_hole_edges, or that triangulate_hole refused
  std::size_t faces_out = 0;
};

struct CleanSoupResult {
  Soup soup;                         // triangles; points are input points (or near-weld representatives)
  std::vector<std::int64_t> source;  // per output face: the input face it came from, -1 for hole fills
  CleanSoupReport report;
};

/// Which duplicate faces go, as clean_soup() decides (the file comment):
/// copies of one vertex set (`tris`: welded vertex ids), opposite ones
/// cancelling in pairs, one copy kept of the prevailing orientation, and a
/// cancelled group given one copy back where the surface around it needs
/// exactly that copy (a closed surface given a reversed stray copy keeps
/// its face). `keep_sheets`: a cancelled group given nothing back keeps all
/// its copies instead (a double-sided sheet, which the overlay grid wraps).
struct DuplicateFaces {
  std::vector<char> keep;          // per triangle
  std::size_t dropped = 0;         // same-orientation copies beyond the first (and a group's given one back)
  std::size_t cancelled = 0;       // opposite copies removed in pairs
  std::size_t opposite_kept = 0;   // cancelling groups given one copy back
};
DuplicateFaces resolve_duplicate_faces(const std::vector<std::array<Index, 3>>& tris, bool keep_sheets);

/// See the file comment. Never throws on a valid soup; an empty input gives
/// an empty result.
CleanSoupResult clean_soup(const Soup& input, const CleanSoupOptions& options = {});

}  // namespace polyheal
