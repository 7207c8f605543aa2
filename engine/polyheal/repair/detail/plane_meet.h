// polyheal — where the planes of two or three triangles meet, exactly, rounded
// once to doubles (rebuild's sharpening, Hu et al. §5 / Fig. 15).
//
// The planes' normals and offsets are polynomials in the corners' doubles,
// computed exactly without normalisation (Mpzf, exact_meet.h); one rational
// division per coordinate at the end, rounded to the nearest double (ties to
// even). The same point as Epeck's Plane_3 intersection (three planes) or
// Line_3 projection (two), correctly rounded, without evaluating their lazy
// trees (hornbug: 0.3 s of a 0.5 s sharpening). Defined in rebuild.cpp, its
// user; declared here, without CGAL, for the test against Epeck.
#pragma once

#include <array>

#include "polyheal/mesh/soup.h"

namespace polyheal::detail {

using Triangle3d = std::array<Point3d, 3>;

enum class Meeting { point, none, degenerate };

/// The point common to the planes of a, b and c, rounded; `none` when they
/// do not meet in one point, `degenerate` when a triangle has no normal.
Meeting planes_meet(const Triangle3d& a, const Triangle3d& b, const Triangle3d& c, Point3d& out);
/// The point of the line where the planes of a and b meet nearest to p,
/// rounded; `none` when the planes are parallel.
Meeting nearest_on_planes_line(const Triangle3d& a, const Triangle3d& b, const Point3d& p, Point3d& out);

}  // namespace polyheal::detail
