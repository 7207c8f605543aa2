#include "polyheal/inspect/detail/triangle_pair.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <variant>

#include <CGAL/Interval_nt.h>
#include <CGAL/intersections.h>

#include "polyheal/mesh/vec3.h"

namespace polyheal::detail {
namespace {

/// What a (possibly degenerate) triangle is geometrically.
template <class K>
using Primitive = std::variant<typename K::Point_3, typename K::Segment_3, typename K::Triangle_3>;

template <class K>
Primitive<K> primitive(const Tri<K>& t) {
  const auto &a = t.p[0], &b = t.p[1], &c = t.p[2];
  if (!CGAL::collinear(a, b, c)) return typename K::Triangle_3(a, b, c);
  if (a == b && b == c) return a;
  // Collinear: the segment between the two extreme points.
  if (CGAL::collinear_are_ordered_along_line(a, b, c)) return typename K::Segment_3(a, c);
  if (CGAL::collinear_are_ordered_along_line(b, a, c)) return typename K::Segment_3(b, c);
  return typename K::Segment_3(a, b);
}

template <class K>
bool primitives_intersect(const Primitive<K>& x, const Primitive<K>& y) {
  return std::visit(
      [](const auto& u, const auto& v) -> bool {
        using U = std::decay_t<decltype(u)>;
        using V = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<U, typename K::Point_3> && std::is_same_v<V, typename K::Point_3>)
          return u == v;
        else
          return CGAL::do_intersect(u, v);
      },
      x, y);
}

/// Segment pq against non-degenerate triangle t. Most pairs of neighbours
/// are rejected by the first two tests: disjoint boxes, or p and q strictly
/// on one side of t's plane.
template <class K>
bool edge_meets_triangle(const typename K::Point_3& p, const typename K::Point_3& q, const Tri<K>& t) {
  // Bounding boxes first: exact for double points, conservative for Epeck's.
  if (!CGAL::do_overlap(p.bbox() + q.bbox(), t.p[0].bbox() + t.p[1].bbox() + t.p[2].bbox())) return false;
  const CGAL::Orientation op = CGAL::orientation(t.p[0], t.p[1], t.p[2], p);
  if (op != CGAL::COPLANAR && op == CGAL::orientation(t.p[0], t.p[1], t.p[2], q)) return false;
  return CGAL::do_intersect(typename K::Segment_3(p, q), typename K::Triangle_3(t.p[0], t.p[1], t.p[2]));
}

/// A cheap proof that two triangles meet at most in the vertices they
/// share, before the exact test. Where two triangles are nearly (or exactly
/// but obliquely) coplanar, as neighbours in a fan of needles or in a planar
/// region of rounded points are, no filter decides CGAL's orientation tests
/// and they fall back to exact arithmetic: rationals for the exact kernel's
/// lazy split points (most of degenerate's decimation time on CAD fans),
/// Mpzf after a thrown exception for doubles (a sixth of rebuild's
/// simplification time on the flat-sided tubes). Such
/// neighbours are usually well apart within their plane, though, so a plane
/// chosen in doubles that separates them is found, and the separation is
/// then checked with interval arithmetic on the points' enclosures: a
/// certificate, exact whenever it answers. Where it cannot, the exact test
/// runs as before.
///   no shared vertex   a plane with one triangle strictly on each side;
///   one, v             a plane through v with the other corners of one
///                      triangle strictly on one side and of the other on
///                      the other (they meet only in v);
///   an edge pq         a plane containing the line pq with the opposite
///                      corners strictly on opposite sides (no fold-over).
class Separation {
 public:
  using I = CGAL::Interval_nt<false>;
  struct IV {
    I x, y, z;
  };
  struct DV {
    double x, y, z;
  };

  /// Epeck's points by their interval enclosures; doubles (Epick) exactly.
  template <class K>
  Separation(const Tri<K>& a, const Tri<K>& b) {
    for (int k = 0; k < 3; ++k) {
      ia_[k] = enclosure(a.p[k]);
      ib_[k] = enclosure(b.p[k]);
      da_[k] = mid(ia_[k]);
      db_[k] = mid(ib_[k]);
    }
    normal_ = unit(add(normal_of(da_), oriented(normal_of(db_), normal_of(da_))));
  }

  /// shared = 0, 1 or 2 vertices, at a's corners ia[...] and b's ib[...].
  bool apart(int shared, const int ia[3], const int ib[3]) const {
    if (!(dot(normal_, normal_) > 0)) return false;
    switch (shared) {
      case 0: return apart_disjoint();
      case 1: return apart_at_vertex(ia[0], ib[0]);
      case 2: return apart_at_edge(ia[0], ia[1], 3 - ia[0] - ia[1], 3 - ib[0] - ib[1]);
      default: return false;
    }
  }

 private:
  static double mid(const I& i) { return 0.5 * i.inf() + 0.5 * i.sup(); }
  static DV mid(const IV& p) { return {mid(p.x), mid(p.y), mid(p.z)}; }
  static DV sub(const DV& a, const DV& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
  static DV add(const DV& a, const DV& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
  static double dot(const DV& a, const DV& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
  static DV cross(const DV& a, const DV& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
  }
  static DV unit(const DV& a) {
    const double l = std::sqrt(dot(a, a));
    return l > 0 ? DV{a.x / l, a.y / l, a.z / l} : DV{0, 0, 0};
  }
  static DV normal_of(const std::array<DV, 3>& t) { return unit(cross(sub(t[1], t[0]), sub(t[2], t[0]))); }
  static DV oriented(const DV& n, const DV& like) { return dot(n, like) < 0 ? DV{-n.x, -n.y, -n.z} : n; }
  /// The sign of m . (x - o), certain (+1, -1) or not (0).
  static int side(const IV& m, const IV& o, const IV& x) {
    const I s = m.x * (x.x - o.x) + m.y * (x.y - o.y) + m.z * (x.z - o.z);
    return s.inf() > 0 ? 1 : (s.sup() < 0 ? -1 : 0);
  }
  static IV exact(const DV& d) { return {I(d.x), I(d.y), I(d.z)}; }
  static IV enclosure(const Kernel::Point_3& p) {
    const auto& q = CGAL::approx(p);
    return {q.x(), q.y(), q.z()};
  }
  static IV enclosure(const InputKernel::Point_3& p) { return {I(p.x()), I(p.y()), I(p.z())}; }

  bool apart_disjoint() const {
    // Candidate normals: both planes and each side extruded along the normal.
    std::array<DV, 8> ms{normal_of(da_), normal_of(db_)};
    for (int k = 0; k < 3; ++k) {
      ms[2 + k] = cross(sub(da_[(k + 1) % 3], da_[k]), normal_);
      ms[5 + k] = cross(sub(db_[(k + 1) % 3], db_[k]), normal_);
    }
    for (const DV& m : ms) {
      double lo_a = INFINITY, hi_a = -INFINITY, lo_b = INFINITY, hi_b = -INFINITY;
      for (int k = 0; k < 3; ++k) {
        const double sa = dot(m, da_[k]), sb = dot(m, db_[k]);
        lo_a = std::min(lo_a, sa), hi_a = std::max(hi_a, sa);
        lo_b = std::min(lo_b, sb), hi_b = std::max(hi_b, sb);
      }
      double c;  // the plane m . x = c midway in the gap
      if (hi_a < lo_b) c = 0.5 * hi_a + 0.5 * lo_b;
      else if (hi_b < lo_a) c = 0.5 * hi_b + 0.5 * lo_a;
      else continue;
      // a point o of the plane: c along m from the origin (exact doubles)
      const double mm = dot(m, m);
      if (!(mm > 0)) continue;
      const IV om = exact(m);
      const I t = I(c) / I(mm);
      const IV o{om.x * t, om.y * t, om.z * t};
      // o is an interval enclosure of a point of a plane parallel to m . x = c:
      // the certificate needs all six signs certain, whatever point of it
      int sa = 0, sb = 0;
      bool ok = true;
      for (int k = 0; k < 3 && ok; ++k) {
        const int x = side(om, o, ia_[k]), y = side(om, o, ib_[k]);
        ok = x != 0 && y != 0 && (sa == 0 || x == sa) && (sb == 0 || y == sb);
        sa = x, sb = y;
      }
      if (ok && sa == -sb) return true;
    }
    return false;
  }

  bool apart_at_vertex(int va, int vb) const {
    // In the plane across the normal, the directions from v to the other
    // corners of a, and from the other corners of b to v, must fit in an
    // open half-plane: m points to its middle.
    const DV e1 = unit(cross(normal_, std::abs(normal_.x) < 0.9 ? DV{1, 0, 0} : DV{0, 1, 0}));
    const DV e2 = cross(normal_, e1);
    std::array<double, 4> angle;
    int n = 0;
    for (int k = 0; k < 3; ++k) {
      if (k != va) {
        const DV d = sub(da_[k], da_[va]);
        angle[n++] = std::atan2(dot(d, e2), dot(d, e1));
      }
    }
    for (int k = 0; k < 3; ++k) {
      if (k != vb) {
        const DV d = sub(db_[vb], db_[k]);
        angle[n++] = std::atan2(dot(d, e2), dot(d, e1));
      }
    }
    std::sort(angle.begin(), angle.end());
    double gap = angle[0] + 2 * M_PI - angle[3], after = angle[3];  // the largest gap, after `after`
    for (int k = 0; k < 3; ++k)
      if (angle[k + 1] - angle[k] > gap) gap = angle[k + 1] - angle[k], after = angle[k];
    if (gap <= M_PI) return false;
    const double middle = after + 0.5 * gap + M_PI;  // opposite the gap's middle
    const DV m = add(DV{e1.x * std::cos(middle), e1.y * std::cos(middle), e1.z * std::cos(middle)},
                     DV{e2.x * std::sin(middle), e2.y * std::sin(middle), e2.z * std::sin(middle)});
    const IV om = exact(m);
    for (int k = 0; k < 3; ++k) {
      if (k != va && side(om, ia_[va], ia_[k]) != 1) return false;
      if (k != vb && side(om, ib_[vb], ib_[k]) != -1) return false;
    }
    return true;
  }

  bool apart_at_edge(int p, int q, int r, int s) const {
    // m = (q - p) x normal, in intervals: exactly perpendicular to pq, so
    // the plane through p with normal m contains the line pq.
    const IV d{ia_[q].x - ia_[p].x, ia_[q].y - ia_[p].y, ia_[q].z - ia_[p].z};
    const IV n = exact(normal_);
    const IV m{d.y * n.z - d.z * n.y, d.z * n.x - d.x * n.z, d.x * n.y - d.y * n.x};
    const int x = side(m, ia_[p], ia_[r]), y = side(m, ia_[p], ib_[s]);
    return x != 0 && y == -x;
  }

  std::array<IV, 3> ia_, ib_;
  std::array<DV, 3> da_, db_;
  DV normal_;
};

/// CGAL's static filter for orientation(p, q, r, s) on doubles
/// (Static_filters/Orientation_3.h, its steps and bound): 1 or -1 when it
/// decides a sign, 0 when it decides ZERO (all four points in one
/// coordinate plane), 2 when it leaves the sign to the slower filters.
inline int static_orientation(const Point3d& p, const Point3d& q, const Point3d& r, const Point3d& s) {
  const double pqx = q[0] - p[0], pqy = q[1] - p[1], pqz = q[2] - p[2];
  const double prx = r[0] - p[0], pry = r[1] - p[1], prz = r[2] - p[2];
  const double psx = s[0] - p[0], psy = s[1] - p[1], psz = s[2] - p[2];
  double maxx = std::max({std::abs(pqx), std::abs(prx), std::abs(psx)});
  double maxy = std::max({std::abs(pqy), std::abs(pry), std::abs(psy)});
  double maxz = std::max({std::abs(pqz), std::abs(prz), std::abs(psz)});
  const double det = CGAL::determinant(pqx, pqy, pqz, prx, pry, prz, psx, psy, psz);
  const double eps = 5.1107127829973299e-15 * maxx * maxy * maxz;
  if (maxx > maxz) std::swap(maxx, maxz);
  if (maxy > maxz) std::swap(maxy, maxz);
  else if (maxy < maxx) std::swap(maxx, maxy);
  if (maxx < 1e-97) return maxx == 0 ? 0 : 2;
  if (maxz < 1e102) {
    if (det > eps) return 1;
    if (det < -eps) return -1;
  }
  return 2;
}

/// What CGAL's static filter says of each triangle's corners (other than
/// shared ones) against the other's plane, the first step of CGAL's own
/// test. `apart`: all of one triangle's strictly on one side, so the faces
/// meet at most in their shared corners (exact: the filter certifies the
/// signs). `uncertain`: the filter leaves a sign to slower arithmetic, as
/// where a corner lies on or next to the other plane and the interval
/// filter fails too unless its arithmetic happens to be exact: neighbours
/// in a planar region whose rounded vertices lie just off their plane;
/// and, exactly, points on two parallel lines (a flat side of a tube
/// extracted from vertical grid lines: four such points are coplanar,
/// though no difference of their coordinates says so), or a corner on the
/// line where two such sides meet. `decided`: every sign decided (corners
/// in one coordinate plane are decided ZERO), CGAL's test goes fast.
enum class Sides { apart, uncertain, decided };

inline Sides static_sides(const Tri<InputKernel>& a, const Tri<InputKernel>& b) {
  auto at = [](const InputKernel::Point_3& p) { return Point3d{p.x(), p.y(), p.z()}; };
  const std::array<Point3d, 3> pa{at(a.p[0]), at(a.p[1]), at(a.p[2])}, pb{at(b.p[0]), at(b.p[1]), at(b.p[2])};
  bool uncertain = false;
  auto apart = [&](const Tri<InputKernel>& t, const std::array<Point3d, 3>& pt, const Tri<InputKernel>& o,
                   const std::array<Point3d, 3>& po) {
    int side = 0;  // +-1 while every corner asked is strictly on that side, 0 before, 3 otherwise
    for (int j = 0; j < 3; ++j) {
      if (o.id[j] == t.id[0] || o.id[j] == t.id[1] || o.id[j] == t.id[2]) continue;  // a shared corner
      const int s = static_orientation(pt[0], pt[1], pt[2], po[std::size_t(j)]);
      if (s == 2) uncertain = true;
      side = (s == 1 || s == -1) && (side == 0 || side == s) ? s : 3;
    }
    return side == 1 || side == -1;
  };
  if (apart(a, pa, b, pb) || apart(b, pb, a, pa)) return Sides::apart;
  return uncertain ? Sides::uncertain : Sides::decided;
}

/// The axis (0, 1, 2) whose coordinate all six corners share exactly, or -1.
/// Such triangles lie in one axis-aligned plane — the flat sides of CAD
/// parts, and of the grid surfaces rebuild extracts next to them — where
/// CGAL's three-dimensional tests take their coplanar branches, whose
/// predicates (coplanar orientation) have no static filter: interval
/// arithmetic under a switched rounding mode, for every pair.
inline int common_axis_plane(const Tri<InputKernel>& a, const Tri<InputKernel>& b) {
  for (int k = 0; k < 3; ++k) {
    const double c = a.p[0][k];
    if (a.p[1][k] == c && a.p[2][k] == c && b.p[0][k] == c && b.p[1][k] == c && b.p[2][k] == c) return k;
  }
  return -1;
}

/// In the plane x_axis = const, dropping that coordinate is a bijection onto
/// the plane of the other two, so intersections there are the
/// intersections of the projections, decided by CGAL's two-dimensional
/// orientation predicate (statically filtered on doubles, exact).
class AxisPlane {
 public:
  using P2 = InputKernel::Point_2;
  explicit AxisPlane(int axis) : u_(axis == 0 ? 1 : 0), v_(axis == 2 ? 1 : 2) {}
  P2 operator()(const InputKernel::Point_3& p) const { return {p[u_], p[v_]}; }

  /// Two non-degenerate triangles v a b and v c d with the common corner v
  /// share another point exactly when their angles at v (each less than a
  /// half turn) share a direction: near v each triangle is its angle, and
  /// the common part of two triangles is convex. Two such arcs of
  /// directions meet exactly when one holds an end of the other.
  static bool angles_meet(const P2& v, P2 a, P2 b, P2 c, P2 d) {
    if (CGAL::orientation(v, a, b) == CGAL::RIGHT_TURN) std::swap(a, b);  // counterclockwise from a to b
    if (CGAL::orientation(v, c, d) == CGAL::RIGHT_TURN) std::swap(c, d);
    // x in the closed angle from a to b: not right of v->a, not left of v->b
    auto in = [&v](const P2& from, const P2& to, const P2& x) {
      return CGAL::orientation(v, from, x) != CGAL::RIGHT_TURN && CGAL::orientation(v, to, x) != CGAL::LEFT_TURN;
    };
    return in(a, b, c) || in(a, b, d) || in(c, d, a) || in(c, d, b);
  }

 private:
  int u_, v_;
};

/// faces_intersect() for two non-degenerate triangles in the plane
/// x_axis = const, with the same semantics, in two dimensions.
inline bool faces_intersect_in_axis_plane(const Tri<InputKernel>& a, const Tri<InputKernel>& b, int axis,
                                          int shared, const int ia[3], const int ib[3]) {
  const AxisPlane to2(axis);
  const std::array<AxisPlane::P2, 3> pa{to2(a.p[0]), to2(a.p[1]), to2(a.p[2])},
      pb{to2(b.p[0]), to2(b.p[1]), to2(b.p[2])};
  switch (shared) {
    case 0:
      return CGAL::do_intersect(InputKernel::Triangle_2(pa[0], pa[1], pa[2]),
                                InputKernel::Triangle_2(pb[0], pb[1], pb[2]));
    case 1: {
      const int i = ia[0], j = ib[0];
      return AxisPlane::angles_meet(pa[i], pa[(i + 1) % 3], pa[(i + 2) % 3], pb[(j + 1) % 3], pb[(j + 2) % 3]);
    }
    case 2: {  // coplanar_orientation(p, q, r, s) == POSITIVE: r and s on one side of pq
      const auto &p = pa[ia[0]], &q = pa[ia[1]];
      return CGAL::orientation(p, q, pa[3 - ia[0] - ia[1]]) == CGAL::orientation(p, q, pb[3 - ib[0] - ib[1]]);
    }
    default:
      return true;
  }
}

}  // namespace

template <class K>
bool faces_intersect(const Tri<K>& a, const Tri<K>& b) {
  int shared = 0, ia[3], ib[3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (a.id[i] == b.id[j]) {
        ia[shared] = i;
        ib[shared] = j;
        ++shared;
        break;
      }
  if (a.degenerate || b.degenerate) {
    if (shared > 0) return false;  // see the header: reported as degenerate instead
    return primitives_intersect<K>(primitive(a), primitive(b));
  }
  // On doubles, CGAL's static filters decide most pairs at once; they fail
  // (and throw to the exact fallback, Mpzf) where a corner lies on or next
  // to the other triangle's plane. Only those are given the certificate
  // first; pairs the filter shows apart are answered at once.
  bool certify_first = true;
  if constexpr (std::is_same_v<K, InputKernel>) {
    if (const int axis = common_axis_plane(a, b); axis >= 0)
      return faces_intersect_in_axis_plane(a, b, axis, shared, ia, ib);
    const Sides sides = static_sides(a, b);
    if (sides == Sides::apart) return false;
    certify_first = sides == Sides::uncertain;
  }
  if (shared < 3 && certify_first) {
    CGAL::Protect_FPU_rounding<true> upward;  // the intervals' arithmetic
    if (Separation(a, b).apart(shared, ia, ib)) return false;
  }
  using Triangle = typename K::Triangle_3;
  switch (shared) {
    case 0:
      return CGAL::do_intersect(Triangle(a.p[0], a.p[1], a.p[2]), Triangle(b.p[0], b.p[1], b.p[2]));
    case 1: {
      const int i = ia[0], j = ib[0];
      return edge_meets_triangle<K>(a.p[(i + 1) % 3], a.p[(i + 2) % 3], b) ||
             edge_meets_triangle<K>(b.p[(j + 1) % 3], b.p[(j + 2) % 3], a);
    }
    case 2: {
      const auto& p = a.p[ia[0]];
      const auto& q = a.p[ia[1]];
      const auto& r = a.p[3 - ia[0] - ia[1]];
      const auto& s = b.p[3 - ib[0] - ib[1]];
      return CGAL::coplanar(p, q, r, s) && CGAL::coplanar_orientation(p, q, r, s) == CGAL::POSITIVE;
    }
    default:
      return true;  // the same three vertices: a duplicate face
  }
}

template bool faces_intersect<InputKernel>(const Tri<InputKernel>&, const Tri<InputKernel>&);
template bool faces_intersect<Kernel>(const Tri<Kernel>&, const Tri<Kernel>&);

}  // namespace polyheal::detail
