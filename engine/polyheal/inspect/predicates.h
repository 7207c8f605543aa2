// polyheal — exact geometric predicates on double coordinates.
//
// Every function here returns the exact answer for the given doubles: values
// are evaluated in interval arithmetic and, when the interval cannot decide,
// again in exact rationals (the geogram/CGAL filter pattern). Angle thresholds
// enter as the double nearest to cos(threshold); the comparison against that
// double is exact. No CGAL in this header.
#pragma once

#include "polyheal/mesh/soup.h"

namespace polyheal {

/// Botsch & Kobbelt §2 classes of a triangle. A cap has an angle above the cap
/// threshold; a needle an angle below the needle threshold and no cap angle;
/// a degenerate triangle has exactly collinear (or repeated) corners.
enum class Shape : char { fine, degenerate, cap, needle };

/// Angle thresholds are given in degrees and enter the predicates as cosines
/// (or sines); one conversion for every caller.
double cos_degrees(double degrees);
double sin_degrees(double degrees);

/// Classifies triangle abc exactly; thresholds enter as cosines.
Shape classify_triangle(const Point3d& a, const Point3d& b, const Point3d& c, double cos_cap, double cos_needle);

/// True when a, b, c are exactly collinear (including repeated points).
bool is_collinear(const Point3d& a, const Point3d& b, const Point3d& c);

/// True when the angle at `apex` between rays to `b` and `c` is strictly
/// greater (resp. smaller) than the angle whose cosine is `cos_threshold`.
/// Precondition: b != apex and c != apex.
bool angle_greater(const Point3d& apex, const Point3d& b, const Point3d& c, double cos_threshold);
bool angle_less(const Point3d& apex, const Point3d& b, const Point3d& c, double cos_threshold);

/// Faces (p, q, r) and (q, p, s) share the edge pq. True when the fold angle
/// between them (0 when folded flat onto each other, 180 when the surface is
/// flat) is strictly below the threshold. Precondition: neither is degenerate.
bool fold_angle_less(const Point3d& p, const Point3d& q, const Point3d& r, const Point3d& s, double cos_threshold);

/// True when p lies within eps * |ab| of segment ab's line (and not exactly
/// on it), its projection strictly between a and b: a vertex TetGen would
/// take for lying on the segment (its relative tolerance -T, 1e-8 by
/// default) without it being there.
bool is_nearly_on_segment(const Point3d& p, const Point3d& a, const Point3d& b, double eps);

/// TetGen's flip test in a facet (1.5.0 lawsonflip / incircle3d) on faces
/// (p, q, r) and (q, p, s): it flips edge pq when, about the circumcircle of
/// the larger face, the other face's apex lies inside by more than its
/// relative tolerance: (|cx| - rad) / rad < -eps, computed in doubles. True
/// when that cannot happen: about each face's circumcircle the other apex
/// lies exactly at |cx| > (1 - eps / 2) rad (the margin eps / 2 covers TetGen's
/// rounding), and each face is shaped well enough for that rounding bound
/// (|n|^2 >= 1e-6 longest_edge^4, n the face normal: TetGen's circumcentre
/// then has a relative error below ~1e-10). A cocircular quad (a grid's
/// rectangle) is kept; a fourth point inside is not.
bool tetgen_keeps_edge(const Point3d& p, const Point3d& q, const Point3d& r, const Point3d& s, double eps);

/// True when segments ab and cd are strictly closer than `tol` (exactly:
/// their squared distance < tol^2 on the doubles given).
bool segments_closer_than(const Point3d& a, const Point3d& b, const Point3d& c, const Point3d& d, double tol);

/// True when every corner of triangle abc is certainly at least `tol` from
/// the line through the other two (twice its area, computed in doubles with
/// a bound on the rounding, exceeds `tol` times its longest side), so no
/// corner is closer than `tol` to the opposite side: segments_closer_than(a,
/// a, b, c, tol) and the two like it are false. False when that is not
/// certain (a sliver, or magnitudes near overflow or underflow).
bool corners_clear_of_sides(const Point3d& a, const Point3d& b, const Point3d& c, double tol);

/// True when point p is strictly closer than `tol` to triangle abc (exactly:
/// squared distance < tol^2 on the doubles given; a degenerate abc as the
/// segments it is).
bool point_closer_than_to_triangle(const Point3d& p, const Point3d& a, const Point3d& b, const Point3d& c, double tol);

/// Exact sign of det[b - a, c - a, d - a] (CGAL::orientation of the doubles
/// given): +1, 0 or -1 as d lies on one side of plane abc, on it, or on the
/// other.
int orientation_sign(const Point3d& a, const Point3d& b, const Point3d& c, const Point3d& d);

/// True when p and q are distinct and strictly closer than `tol` (exactly:
/// |pq|^2 < tol^2 on the doubles given): TetGen merges two such points
/// when tol is its shortest allowed edge (-T times the bbox diagonal).
bool is_closer_than(const Point3d& p, const Point3d& q, double tol);

/// True when p projects strictly between a and b, lies farther than `tol`
/// from both, and within `tol` of the line ab (absolute; tol 0: exactly on
/// it): a T-junction vertex of edge ab.
bool lies_along_segment(const Point3d& p, const Point3d& a, const Point3d& b, double tol);

/// True when triangle abc is not exactly degenerate but its area is tiny
/// relative to its longest edge: |ab x ac| <= eps * longest_edge^2 (TetGen's
/// relative collinearity tolerance, eps = 1e-8 by default).
bool is_nearly_degenerate(const Point3d& a, const Point3d& b, const Point3d& c, double eps);

/// Sign of the volume that faces `faces` of `soup` enclose (the sum of the
/// determinants (a-o) . ((b-o) x (c-o)) over their fan triangles, o the
/// centre of their bounding box), exactly: intervals, then rationals.
/// Meaningful for a closed, oriented set of faces: positive when they face
/// outwards, negative inwards (a cavity, or inside out); for others a
/// guess that does not change when the faces are moved far away.
int enclosed_volume_sign(const Soup& soup, const std::vector<std::size_t>& faces);
/// The same over every face of `soup`.
int enclosed_volume_sign(const Soup& soup);

}  // namespace polyheal
