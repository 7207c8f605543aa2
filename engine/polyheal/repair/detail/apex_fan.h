// polyheal — a graded triangulation of an apex fan (a CAD cone's tip: n
// triangles (a, b_i, b_{i+1}) around one vertex, each a needle at a).
//
// Botsch & Kobbelt's operations do not reach such a fan. Every triangle at a
// needs an angle of at least the needle angle there, so a can keep at most
// (total angle at a) / (needle angle) faces: a 100-segment cone of half
// angle 45 degrees at most 50, a tall 30-segment cone 3. Collapsing spokes
// into each other moves the surface by the chord's sagitta, far beyond the
// tolerance away from a; and cuts across one wedge (the §5 supersampling
// of degenerate.cpp's cut_wedge) leave the tips of the others.
//
// The plan: rings of points on the spokes at radii falling inward, every
// spoke on the outer rings and every other one further in (a quadtree-like
// grading), coarsened only where the chords between the spokes kept stay
// within half the tolerance of the fan (so the fewer spokes near a), and a
// fan of the spokes left at a, whose angles there clear the needle angle.
// Between two rings with the same spokes each sector gets a trapezoid (two
// triangles), at most about five times longer than wide; between a ring and
// its coarsening, each kept pair of spokes gets the fan of the outer points
// from its two ends. Computed on doubles: it only proposes; the decimation
// (ShapeDecimator::replace_star) checks every triangle exactly.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <vector>

#include "polyheal/mesh/soup.h"

namespace polyheal::detail {

struct ApexFanPlan {
  /// New points on the spokes, each a + (link[s] - a) t for its spoke s
  /// and fraction t (in doubles). Vertex ids of `triangles`: 0 is the apex,
  /// 1 + i is link[i], and 1 + n + k is points[k] (n = link.size()).
  std::vector<Point3d> points;
  /// Where the apex goes: a itself unless the cone is too narrow (moved).
  Point3d apex{};
  bool moved = false;
  std::vector<std::array<std::size_t, 3>> triangles;  // oriented as the fan's (a, b_i, b_{i+1})
  /// Per triangle, the fan sectors (sector i: a, b_i, b_{i+1}) it spans, from first to last (cyclic).
  std::vector<std::array<std::size_t, 2>> sectors;
  std::size_t rings = 0;
};

/// The plan for the fan of apex `a` whose link (the other corners, in the
/// faces' order: face i is (a, link[i], link[i + 1 mod n])) is given; the
/// tolerance is the distance it may move the surface; angles in degrees.
/// Nothing when the fan is no apex fan it can serve (fewer than four
/// spokes, a spoke too short, too many rings). A fan whose gaps clear the
/// needle angle already is its own plan (no rings: a new centre's fan).
std::optional<ApexFanPlan> plan_apex_fan(const Point3d& a, const std::vector<Point3d>& link, double tolerance,
                                         double needle_angle, double cap_angle);

}  // namespace polyheal::detail
