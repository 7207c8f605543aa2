// polyheal — where lines and planes through input doubles meet, exactly, as
// homogeneous points: ring operations on the doubles' values (Mpzf, no
// normalisation, no gcd), and one division per coordinate by whoever needs a
// rational (degenerate's split points; regularize's exact points, kept
// homogeneous in Epeck's lazy tree until a filter fails: lazy_point) or a
// double (rebuild's sharpening, plane_meet.h). Cheaper than the same
// construction through Epeck's lazy tree, whose exact evaluation normalises a
// rational at every step.
//
// CGAL's Mpzf and kernel: include only from the CGAL-heavy translation units.
#pragma once

#include <CGAL/Lazy.h>
#include <CGAL/Mpzf.h>
#include <CGAL/Simple_cartesian.h>
#include <gmpxx.h>

#include <array>
#include <functional>
#include <utility>

#include "polyheal/repair/detail/plane_meet.h"

namespace polyheal::detail {

using Z = CGAL::Mpzf;
using Z3 = CGAL::Simple_cartesian<Z>::Vector_3;

/// The point num / den (den != 0).
struct Homogeneous {
  Z3 num;
  Z den;
};

/// num / den's coordinates as exact rationals: one division each.
template <std::size_t D>
std::array<mpq_class, D> rationals(const std::array<Z, D>& num, const Z& den) {
  const mpq_class d(den);
  std::array<mpq_class, D> out;
  for (std::size_t c = 0; c < D; ++c) out[c] = mpq_class(num[c]) / d;
  return out;
}

/// h's coordinates as exact rationals.
inline std::array<mpq_class, 3> rationals(const Homogeneous& h) {
  return rationals<3>({h.num.x(), h.num.y(), h.num.z()}, h.den);
}

/// h as an Epeck point known exactly: a leaf of the lazy tree, with tight
/// intervals (a point built from three exact coordinates would still be a
/// node to evaluate when a filter fails on it or it is rounded).
template <class EpeckPoint>
EpeckPoint leaf_point(const Homogeneous& h) {
  using Exact = typename CGAL::Kernel_traits<EpeckPoint>::Kernel::Exact_kernel::Point_3;
  const std::array<mpq_class, 3> c = rationals(h);
  return EpeckPoint(typename EpeckPoint::Rep(Exact(c[0], c[1], c[2])));
}

/// num / den's coordinates as rationals left unreduced: numerator and
/// denominator as the ring operations left them (no gcd), the denominator
/// positive. Only for MPFR's correctly rounded conversions (mpfr_set_q
/// divides the numerator by the denominator as they are: CGAL::to_interval,
/// nearest_double_of); never for mpq arithmetic, which needs canonical form.
template <std::size_t D>
std::array<mpq_class, D> unreduced(const std::array<Z, D>& num, const Z& den) {
  const mpq_class d(den);  // an integer times a power of two, canonical
  std::array<mpq_class, D> out;
  for (std::size_t c = 0; c < D; ++c) {
    const mpq_class n(num[c]);
    mpz_mul(out[c].get_num_mpz_t(), n.get_num_mpz_t(), d.get_den_mpz_t());
    mpz_mul(out[c].get_den_mpz_t(), n.get_den_mpz_t(), d.get_num_mpz_t());
    if (sgn(out[c].get_den()) < 0) {
      mpz_neg(out[c].get_num_mpz_t(), out[c].get_num_mpz_t());
      mpz_neg(out[c].get_den_mpz_t(), out[c].get_den_mpz_t());
    }
  }
  return out;
}

/// A point of an Epeck kernel (Point_2 or Point_3) known as homogeneous
/// coordinates num / den: a leaf of the lazy tree whose intervals are the
/// tight ones of its exact value (CGAL::to_interval on the unreduced
/// rationals: what E2A makes of the reduced ones, bit for bit), and whose
/// exact rationals — a gcd per coordinate — are made only when a filter
/// fails on it. Tests that can take the homogeneous form (orientation_2 of
/// projected points, rounding, hashing) read it with homogeneous_of().
template <class Lazy, int D>
class HomogeneousRep final : public Lazy::Self_rep {
  using Base = typename Lazy::Self_rep;

 public:
  /// num[0..D) / den.
  struct Form {
    std::array<Z, D> num;
    Z den;
  };
  HomogeneousRep(const typename Lazy::AT& approx, Form form) : Base(approx), form_(std::move(form)) {}
  const Form& form() const { return form_; }
  void update_exact() const override {
    typename Lazy::ET e = make_exact(rationals<D>(form_.num, form_.den), std::make_index_sequence<D>());
    auto* p = new typename Base::Indirect(std::move(e));
    this->keep_at(p);
    this->set_ptr(p);
  }

 private:
  template <std::size_t... I>
  static typename Lazy::ET make_exact(const std::array<mpq_class, D>& c, std::index_sequence<I...>) {
    return typename Lazy::ET(c[I]...);
  }
  Form form_;
};

/// A 2D point of an Epeck kernel that is a point of a 3D one known as
/// homogeneous coordinates (HomogeneousRep) with all but coordinates i and
/// j dropped (an exact projection): it holds the 3D point, not a copy of
/// its form (three Mpzf copies a point: 7% of regularize's planning and
/// triangulation, where every point of a triangle is projected into its
/// plane), and makes its exact rationals only when a filter fails on it.
template <class Lazy2, class EpeckPoint3>
class ProjectedRep final : public Lazy2::Self_rep {
  using Base = typename Lazy2::Self_rep;

 public:
  using Form3 = typename HomogeneousRep<typename EpeckPoint3::Rep, 3>::Form;
  /// `form`: p's (homogeneous_of), which p keeps alive.
  ProjectedRep(const typename Lazy2::AT& approx, EpeckPoint3 p, const Form3& form, int i, int j)
      : Base(approx), point_(std::move(p)), form_(&form), i_(i), j_(j) {}
  /// The projection's homogeneous coordinates (x, y, w).
  std::array<Z, 3> row() const { return {form_->num[std::size_t(i_)], form_->num[std::size_t(j_)], form_->den}; }
  void update_exact() const override {
    const std::array<mpq_class, 2> c =
        rationals<2>({form_->num[std::size_t(i_)], form_->num[std::size_t(j_)]}, form_->den);
    auto* p = new typename Base::Indirect(typename Lazy2::ET(c[0], c[1]));
    this->keep_at(p);
    this->set_ptr(p);
  }

 private:
  EpeckPoint3 point_;  // keeps form_ alive
  const Form3* form_;
  int i_, j_;
};

/// h as an Epeck point (HomogeneousRep: exact rationals on demand).
template <class EpeckPoint>
EpeckPoint lazy_point(const Homogeneous& h) {
  using Lazy = typename EpeckPoint::Rep;
  using Rep = HomogeneousRep<Lazy, 3>;
  typename Rep::Form form{{h.num.x(), h.num.y(), h.num.z()}, h.den};
  const std::array<mpq_class, 3> u = unreduced(form.num, form.den);
  const typename Lazy::AT approx(CGAL::to_interval(u[0]), CGAL::to_interval(u[1]), CGAL::to_interval(u[2]));
  return EpeckPoint(Lazy(new Rep(approx, std::move(form))));
}

/// The rep a lazy object's handle points to (CGAL::Handle keeps the
/// pointer protected: a pointer to member formed through a derived class).
struct HandleRep : CGAL::Handle {
  static const CGAL::Rep* of(const CGAL::Handle& h) {
    CGAL::Rep* CGAL::Handle::*const ptr = &HandleRep::PTR;
    return h.*ptr;
  }
};

/// The homogeneous form p was made from (lazy_point), or null.
template <class EpeckPoint, int D>
const typename HomogeneousRep<typename EpeckPoint::Rep, D>::Form* homogeneous_of(const EpeckPoint& p) {
  const auto* rep = dynamic_cast<const HomogeneousRep<typename EpeckPoint::Rep, D>*>(HandleRep::of(p));
  return rep ? &rep->form() : nullptr;
}

/// p (whose homogeneous form is `form`: homogeneous_of) with all but
/// coordinates i and j dropped, as a ProjectedRep.
template <class EpeckPoint2, class EpeckPoint3>
EpeckPoint2 projected_point(const EpeckPoint3& p,
                            const typename ProjectedRep<typename EpeckPoint2::Rep, EpeckPoint3>::Form3& form, int i,
                            int j) {
  using Lazy2 = typename EpeckPoint2::Rep;
  const auto& a = p.approx();
  return EpeckPoint2(Lazy2(new ProjectedRep<Lazy2, EpeckPoint3>(typename Lazy2::AT(a[i], a[j]), p, form, i, j)));
}

/// The ProjectedRep p is, or null.
template <class EpeckPoint2, class EpeckPoint3>
const ProjectedRep<typename EpeckPoint2::Rep, EpeckPoint3>* projected_of(const EpeckPoint2& p) {
  return dynamic_cast<const ProjectedRep<typename EpeckPoint2::Rep, EpeckPoint3>*>(HandleRep::of(p));
}

inline Z3 exact_vector(const Point3d& q) { return {Z(q[0]), Z(q[1]), Z(q[2])}; }

/// The orientation of the 2D points p, q, r with exact rational coordinates
/// (x, y): the sign of (qx - px)(ry - py) - (qy - py)(rx - px), on integers
/// only. Over the common denominator of its terms (positive: a canonical
/// rational's is), without px's and py's denominators, which all share.
/// mpq arithmetic on the same expression reduces every difference and
/// product by a gcd; on points of an intersection curve (a few hundred
/// bits) those gcds were most of the test's time.
using Rational2 = std::array<std::reference_wrapper<const mpq_class>, 2>;
inline CGAL::Orientation rational_orientation(const Rational2& p, const Rational2& q, const Rational2& r) {
  // a/b - c/d as its numerator a d - c b over b d
  auto numerator = [](const mpq_class& x, const mpq_class& y) {
    return mpz_class(x.get_num() * y.get_den() - y.get_num() * x.get_den());
  };
  const mpq_class &px = p[0], &py = p[1], &qx = q[0], &qy = q[1], &rx = r[0], &ry = r[1];
  // (qx - px)(ry - py) over qxd pxd ryd pyd, (qy - py)(rx - px) over qyd pyd rxd pxd
  const mpz_class left = numerator(qx, px) * numerator(ry, py) * qy.get_den() * rx.get_den();
  const mpz_class right = numerator(qy, py) * numerator(rx, px) * qx.get_den() * ry.get_den();
  const int c = cmp(left, right);
  return c > 0 ? CGAL::LEFT_TURN : c < 0 ? CGAL::RIGHT_TURN : CGAL::COLLINEAR;
}

/// The orientation of the 2D points (x / w, y / w) given as integer rows
/// (x, y, w), w != 0: the sign of the rows' determinant times that of
/// w1 w2 w3 (each row is its point's (x / w, y / w, 1) scaled by w). No
/// rational, no gcd: for points kept homogeneous (HomogeneousRep).
using Row2 = std::array<Z, 3>;
inline CGAL::Orientation homogeneous_orientation(const Row2& a, const Row2& b, const Row2& c) {
  const Z det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                a[2] * (b[0] * c[1] - b[1] * c[0]);
  const int s = int(CGAL::sign(det)) * int(CGAL::sign(a[2])) * int(CGAL::sign(b[2])) * int(CGAL::sign(c[2]));
  return s > 0 ? CGAL::LEFT_TURN : s < 0 ? CGAL::RIGHT_TURN : CGAL::COLLINEAR;
}

/// An integer as an Mpzf. (CGAL 5.5's Mpzf(mpz_class) drops the sign and
/// mishandles zero: only a positive magnitude goes through it.)
inline Z integer(const mpz_class& z) {
  const int s = sgn(z);
  if (s == 0) return Z(0);
  const Z magnitude{mpz_class(abs(z))};
  return s > 0 ? magnitude : -magnitude;
}

/// Rationals scaled by the least common multiple of their denominators (a
/// positive factor): integers with the same signs and ratios.
template <std::size_t N>
std::array<Z, N> common_integers(const std::array<mpq_class, N>& q) {
  mpz_class den = 1;
  for (const mpq_class& x : q) mpz_lcm(den.get_mpz_t(), den.get_mpz_t(), x.get_den_mpz_t());
  std::array<Z, N> out;
  for (std::size_t i = 0; i < N; ++i) out[i] = integer(q[i].get_num() * (den / q[i].get_den()));
  return out;
}

/// An Epeck point as a homogeneous point with integer coordinates: its own
/// doubles over 1 when it is a double point (no exact evaluation), else its
/// exact rationals over their common denominator.
template <class EpeckPoint>
Homogeneous homogeneous(const EpeckPoint& p) {
  const auto& a = p.approx();
  if (a.x().is_point() && a.y().is_point() && a.z().is_point())
    return {Z3(Z(a.x().inf()), Z(a.y().inf()), Z(a.z().inf())), Z(1)};
  const auto& e = p.exact();
  const std::array<Z, 4> c = common_integers(std::array<mpq_class, 4>{e.x(), e.y(), e.z(), mpq_class(1)});
  return {Z3(c[0], c[1], c[2]), c[3]};
}

/// An Epeck plane a x + b y + c z + d = 0 as integers n . x + d = 0 (scaled
/// by a positive factor: the same plane, the same sides).
template <class EpeckPlane>
void integer_plane(const EpeckPlane& plane, Z3& n, Z& d) {
  const auto& a = plane.approx();
  if (a.a().is_point() && a.b().is_point() && a.c().is_point() && a.d().is_point()) {
    n = Z3(Z(a.a().inf()), Z(a.b().inf()), Z(a.c().inf()));
    d = Z(a.d().inf());
    return;
  }
  const auto& e = plane.exact();
  const std::array<Z, 4> c = common_integers(std::array<mpq_class, 4>{e.a(), e.b(), e.c(), e.d()});
  n = Z3(c[0], c[1], c[2]);
  d = c[3];
}

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
