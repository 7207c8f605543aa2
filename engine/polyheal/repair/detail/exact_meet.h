// polyheal — where lines and planes through input doubles meet, exactly, as
// homogeneous points: ring operations on the doubles' values (Mpzf, no
// normalisation, no gcd), and one division per coordinate by whoever needs a
// rational (regularize's exact points) or a double (rebuild's sharpening,
// plane_meet.h). Cheaper than the same construction through Epeck's lazy
// tree, whose exact evaluation normalises a rational at every step.
//
// CGAL's Mpzf and kernel: include only from the CGAL-heavy translation units.
#pragma once

#include <CGAL/Mpzf.h>
#include <CGAL/Simple_cartesian.h>
#include <gmpxx.h>

#include <array>

#include "polyheal/repair/detail/plane_meet.h"

namespace polyheal::detail {

using Z = CGAL::Mpzf;
using Z3 = CGAL::Simple_cartesian<Z>::Vector_3;

/// The point num / den (den != 0).
struct Homogeneous {
  Z3 num;
  Z den;
};

/// h's coordinates as exact rationals: one division each.
inline std::array<mpq_class, 3> rationals(const Homogeneous& h) {
  const mpq_class den(h.den);
  return {mpq_class(h.num.x()) / den, mpq_class(h.num.y()) / den, mpq_class(h.num.z()) / den};
}

inline Z3 exact_vector(const Point3d& q) { return {Z(q[0]), Z(q[1]), Z(q[2])}; }

/// The plane n . x = d through t's corners; false when n = 0 (collinear corners).
inline bool exact_plane(const Triangle3d& t, Z3& n, Z& d) {
  const Z3 o = exact_vector(t[0]);
  n = CGAL::cross_product(exact_vector(t[1]) - o, exact_vector(t[2]) - o);
  d = n * o;
  return n != CGAL::NULL_VECTOR;
}

/// Where the line through p and q crosses the plane of t: with dp, dq the
/// signed (unnormalised) distances of p and q, (dp q - dq p) / (dp - dq).
/// `none` when the line is parallel to the plane.
inline Meeting line_meets_plane(const Point3d& p, const Point3d& q, const Triangle3d& t, Homogeneous& out) {
  Z3 n;
  Z d;
  if (!exact_plane(t, n, d)) return Meeting::degenerate;
  const Z3 P = exact_vector(p), Q = exact_vector(q);
  const Z dp = n * P - d, dq = n * Q - d;
  out = {dp * Q - dq * P, dp - dq};
  return out.den.is_zero() ? Meeting::none : Meeting::point;
}

/// The point common to the planes of a, b and c by Cramer's rule:
/// (da (nb x nc) + db (nc x na) + dc (na x nb)) / na . (nb x nc); `none`
/// when they do not meet in one point.
inline Meeting planes_meet_exactly(const Triangle3d& a, const Triangle3d& b, const Triangle3d& c, Homogeneous& out) {
  Z3 na, nb, nc;
  Z da, db, dc;
  if (!exact_plane(a, na, da) || !exact_plane(b, nb, db) || !exact_plane(c, nc, dc)) return Meeting::degenerate;
  const Z3 bc = CGAL::cross_product(nb, nc), ca = CGAL::cross_product(nc, na), ab = CGAL::cross_product(na, nb);
  out = {da * bc + db * ca + dc * ab, na * bc};
  return out.den.is_zero() ? Meeting::none : Meeting::point;
}

}  // namespace polyheal::detail
