// polyheal — pushing apart what TetGen's tolerance would join (repair --for
// tetgen).
//
// A clean surface can still hold two sheets closer than TetGen's shortest
// edge (its -T tolerance times the bounding-box diagonal) without sharing
// anything there: parts of an assembly lying face to face 1e-10 apart, a
// vertex of one part just over a face of another, two edges crossing 1e-10
// apart. TetGen then merges what it cannot tell apart and stops. No
// collapse or flip changes that, and collapsing applies only where two
// vertices share a short edge (short_edges.h). Here each
// vertex that such a pair involves moves a little — twice the tolerance —
// away from the other simplex, along the direction that separates them
// (the side is decided by an exact orientation; the move itself is a double
// construction), and the result is inspected exactly: a vertex whose move
// makes a face intersect another or degenerate moves back and stays. Rounds
// repeat on what is still too close (a face lies tilted once only one of its
// corners has moved) until nothing is left or nothing moves.
#pragma once

#include <cstddef>

#include "polyheal/mesh/soup.h"

namespace polyheal {

struct Report;

struct SeparateOptions {
  double epsilon = 1e-8;  // TetGen's -T, relative to the bbox diagonal
  double step = 2;        // each move, in units of epsilon x diagonal
  int max_rounds = 8;     // inspections (moves, and moves refused, between them)
};

struct SeparateReport {
  std::size_t pairs_before = 0;    // vertex-face, edge-edge, vertex-vertex and vertex-edge pairs closer than the tolerance
  std::size_t pairs_after = 0;
  std::size_t moved_vertices = 0;  // vertices that moved (kept)
  std::size_t refused = 0;         // moves undone: they made a face intersect or degenerate
  double max_displacement = 0;     // largest distance a vertex moved
  int rounds = 0;
};

/// The pairs of `r` (inspected with TetGen's segments) this works on:
/// vertex-face, edge-edge, vertex-vertex and vertex-edge pairs closer than
/// TetGen's shortest edge.
std::size_t close_pair_count(const Report& r);

/// `clean`: a certified clean surface; `known`, when given, its inspection
/// with TetGen's segments (InspectOptions::tetgen_segments, epsilon as in
/// `options`): not made again. The result is certified clean too (exactly,
/// on its doubles), with the same faces (the same corners, some of them
/// moved); pairs_after tells what is still too close.
Soup separate_near_sheets(const Soup& clean, const SeparateOptions& options, SeparateReport& report,
                          const Report* known = nullptr);

}  // namespace polyheal
