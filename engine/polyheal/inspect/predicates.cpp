#include "polyheal/inspect/predicates.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Exact_rational.h>
#include <CGAL/Interval_nt.h>

namespace polyheal {
namespace {

using Interval = CGAL::Interval_nt<false>;
using Rational = CGAL::Exact_rational;

/// Runs `eval<NT>()` with intervals and, if any comparison is uncertain,
/// again with exact rationals.
template <class Eval>
bool filtered(Eval eval) {
  {
    CGAL::Protect_FPU_rounding<true> protect;
    try {
      return eval(Interval());
    } catch (CGAL::Uncertain_conversion_exception&) {
    }
  }
  return eval(Rational());
}

template <class NT>
struct Vec {
  NT x, y, z;
};
template <class NT>
Vec<NT> sub(const Point3d& a, const Point3d& b) {
  return {NT(a[0]) - NT(b[0]), NT(a[1]) - NT(b[1]), NT(a[2]) - NT(b[2])};
}
template <class NT>
NT dot(const Vec<NT>& u, const Vec<NT>& v) {
  return u.x * v.x + u.y * v.y + u.z * v.z;
}
template <class NT>
Vec<NT> cross(const Vec<NT>& u, const Vec<NT>& v) {
  return {u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
}

/// angle(u, v) > acos(c)  <=>  u.v < c |u||v|, decided without square roots.
template <class NT>
bool vector_angle_greater(const Vec<NT>& u, const Vec<NT>& v, double c) {
  const NT d = dot(u, v);
  const NT rhs = NT(c) * NT(c) * dot(u, u) * dot(v, v);
  if (c >= 0) return bool(d < 0) || bool(d * d < rhs);
  return bool(d < 0) && bool(d * d > rhs);
}
/// angle(u, v) < acos(c)  <=>  u.v > c |u||v|.
template <class NT>
bool vector_angle_less(const Vec<NT>& u, const Vec<NT>& v, double c) {
  const NT d = dot(u, v);
  const NT rhs = NT(c) * NT(c) * dot(u, u) * dot(v, v);
  if (c >= 0) return bool(d > 0) && bool(d * d > rhs);
  return bool(d >= 0) || bool(d * d < rhs);
}

}  // namespace

bool is_collinear(const Point3d& a, const Point3d& b, const Point3d& c) {
  using P = CGAL::Epick::Point_3;
  return CGAL::collinear(P(a[0], a[1], a[2]), P(b[0], b[1], b[2]), P(c[0], c[1], c[2]));
}

bool angle_greater(const Point3d& apex, const Point3d& b, const Point3d& c, double cos_threshold) {
  return filtered([&](auto nt) {
    using NT = decltype(nt);
    return vector_angle_greater(sub<NT>(b, apex), sub<NT>(c, apex), cos_threshold);
  });
}

bool angle_less(const Point3d& apex, const Point3d& b, const Point3d& c, double cos_threshold) {
  return filtered([&](auto nt) {
    using NT = decltype(nt);
    return vector_angle_less(sub<NT>(b, apex), sub<NT>(c, apex), cos_threshold);
  });
}

bool fold_angle_less(const Point3d& p, const Point3d& q, const Point3d& r, const Point3d& s, double cos_threshold) {
  // n1 = pq x pr and n2 = pq x ps are parallel when r and s lie on the same
  // half-plane (folded) and opposite when the surface is flat.
  return filtered([&](auto nt) {
    using NT = decltype(nt);
    const Vec<NT> e = sub<NT>(q, p);
    return vector_angle_less(cross(e, sub<NT>(r, p)), cross(e, sub<NT>(s, p)), cos_threshold);
  });
}

bool is_nearly_degenerate(const Point3d& a, const Point3d& b, const Point3d& c, double eps) {
  if (is_collinear(a, b, c)) return false;
  return filtered([&](auto nt) {
    using NT = decltype(nt);
    const Vec<NT> ab = sub<NT>(b, a), ac = sub<NT>(c, a), bc = sub<NT>(c, b);
    const Vec<NT> n = cross(ab, ac);
    const NT l1 = dot(ab, ab), l2 = dot(ac, ac), l3 = dot(bc, bc);
    const NT e2 = NT(eps) * NT(eps);
    // |n|^2 <= eps^2 * max(l)^2  <=>  |n|^2 <= eps^2 l_i^2 for some i
    const NT n2 = dot(n, n);
    return bool(n2 <= e2 * l1 * l1) || bool(n2 <= e2 * l2 * l2) || bool(n2 <= e2 * l3 * l3);
  });
}

}  // namespace polyheal
