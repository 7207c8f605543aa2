// polyheal — collapsing the edges TetGen would merge (repair --for tetgen).
//
// TetGen merges two points closer than its shortest edge (its -T tolerance
// times the bounding-box diagonal, 'minedgelength'; Report::close_vertices)
// and then stops on the faces that repeat a corner. Exact unions leave such
// points wherever an intersection curve passes within 1e-10 of a vertex or
// several curves meet (regularized raw offsets: chains of twenty points
// within 2e-8 at the corners where strips and patches cross). Here the
// edges shorter than that are collapsed on purpose, shortest first, each
// into its lower-numbered end, which keeps its coordinates (no coordinate is
// computed), where the link condition holds — so the closed 2-manifold keeps
// its topology —, and the result is inspected exactly: the collapses into a
// vertex that a defect involves (a degenerate face, an intersection) are
// refused and the sequence is made again, until nothing is left to refuse.
// Close points that share no edge (two sheets within 1e-8 of each other)
// are not merged: that would change the topology; near_sheets.h pushes them
// apart.
#pragma once

#include <cstddef>

#include "polyheal/mesh/soup.h"

namespace polyheal {

struct ShortEdgeOptions {
  double epsilon = 1e-8;  // TetGen's -T: edges shorter than epsilon x bbox diagonal are collapsed
  int max_rounds = 16;    // inspections, with collapses refused between them
};

struct ShortEdgeReport {
  std::size_t collapses = 0;         // edges collapsed (kept)
  std::size_t faces_removed = 0;     // two a collapse
  std::size_t collapses_undone = 0;  // refused after an inspection found a defect around them
  double max_displacement = 0;       // largest distance from a point to the one it went to
  /// A defect no collapse explains, the topology changed (the link
  /// condition should prevent it), or max_rounds ran out: the input is
  /// returned unchanged.
  bool gave_up = false;
};

/// `clean`: a certified clean surface (closed, 2-manifold, oriented, no
/// degenerate face or intersection). The result is certified clean too
/// (exactly, on its doubles) with the same topology, and its points are
/// only those its faces use.
Soup collapse_short_edges(const Soup& clean, const ShortEdgeOptions& options, ShortEdgeReport& report);

}  // namespace polyheal
