#include "polyheal/inspect/predicates.h"
#include "polyheal/inspect/exact_predicates.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Exact_rational.h>
#include <CGAL/Interval_nt.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/squared_distance_3.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

namespace polyheal {
namespace {

using Interval = CGAL::Interval_nt<false>;
using Rational = CGAL::Exact_rational;

/// Runs `eval<NT>()` with intervals and, if any comparison is uncertain,
/// again with exact rationals. (Callers try a static double filter first.)
template <class Eval>
auto filtered(Eval eval) {
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

/// Signs of u.v and of T = (u.v)^2 - c^2 (u.u)(v.v): they decide how the angle
/// between u and v compares with acos(c), without square roots. T < 0
/// (|cos| below |c|) decides every comparison alone (greater_from_signs,
/// less_from_signs), so then u.v's sign is not asked and reported as 0: at
/// a right angle, which slicing perpendicular to an edge makes and CAD
/// parts are full of, u.v is exactly 0 and no interval decides its sign.
/// With intervals, an undecidable sign throws Uncertain_conversion_exception.
template <class NT>
std::pair<int, int> angle_signs(const Vec<NT>& u, const Vec<NT>& v, double c) {
  const NT d = dot(u, v);
  const NT t = d * d - NT(c) * NT(c) * dot(u, u) * dot(v, v);
  const int test = static_cast<int>(static_cast<CGAL::Sign>(CGAL::sign(t)));
  if (test < 0) return {0, test};
  return {static_cast<int>(static_cast<CGAL::Sign>(CGAL::sign(d))), test};
}

/// x - y in intervals, from the exact points' own approximations (no lazy
/// expression built). The caller protects the rounding mode.
Vec<Interval> isub(const Point& x, const Point& y) {
  const auto &ax = x.approx(), &ay = y.approx();
  return Vec<Interval>{ax.x() - ay.x(), ax.y() - ay.y(), ax.z() - ay.z()};
}

/// Static filter for the angle tests, in plain double arithmetic.
///
/// For u = b - a, v = c - a (a, b, c doubles), the tests compare
/// T = (u.v)^2 - c^2 (u.u)(v.v) with 0 and u.v with 0. Each difference carries
/// a relative error <= eps, each dot product of three terms <= 3 eps more, so
/// |T~ - T| <= 16 eps (D^2 + R) with D = sum |u_i v_i| and R = c^2 (u.u)(v.v),
/// and |(u.v)~ - u.v| <= 6 eps D (eps = 2^-53; second-order terms included in
/// the margin below). We use 1e-13 (> 500 eps) and refuse to decide when the
/// magnitudes leave [1e-70, 1e70] or the sum falls near the underflow range,
/// where the relative bounds do not hold; the caller then evaluates exactly.
struct StaticAngle {
  bool decided = false;
  int dot_sign = 0;   // sign of u.v
  int test_sign = 0;  // sign of (u.v)^2 - c^2 (u.u)(v.v)
};

/// The signs of d = u.v and T = (u.v)^2 - c^2 (u.u)(v.v) when the computed
/// values decide them: |T - T~| and |d - d~| are below 1e-13 times `scale`
/// and D (the callers' error bounds), away from underflow.
StaticAngle decided_signs(double d, double D, double T, double scale) {
  StaticAngle r;
  if (!(scale > 1e-250) || std::fabs(T) <= 1e-13 * scale) return r;
  if (T < 0) {  // decides alone (see angle_signs): a right angle needs no sign of u.v
    r.decided = true;
    r.test_sign = -1;
    return r;
  }
  if (std::fabs(d) <= 1e-13 * D) return r;
  r.decided = true;
  r.dot_sign = d > 0 ? 1 : -1;
  r.test_sign = 1;
  return r;
}

StaticAngle static_angle(const Point3d& apex, const Point3d& b, const Point3d& c, double cos_threshold) {
  StaticAngle r;
  double u[3], v[3], m = 0;
  for (int i = 0; i < 3; ++i) {
    u[i] = b[i] - apex[i];
    v[i] = c[i] - apex[i];
    m = std::max({m, std::fabs(u[i]), std::fabs(v[i])});
  }
  if (!(m > 1e-70 && m < 1e70)) return r;
  const double d = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
  const double D = std::fabs(u[0] * v[0]) + std::fabs(u[1] * v[1]) + std::fabs(u[2] * v[2]);
  const double uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2], vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  const double R = cos_threshold * cos_threshold * uu * vv;
  return decided_signs(d, D, d * d - R, D * D + R);
}

/// angle > acos(c)  <=>  u.v < c |u||v|, from the signs of u.v and T.
bool greater_from_signs(int dot, int test, double c) {
  return c >= 0 ? (dot < 0 || test < 0) : (dot < 0 && test > 0);
}
/// angle < acos(c)  <=>  u.v > c |u||v|.
bool less_from_signs(int dot, int test, double c) {
  return c >= 0 ? (dot > 0 && test > 0) : (dot >= 0 || test < 0);
}

/// The angle at `apex` between rays to b and c, compared with acos(cos_threshold)
/// by `decide`: static filter, then intervals, then rationals.
template <class Decide>
bool angle_at(const Point3d& apex, const Point3d& b, const Point3d& c, double cos_threshold, Decide decide) {
  const StaticAngle s = static_angle(apex, b, c, cos_threshold);
  if (s.decided) return decide(s.dot_sign, s.test_sign, cos_threshold);
  const auto [dot_sign, test_sign] = filtered([&](auto nt) {
    using NT = decltype(nt);
    return angle_signs(sub<NT>(b, apex), sub<NT>(c, apex), cos_threshold);
  });
  return decide(dot_sign, test_sign, cos_threshold);
}

/// The classification, shared by double and exact points: collinear first,
/// then any cap angle, then any needle angle.
template <class P, class Collinear, class Greater, class Less>
Shape classify_with(const P& a, const P& b, const P& c, Collinear collinear, Greater greater, Less less) {
  if (collinear(a, b, c)) return Shape::degenerate;
  const P* p[3] = {&a, &b, &c};
  for (int k = 0; k < 3; ++k)
    if (greater(*p[k], *p[(k + 1) % 3], *p[(k + 2) % 3])) return Shape::cap;
  for (int k = 0; k < 3; ++k)
    if (less(*p[k], *p[(k + 1) % 3], *p[(k + 2) % 3])) return Shape::needle;
  return Shape::fine;
}

/// The doubles of a point that is_double_point() holds for.
Point3d doubles_of(const Point& p) {
  const auto q = to_input_point(p);
  return {q.x(), q.y(), q.z()};
}

}  // namespace

double cos_degrees(double degrees) { return std::cos(degrees * 3.14159265358979323846 / 180.0); }
double sin_degrees(double degrees) { return std::sin(degrees * 3.14159265358979323846 / 180.0); }

Shape classify_triangle(const Point3d& a, const Point3d& b, const Point3d& c, double cos_cap, double cos_needle) {
  return classify_with(
      a, b, c, is_collinear,
      [&](const Point3d& x, const Point3d& y, const Point3d& z) { return angle_greater(x, y, z, cos_cap); },
      [&](const Point3d& x, const Point3d& y, const Point3d& z) { return angle_less(x, y, z, cos_needle); });
}

Shape classify_triangle(const Point& a, const Point& b, const Point& c, double cos_cap, double cos_needle) {
  if (is_double_point(a) && is_double_point(b) && is_double_point(c)) {  // the cheaper exact path
    return classify_triangle(doubles_of(a), doubles_of(b), doubles_of(c), cos_cap, cos_needle);
  }
  using FT = Kernel::FT;
  auto sub = [](const Point& x, const Point& y) { return Vec<FT>{x.x() - y.x(), x.y() - y.y(), x.z() - y.z()}; };
  // Intervals from the points' own approximations first (no lazy DAG built),
  // exact lazy arithmetic only when a sign is uncertain.
  auto decide = [&](const Point& apex, const Point& y, const Point& z, double c, auto from_signs) {
    {
      CGAL::Protect_FPU_rounding<true> protect;
      try {
        const auto [dot_sign, test_sign] = angle_signs(isub(y, apex), isub(z, apex), c);
        return from_signs(dot_sign, test_sign, c);
      } catch (CGAL::Uncertain_conversion_exception&) {
      }
    }
    const auto [dot_sign, test_sign] = angle_signs(sub(y, apex), sub(z, apex), c);
    return from_signs(dot_sign, test_sign, c);
  };
  return classify_with(
      a, b, c, [](const Point& x, const Point& y, const Point& z) { return CGAL::collinear(x, y, z); },
      [&](const Point& x, const Point& y, const Point& z) { return decide(x, y, z, cos_cap, greater_from_signs); },
      [&](const Point& x, const Point& y, const Point& z) { return decide(x, y, z, cos_needle, less_from_signs); });
}


namespace {

/// u x v on doubles with, per component n_i = x - y, the magnitude
/// P_i = |x| + |y| of its two products: the static filters below bound the
/// component's error by 4 eps P_i (eps = 2^-53; the differences u, v each
/// carry a relative error <= eps).
struct BoundedCross {
  double n[3], p[3];
  BoundedCross(const double u[3], const double v[3]) {
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3, k = (i + 2) % 3;
      n[i] = u[j] * v[k] - u[k] * v[j];
      p[i] = std::fabs(u[j] * v[k]) + std::fabs(u[k] * v[j]);
    }
  }
};

/// Static filter for normals_agree on doubles: the sign of
/// D = ((b - a) x (c - a)) . ((e - d) x (f - d)), or 0 when the bound below
/// does not decide it. Each difference carries a relative error <= eps, each
/// cross-product component n_i = x - y <= 4 eps P_i with P_i = |x| + |y| (the
/// magnitudes of its two products), each term n_i m_i <= 8 eps P_i Q_i more
/// and the sum 3 eps of the terms' magnitudes: |D~ - D| <= 11 eps sum P_i Q_i
/// (eps = 2^-53; second-order terms in the margin: 1e-13 > 900 eps). As in
/// static_angle, magnitudes outside [1e-70, 1e70] or a scale near the
/// underflow range are left to the intervals.
int static_normals_sign(const std::array<Point3d, 6>& p) {
  double u[3], v[3], s[3], t[3], m = 0;
  for (int i = 0; i < 3; ++i) {
    u[i] = p[1][i] - p[0][i];
    v[i] = p[2][i] - p[0][i];
    s[i] = p[4][i] - p[3][i];
    t[i] = p[5][i] - p[3][i];
    m = std::max({m, std::fabs(u[i]), std::fabs(v[i]), std::fabs(s[i]), std::fabs(t[i])});
  }
  if (!(m > 1e-70 && m < 1e70)) return 0;
  const BoundedCross n1(u, v), n2(s, t);
  double dot = 0, scale = 0;
  for (int i = 0; i < 3; ++i) {
    dot += n1.n[i] * n2.n[i];
    scale += n1.p[i] * n2.p[i];
  }
  if (!(scale > 1e-250)) return 0;
  if (dot > 1e-13 * scale) return 1;
  if (dot < -1e-13 * scale) return -1;
  return 0;
}

}  // namespace

bool normals_agree(const Point& a, const Point& b, const Point& c, const Point& d, const Point& e, const Point& f) {
  if (is_double_point(a) && is_double_point(b) && is_double_point(c) && is_double_point(d) && is_double_point(e) &&
      is_double_point(f)) {
    const int sign = static_normals_sign(
        {doubles_of(a), doubles_of(b), doubles_of(c), doubles_of(d), doubles_of(e), doubles_of(f)});
    if (sign != 0) return sign > 0;
  }
  {
    CGAL::Protect_FPU_rounding<true> protect;
    const Interval s = dot(cross(isub(b, a), isub(c, a)), cross(isub(e, d), isub(f, d)));
    if (s.inf() > 0) return true;
    if (s.sup() <= 0) return false;
  }
  return CGAL::is_positive(CGAL::cross_product(b - a, c - a) * CGAL::cross_product(e - d, f - d));
}

bool angle_to_plane_less(const Kernel::Vector_3& e, const Kernel::Vector_3& n, double sin_threshold) {
  // angle(e, plane) < d  <=>  |cos(e, n)| < sin d  <=>  (e.n)^2 - sin^2 d |e|^2 |n|^2 < 0
  using FT = Kernel::FT;
  const auto test_sign =
      angle_signs(Vec<FT>{e.x(), e.y(), e.z()}, Vec<FT>{n.x(), n.y(), n.z()}, sin_threshold).second;
  return test_sign < 0;
}

std::size_t largest_angle_corner(const std::vector<Point>& polygon) {
  using FT = Kernel::FT;
  const std::size_t n = polygon.size();
  // cos(angle k) = d_k / sqrt(l_k): compare without square roots.
  std::vector<FT> d(n), l(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Kernel::Vector_3 u = polygon[(k + n - 1) % n] - polygon[k], v = polygon[(k + 1) % n] - polygon[k];
    d[k] = u * v;
    l[k] = u.squared_length() * v.squared_length();
  }
  auto cos_less = [&](std::size_t i, std::size_t j) {
    const CGAL::Sign si = CGAL::sign(d[i]), sj = CGAL::sign(d[j]);
    if (si != sj) return si < sj;
    if (si == CGAL::ZERO) return false;
    const FT a = d[i] * d[i] * l[j], b = d[j] * d[j] * l[i];  // cos_i^2 vs cos_j^2, scaled
    return si == CGAL::POSITIVE ? a < b : b < a;
  };
  // Ties go to the lexicographically smallest corner, so the answer does not
  // depend on where the polygon's corner list starts (plane_slice plans a
  // cut on one rotation and makes it on another).
  std::size_t best = 0;
  for (std::size_t k = 1; k < n; ++k)
    if (cos_less(k, best) || (!cos_less(best, k) && polygon[k] < polygon[best])) best = k;
  return best;
}

bool is_collinear(const Point3d& a, const Point3d& b, const Point3d& c) {
  using P = CGAL::Epick::Point_3;
  return CGAL::collinear(P(a[0], a[1], a[2]), P(b[0], b[1], b[2]), P(c[0], c[1], c[2]));
}

bool angle_greater(const Point3d& apex, const Point3d& b, const Point3d& c, double cos_threshold) {
  return angle_at(apex, b, c, cos_threshold, greater_from_signs);
}

bool angle_less(const Point3d& apex, const Point3d& b, const Point3d& c, double cos_threshold) {
  return angle_at(apex, b, c, cos_threshold, less_from_signs);
}

namespace {

/// Static filter for fold_angle_less, in the form of static_angle: the signs
/// angle_signs() gives for n1 = e x a and n2 = e x b (e = q - p, a = r - p,
/// b = s - p), from forward error bounds. Each cross-product component
/// carries <= 4 eps P_i (P_i: the magnitudes of its two products), so
/// d = n1.n2 carries <= 11 eps D with D = sum P1_i P2_i, each |n|^2 <= 11 eps
/// A with A = sum P_i^2, and T = d^2 - c^2 |n1|^2 |n2|^2 <= 26 eps (D^2 +
/// c^2 A1 A2) (eps = 2^-53; second-order terms in the margin: 1e-13).
/// T is of degree 8 in the differences: outside [1e-35, 1e35], or with a
/// scale near the underflow range, the intervals decide.
StaticAngle static_fold(const Point3d& p, const Point3d& q, const Point3d& r, const Point3d& s, double c) {
  StaticAngle out;
  double e[3], a[3], b[3], m = 0;
  for (int i = 0; i < 3; ++i) {
    e[i] = q[i] - p[i];
    a[i] = r[i] - p[i];
    b[i] = s[i] - p[i];
    m = std::max({m, std::fabs(e[i]), std::fabs(a[i]), std::fabs(b[i])});
  }
  if (!(m > 1e-35 && m < 1e35)) return out;
  const BoundedCross n1(e, a), n2(e, b);
  double d = 0, D = 0, n1n1 = 0, n2n2 = 0, A1 = 0, A2 = 0;
  for (int i = 0; i < 3; ++i) {
    d += n1.n[i] * n2.n[i];
    D += n1.p[i] * n2.p[i];
    n1n1 += n1.n[i] * n1.n[i];
    n2n2 += n2.n[i] * n2.n[i];
    A1 += n1.p[i] * n1.p[i];
    A2 += n2.p[i] * n2.p[i];
  }
  return decided_signs(d, D, d * d - c * c * n1n1 * n2n2, D * D + c * c * A1 * A2);
}

}  // namespace

bool fold_angle_less(const Point3d& p, const Point3d& q, const Point3d& r, const Point3d& s, double cos_threshold) {
  // n1 = pq x pr and n2 = pq x ps are parallel when r and s lie on the same
  // half-plane (folded) and opposite when the surface is flat.
  if (const StaticAngle st = static_fold(p, q, r, s, cos_threshold); st.decided)
    return less_from_signs(st.dot_sign, st.test_sign, cos_threshold);
  const auto [dot_sign, test_sign] = filtered([&](auto nt) {
    using NT = decltype(nt);
    const Vec<NT> e = sub<NT>(q, p);
    return angle_signs(cross(e, sub<NT>(r, p)), cross(e, sub<NT>(s, p)), cos_threshold);
  });
  return less_from_signs(dot_sign, test_sign, cos_threshold);
}

namespace {

/// |n|^2 >= 1e-6 l^4 for triangle abc's normal n and longest edge l (doubles:
/// a gate on the conditioning, not a predicate on the surface).
bool well_shaped_for_circumcircle(const Point3d& a, const Point3d& b, const Point3d& c) {
  double u[3], v[3], w[3];
  for (int i = 0; i < 3; ++i) {
    u[i] = b[i] - a[i];
    v[i] = c[i] - a[i];
    w[i] = c[i] - b[i];
  }
  const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const double l2 = std::max({u[0] * u[0] + u[1] * u[1] + u[2] * u[2], v[0] * v[0] + v[1] * v[1] + v[2] * v[2],
                              w[0] * w[0] + w[1] * w[1] + w[2] * w[2]});
  return n[0] * n[0] + n[1] * n[1] + n[2] * n[2] >= 1e-6 * l2 * l2;
}

/// x farther than k times the radius from the centre of the circle through
/// a, b, c (in their plane), exactly. With u = b - a, v = c - a, n = u x v,
/// the centre is a + W / D, W = |v|^2 (n x u) + |u|^2 (v x n), D = 2 |n|^2;
/// so |centre - x| > k |centre - a|  <=>  |D (a - x) + W|^2 > k^2 |W|^2.
bool outside_circle(const Point3d& a, const Point3d& b, const Point3d& c, const Point3d& x, double k) {
  return filtered([&](auto nt) -> bool {
    using NT = decltype(nt);
    const Vec<NT> u = sub<NT>(b, a), v = sub<NT>(c, a), n = cross(u, v), ax = sub<NT>(a, x);
    const NT uu = dot(u, u), vv = dot(v, v), d = NT(2) * dot(n, n);
    const Vec<NT> nu = cross(n, u), vn = cross(v, n);
    const Vec<NT> w{vv * nu.x + uu * vn.x, vv * nu.y + uu * vn.y, vv * nu.z + uu * vn.z};
    const Vec<NT> dx{d * ax.x + w.x, d * ax.y + w.y, d * ax.z + w.z};
    return dot(dx, dx) > NT(k) * NT(k) * dot(w, w);
  });
}

}  // namespace

bool tetgen_keeps_edge(const Point3d& p, const Point3d& q, const Point3d& r, const Point3d& s, double eps) {
  if (!well_shaped_for_circumcircle(p, q, r) || !well_shaped_for_circumcircle(q, p, s)) return false;
  const double k = 1 - 0.5 * eps;
  return outside_circle(p, q, r, s, k) && outside_circle(q, p, s, r, k);
}

namespace {

double max_abs(std::initializer_list<const Point3d*> points) {
  double m = 0;
  for (const Point3d* p : points)
    for (int k = 0; k < 3; ++k) m = std::max(m, std::fabs((*p)[k]));
  return m;
}

/// Point sets x and y (a segment's ends, a triangle's corners, a point)
/// certainly farther apart than `tol`: along direction u their projections
/// are separated by more than tol |u|. Plain doubles with a rounding bound:
/// u need not be exact (any u separates), each projection of three products
/// carries at most 3 eps |u|_1 m of error (m bounds every |coordinate|; 4e-15
/// used, for both sides), and |u| is taken 1e-12 larger. Undecided (false)
/// near overflow or where the products could underflow.
bool separated_along(std::initializer_list<const Point3d*> x, std::initializer_list<const Point3d*> y,
                     const double* u, double m, double tol) {
  const double norm1 = std::fabs(u[0]) + std::fabs(u[1]) + std::fabs(u[2]);
  if (!(m < 1e150) || !(norm1 < 1e150) || !(norm1 * m > 1e-250)) return false;
  auto range = [&](std::initializer_list<const Point3d*> points) {
    double lo = HUGE_VAL, hi = -HUGE_VAL;
    for (const Point3d* p : points) {
      const double d = (*p)[0] * u[0] + (*p)[1] * u[1] + (*p)[2] * u[2];
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    return std::pair{lo, hi};
  };
  const auto [xl, xh] = range(x);
  const auto [yl, yh] = range(y);
  const double gap = std::max(yl - xh, xl - yh);
  const double len = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) * (1 + 1e-12);
  return gap - 4e-15 * norm1 * m > tol * len;
}

void cross3(const double* x, const double* y, double* z) {
  z[0] = x[1] * y[2] - x[2] * y[1];
  z[1] = x[2] * y[0] - x[0] * y[2];
  z[2] = x[0] * y[1] - x[1] * y[0];
}

/// Segments ab and cd certainly farther apart than `tol`, separated along an
/// axis, either segment's direction, their common normal or the normal to
/// either within their common plane. When there is no common normal (a
/// point, a == b, or parallel segments), the plane is the one through cd
/// and a, and the normal to cd within it is the direction of the distance
/// from a point to a line. Most pairs a box search meets are decided here.
bool static_segments_apart(const Point3d& a, const Point3d& b, const Point3d& c, const Point3d& d, double tol) {
  if (!(tol > 0)) return false;
  const double m = max_abs({&a, &b, &c, &d});
  double v[3], w[3], n[3], u1[3], u2[3];
  for (int k = 0; k < 3; ++k) {
    v[k] = b[k] - a[k];
    w[k] = d[k] - c[k];
  }
  cross3(v, w, n);
  if (n[0] == 0 && n[1] == 0 && n[2] == 0) {
    const double ca[3] = {a[0] - c[0], a[1] - c[1], a[2] - c[2]};
    cross3(w, ca, n);
  }
  cross3(v, n, u1);
  cross3(w, n, u2);
  // A point (a corner against a side, as the coarsening and the decimation
  // ask): the normal to cd towards it separates whenever anything does.
  if (a == b && separated_along({&a}, {&c, &d}, u2, m, tol)) return true;
  static const double axes[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (const double* u : {axes[0], axes[1], axes[2], static_cast<const double*>(n), static_cast<const double*>(u1),
                          static_cast<const double*>(u2), static_cast<const double*>(v), static_cast<const double*>(w)})
    if (separated_along({&a, &b}, {&c, &d}, u, m, tol)) return true;
  return false;
}

/// Point p certainly farther than `tol` from triangle abc, separated along
/// its normal, the normal to one of its edges in its plane, or the direction
/// from a corner to p.
bool static_point_triangle_apart(const Point3d& p, const Point3d& a, const Point3d& b, const Point3d& c, double tol) {
  if (!(tol > 0)) return false;
  const double m = max_abs({&p, &a, &b, &c});
  double e[3][3], n[3], u[3];
  for (int k = 0; k < 3; ++k) {
    e[0][k] = b[k] - a[k];
    e[1][k] = c[k] - b[k];
    e[2][k] = a[k] - c[k];
  }
  cross3(e[0], e[1], n);
  if (separated_along({&p}, {&a, &b, &c}, n, m, tol)) return true;
  for (int i = 0; i < 3; ++i) {
    cross3(e[i], n, u);
    if (separated_along({&p}, {&a, &b, &c}, u, m, tol)) return true;
  }
  for (const Point3d* x : {&a, &b, &c}) {  // beyond a corner
    const double d[3] = {p[0] - (*x)[0], p[1] - (*x)[1], p[2] - (*x)[2]};
    if (separated_along({&p}, {&a, &b, &c}, d, m, tol)) return true;
  }
  return false;
}

/// The squared distance between the two objects `make(K, point)` builds (a
/// pair; K is Simple_cartesian over intervals, then over rationals) is below
/// tol^2, exactly.
template <class Make>
bool squared_distance_below(Make make, double tol) {
  return filtered([&](auto nt) -> bool {
    using NT = decltype(nt);
    using K = CGAL::Simple_cartesian<NT>;
    auto pt = [](const Point3d& p) { return typename K::Point_3(NT(p[0]), NT(p[1]), NT(p[2])); };
    const auto objects = make(K(), pt);
    return CGAL::squared_distance(objects.first, objects.second) < NT(tol) * NT(tol);
  });
}

}  // namespace

bool point_closer_than_to_triangle(const Point3d& p, const Point3d& a, const Point3d& b, const Point3d& c, double tol) {
  if (static_point_triangle_apart(p, a, b, c, tol)) return false;
  if (is_collinear(a, b, c))  // the segments it is
    return segments_closer_than(p, p, a, b, tol) || segments_closer_than(p, p, b, c, tol) ||
           segments_closer_than(p, p, c, a, tol);
  return squared_distance_below(
      [&](auto k, auto pt) {
        using K = decltype(k);
        return std::pair{pt(p), typename K::Triangle_3(pt(a), pt(b), pt(c))};
      },
      tol);
}

bool corners_clear_of_sides(const Point3d& a, const Point3d& b, const Point3d& c, double tol) {
  // The sides e1 = b - a, e2 = c - a, e3 = c - b are rounded (each
  // coordinate by a relative eps = 2^-53), and so is every operation of the
  // cross product n = e1 x e2: each coordinate of n is off by at most about
  // 8.5 eps m1 m2 (m1, m2 the sides' largest coordinates), |n| by 15 eps m1
  // m2; 64 eps covers that and the rounding of |n| itself. The longest side
  // is taken 1e-12 longer than computed (its rounding is ~4 eps).
  double e1[3], e2[3], e3[3], n[3];
  for (int k = 0; k < 3; ++k) {
    e1[k] = b[k] - a[k];
    e2[k] = c[k] - a[k];
    e3[k] = c[k] - b[k];
  }
  double m1 = 0, m2 = 0;
  for (int k = 0; k < 3; ++k) {
    m1 = std::max(m1, std::fabs(e1[k]));
    m2 = std::max(m2, std::fabs(e2[k]));
  }
  if (!(m1 * m2 > 1e-250) || !(m1 * m2 < 1e250) || !(tol > 0) || !(tol < 1e100)) return false;
  cross3(e1, e2, n);
  const double twice_area = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  auto len2 = [](const double* e) { return e[0] * e[0] + e[1] * e[1] + e[2] * e[2]; };
  const double longest = std::sqrt(std::max({len2(e1), len2(e2), len2(e3)})) * (1 + 1e-12);
  const double eps = std::ldexp(1.0, -53);
  return twice_area - 64 * eps * m1 * m2 > tol * longest * (1 + 1e-12);
}

bool segments_closer_than(const Point3d& a, const Point3d& b, const Point3d& c, const Point3d& d, double tol) {
  if (static_segments_apart(a, b, c, d, tol)) return false;
  return squared_distance_below(
      [&](auto k, auto pt) {
        using K = decltype(k);
        return std::pair{typename K::Segment_3(pt(a), pt(b)), typename K::Segment_3(pt(c), pt(d))};
      },
      tol);
}

bool is_nearly_on_segment(const Point3d& p, const Point3d& a, const Point3d& b, double eps) {
  // Outside the segment's box grown by eps |ab| in some coordinate: farther
  // than that from every point of it. |ab| <= sqrt(3) max_k |b_k - a_k|;
  // the factor 2.5 covers that and the rounding of these few operations.
  // (Most vertices asked about an edge are its neighbours, nowhere near it.)
  double m = 0;
  for (int k = 0; k < 3; ++k) m = std::max(m, std::abs(b[k] - a[k]));
  const double reach = 2.5 * eps * m;
  for (int k = 0; k < 3; ++k)
    if (p[k] - std::max(a[k], b[k]) > reach || std::min(a[k], b[k]) - p[k] > reach) return false;
  if (is_collinear(a, b, p)) return false;  // exactly on the line: an exact defect, not a tolerance one
  return filtered([&](auto nt) {
    using NT = decltype(nt);
    const Vec<NT> ab = sub<NT>(b, a), ap = sub<NT>(p, a), bp = sub<NT>(p, b);
    if (!(dot(ap, ab) > NT(0)) || !(dot(bp, ab) < NT(0))) return false;
    // distance^2 = |ap x ab|^2 / |ab|^2 <= eps^2 |ab|^2
    const Vec<NT> n = cross(ap, ab);
    const NT l2 = dot(ab, ab);
    return bool(dot(n, n) <= NT(eps) * NT(eps) * l2 * l2);
  });
}

int orientation_sign(const Point3d& a, const Point3d& b, const Point3d& c, const Point3d& d) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  auto pt = [](const Point3d& p) { return K::Point_3(p[0], p[1], p[2]); };
  return static_cast<int>(CGAL::orientation(pt(a), pt(b), pt(c), pt(d)));
}

bool is_closer_than(const Point3d& p, const Point3d& q, double tol) {
  if (p == q) return false;
  return filtered([&](auto nt) {
    using NT = decltype(nt);
    const Vec<NT> pq = sub<NT>(q, p);
    return bool(dot(pq, pq) < NT(tol) * NT(tol));
  });
}

bool lies_along_segment(const Point3d& p, const Point3d& a, const Point3d& b, double tol) {
  return filtered([&](auto nt) {
    using NT = decltype(nt);
    const Vec<NT> ab = sub<NT>(b, a), ap = sub<NT>(p, a), bp = sub<NT>(p, b);
    if (!(dot(ap, ab) > NT(0)) || !(dot(bp, ab) < NT(0))) return false;
    const NT tol2 = NT(tol) * NT(tol);
    if (dot(ap, ap) <= tol2 || dot(bp, bp) <= tol2) return false;  // at an end: the same point
    // distance^2 = |ap x ab|^2 / |ab|^2 <= tol^2
    const Vec<NT> n = cross(ap, ab);
    return bool(dot(n, n) <= tol2 * dot(ab, ab));
  });
}

bool is_nearly_degenerate(const Point3d& a, const Point3d& b, const Point3d& c, double eps) {
  // Quick reject in doubles: each component of ab x ac is off by at most
  // ~8 eps_mach |ab||ac| <= 1e-14 L^2 (L the longest edge), so a computed
  // |n|^2 above 4 eps^2 L^4 proves |n| > eps L^2 whenever eps >= 1e-12.
  if (eps >= 1e-12) {
    double u[3], v[3], w[3], m = 0;
    for (int i = 0; i < 3; ++i) {
      u[i] = b[i] - a[i];
      v[i] = c[i] - a[i];
      w[i] = c[i] - b[i];
      m = std::max({m, std::fabs(u[i]), std::fabs(v[i])});
    }
    if (m > 1e-70 && m < 1e70) {
      const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
      const double n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
      const double l2 = 1.01 * std::max({u[0] * u[0] + u[1] * u[1] + u[2] * u[2], v[0] * v[0] + v[1] * v[1] + v[2] * v[2],
                                         w[0] * w[0] + w[1] * w[1] + w[2] * w[2]});
      if (n2 > 4 * eps * eps * l2 * l2) return false;
    }
  }
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

int enclosed_volume_sign(const Soup& soup) {
  std::vector<std::size_t> all(soup.face_count());
  std::iota(all.begin(), all.end(), std::size_t(0));
  return enclosed_volume_sign(soup, all);
}

int enclosed_volume_sign(const Soup& soup, const std::vector<std::size_t>& faces) {
  for (std::size_t f : faces)  // readers refuse non-finite points; a computed soup might hold one
    for (Index i : soup.face(f))
      if (!std::isfinite(soup.points[i][0]) || !std::isfinite(soup.points[i][1]) || !std::isfinite(soup.points[i][2]))
        return 0;
  // About the faces' bounding-box centre, not the origin: for a closed,
  // oriented set of faces the sum is the same about any point, but a set
  // that is not (an open or non-manifold soup the pipeline asks about) has
  // a sum that grows with its distance from the reference point — about the
  // origin, deer_bound moved 1e5 away read as inside out and was turned.
  Point3d lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (std::size_t f : faces)
    for (Index i : soup.face(f))
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], soup.points[i][k]);
        hi[k] = std::max(hi[k], soup.points[i][k]);
      }
  if (faces.empty()) return 0;
  const Point3d o{0.5 * lo[0] + 0.5 * hi[0], 0.5 * lo[1] + 0.5 * hi[1], 0.5 * lo[2] + 0.5 * hi[2]};
  return filtered([&](auto nt) {
    using NT = decltype(nt);
    auto at = [&](const Point3d& p) { return sub<NT>(p, o); };
    NT volume = 0;
    for (std::size_t f : faces) {
      const FaceView v = soup.face(f);
      const Vec<NT> pa = at(soup.points[v[0]]);
      for (std::size_t k = 1; k + 1 < v.size(); ++k)
        volume += dot(pa, cross(at(soup.points[v[k]]), at(soup.points[v[k + 1]])));
    }
    return static_cast<int>(static_cast<CGAL::Sign>(CGAL::sign(volume)));
  });
}

}  // namespace polyheal
