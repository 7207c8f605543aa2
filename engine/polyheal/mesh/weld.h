// polyheal — welding identical points.
#pragma once

#include <cstddef>
#include <vector>

#include "polyheal/mesh/soup.h"

namespace polyheal {

/// Maps each point to the smallest index of a point with the same value
/// (x, y, z compared as doubles, so +0.0 and -0.0 weld; NaN never occurs
/// because readers reject it). `representative[i] == i` for points kept.
struct Weld {
  std::vector<Index> representative;
  std::size_t merged = 0;  // points that had an identical earlier twin
};

Weld weld_identical_points(const std::vector<Point3d>& points);

/// The soup with every face index replaced by its representative. Points are
/// kept (unreferenced twins stay as isolated points, so indices stay valid).
Soup apply_weld(const Soup& soup, const Weld& weld);

/// Representatives after merging points closer than `d`, starting from
/// `identical` (weld_identical_points' representatives; only their
/// representatives are compared): a grid of cell d, distances in doubles
/// (a choice, not a certificate: callers check what the weld makes), and
/// clusters by union-find, so a chain can move a point further than d.
/// The representative is the cluster's first point. `merged` counts the
/// points given another representative, `max_move` their largest distance
/// to it.
std::vector<Index> weld_near_points(const std::vector<Point3d>& pts, const std::vector<Index>& identical, double d,
                                    std::size_t& merged, double& max_move);

}  // namespace polyheal
