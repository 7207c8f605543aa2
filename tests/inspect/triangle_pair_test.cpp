// The one exact triangle-pair test (inspect/detail/triangle_pair.h), on the
// exact kernel's lazy rational points and on doubles: its answers against
// CGAL's exact predicates applied directly, on the configurations where its
// cheap separation certificate runs instead of them — nearly or exactly
// (obliquely, or in a plane z = const) coplanar fans of needles, as slicing
// and a planar region's rounded points leave them.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include <CGAL/intersections.h>

#include "polyheal/inspect/detail/triangle_pair.h"
#include "polyheal/mesh/mesh.h"

using namespace polyheal;

namespace {

using FT = Kernel::FT;
using Tri = detail::Tri<Kernel>;

/// Points of the oblique plane through a, b, c (doubles) at rational
/// parameters (s, t) / 9973, lifted along the plane's normal by h / 9973:
/// exact rationals that no double represents, exactly coplanar when h = 0.
struct Plane {
  Point a, b, c;
  Kernel::Vector_3 n;
  Point at(double s, double t, double h) const {
    const FT k(9973);
    const FT fs(std::round(s * 1e6)), ft(std::round(t * 1e6)), fh(std::round(h * 1e6));
    return a + (b - a) * (fs / (k * FT(1e6))) + (c - a) * (ft / (k * FT(1e6))) + n * (fh / (k * FT(1e6)));
  }
};

/// An oblique plane through three random points near the origin.
Plane random_plane(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Plane pl;
  pl.a = Point(u(rng), u(rng), u(rng));
  pl.b = Point(u(rng) + 2, u(rng), u(rng));
  pl.c = Point(u(rng), u(rng) + 2, u(rng));
  pl.n = CGAL::cross_product(pl.b - pl.a, pl.c - pl.a);
  return pl;
}

/// CGAL's predicates, applied directly, in the pair test's semantics.
template <class K>
bool truth(const detail::Tri<K>& x, const detail::Tri<K>& y, int shared) {
  using T = typename K::Triangle_3;
  using S = typename K::Segment_3;
  const T tx(x.p[0], x.p[1], x.p[2]), ty(y.p[0], y.p[1], y.p[2]);
  switch (shared) {
    case 0: return CGAL::do_intersect(tx, ty);
    case 1:  // x.p[0] == y.p[0]
      return CGAL::do_intersect(S(x.p[1], x.p[2]), ty) || CGAL::do_intersect(S(y.p[1], y.p[2]), tx);
    default:  // the edge x.p[0] x.p[1] is y's edge; x.p[2], y.p[2] opposite
      return CGAL::coplanar(x.p[0], x.p[1], x.p[2], y.p[2]) &&
             CGAL::coplanar_orientation(x.p[0], x.p[1], x.p[2], y.p[2]) == CGAL::POSITIVE;
  }
}

/// A fan of needles in `pl`, lifted by +-h, as one pair of the three
/// configurations (0: needles of neighbouring fans, 1: of one fan, 2:
/// across an edge), each triangle's corners through `point`.
template <class K, class ToPoint>
std::pair<detail::Tri<K>, detail::Tri<K>> needle_pair(const Plane& pl, double h, int shared, std::mt19937& rng,
                                                      ToPoint point) {
  std::uniform_real_distribution<double> u(-1.0, 1.0), angle(0.0, 2 * M_PI), radius(0.2, 3.0);
  const double s0 = u(rng), t0 = u(rng);
  auto corner = [&](double th, double r) { return pl.at(s0 + r * std::cos(th), t0 + r * std::sin(th), h * u(rng)); };
  const double th = angle(rng), w = 0.02 + 0.05 * (u(rng) + 1), gap = 0.03 * u(rng);  // gap < 0: overlap
  const auto v = point(pl.at(s0, t0, 0));
  const auto a1 = point(corner(th, radius(rng))), a2 = point(corner(th + w, radius(rng)));
  const auto b1 = point(corner(th + w + gap, radius(rng))), b2 = point(corner(th + 2 * w + gap, radius(rng)));
  const std::uint64_t V = 1, A1 = 2, A2 = 3, B1 = 4, B2 = 5;
  if (shared == 0) {  // two needles of neighbouring fans: b's apex moved off v
    const auto w0 = point(pl.at(s0 + 0.05 * u(rng), t0 + 0.05 * u(rng), h * u(rng)));
    return {detail::make_tri<K>(v, a1, a2, V, A1, A2), detail::make_tri<K>(w0, b1, b2, 6, B1, B2)};
  }
  if (shared == 1)  // two needles of one fan
    return {detail::make_tri<K>(v, a1, a2, V, A1, A2), detail::make_tri<K>(v, b1, b2, V, B1, B2)};
  // two needles across the edge v a2; b1 beside a2 (fold when on a1's side)
  return {detail::make_tri<K>(v, a2, a1, V, A2, A1), detail::make_tri<K>(v, a2, b1, V, A2, B1)};
}

}  // namespace

TEST_CASE("triangle_pair: nearly coplanar rational fans are decided as CGAL's exact predicates decide them",
          "[inspect]") {
  std::mt19937 rng(5);
  // Heights over the plane, one per row: exactly in it; an ulp-scale lift
  // (no interval filter decides those); well out of it.
  const double heights[] = {0.0, 1e-12, 1e-3};
  std::size_t intersecting[3] = {0, 0, 0}, apart[3] = {0, 0, 0};
  for (int trial = 0; trial < 900; ++trial) {
    const Plane pl = random_plane(rng);
    const double h = heights[(trial / 3) % 3];
    const int shared = trial % 3;
    const auto [x, y] = needle_pair<Kernel>(pl, h, shared, rng, [](const Point& p) { return p; });
    if (x.degenerate || y.degenerate) continue;
    const bool want = truth(x, y, shared);
    INFO("trial " << trial << ", shared " << shared << ", height " << h);
    CHECK(detail::faces_intersect<Kernel>(x, y) == want);
    CHECK(detail::faces_intersect<Kernel>(y, x) == want);
    ++(want ? intersecting : apart)[shared];
  }
  // both answers occur in every configuration (the table is not one-sided)
  for (int k = 0; k < 3; ++k) {
    CHECK(intersecting[k] > 10);
    CHECK(apart[k] > 10);
  }
}

TEST_CASE("triangle_pair: nearly and exactly coplanar fans of doubles are decided as CGAL's predicates decide them",
          "[inspect]") {
  // On doubles the certificate runs first only where CGAL's static filter
  // leaves a corner's side of the other plane undecided, as a planar
  // region's rounded points make: here the fans' corners rounded to doubles
  // in an oblique plane (nearly coplanar, or lifted), and in a plane
  // z = const (exactly coplanar, decided ZERO by the filter: left to CGAL,
  // whose interval filter decides such pairs).
  std::mt19937 rng(11);
  const double heights[] = {0.0, 1e-12, 1e-3};
  auto to_input = [](const Point& p) { return InputKernel::Point_3(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())); };
  std::size_t intersecting[2][3] = {{0, 0, 0}, {0, 0, 0}}, apart[2][3] = {{0, 0, 0}, {0, 0, 0}};
  for (int trial = 0; trial < 1800; ++trial) {
    const bool flat = trial >= 900;  // the plane z = const
    Plane pl = random_plane(rng);
    if (flat) {
      pl.b = Point(pl.b.x(), pl.b.y(), pl.a.z());
      pl.c = Point(pl.c.x(), pl.c.y(), pl.a.z());
      pl.n = CGAL::cross_product(pl.b - pl.a, pl.c - pl.a);
    }
    const double h = flat ? 0.0 : heights[(trial / 3) % 3];
    const int shared = trial % 3;
    const auto [x, y] = needle_pair<InputKernel>(pl, h, shared, rng, to_input);
    if (x.degenerate || y.degenerate) continue;
    if (flat) REQUIRE(CGAL::coplanar(x.p[0], x.p[1], x.p[2], y.p[2]));
    const bool want = truth(x, y, shared);
    INFO("trial " << trial << ", shared " << shared << ", height " << h);
    CHECK(detail::faces_intersect<InputKernel>(x, y) == want);
    CHECK(detail::faces_intersect<InputKernel>(y, x) == want);
    ++(want ? intersecting : apart)[flat][shared];
  }
  // Both answers occur in every configuration, but one: rounded off their
  // oblique plane, two faces across an edge are never exactly coplanar, so
  // they never fold (they meet only in the edge).
  for (int f = 0; f < 2; ++f)
    for (int k = 0; k < 3; ++k) {
      INFO("flat " << f << ", shared " << k);
      if (f == 1 || k < 2) CHECK(intersecting[f][k] > 10);
      CHECK(apart[f][k] > 10);
    }
  CHECK(intersecting[0][2] == 0);
}

TEST_CASE("triangle_pair: corners on parallel lines of doubles (a tube's flat sides and creases) are decided as CGAL's predicates decide them",
          "[inspect]") {
  // A grid extracted across a tube's oblique flat sides puts its points on
  // vertical lines: any four on two lines are exactly coplanar though no
  // difference of their coordinates shows it, and a corner on the line
  // where two sides meet lies exactly in both sides' planes. CGAL's filters
  // leave such pairs to exact arithmetic, so the certificate runs first;
  // its answers must be CGAL's. Three lines at oblique positions (doubles),
  // points at random heights; pairs from two lines (one side) or across
  // the middle line (two sides), sharing 0, 1 or 2 corners.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0), z(0.0, 4.0);
  using P = InputKernel::Point_3;
  using T = detail::Tri<InputKernel>;
  std::size_t intersecting[2][3] = {{0, 0, 0}, {0, 0, 0}}, apart[2][3] = {{0, 0, 0}, {0, 0, 0}};
  for (int trial = 0; trial < 6000; ++trial) {
    const double x0 = u(rng), y0 = u(rng);
    const double lines[3][2] = {{x0, y0}, {x0 + 1.3 + 0.1 * u(rng), y0 + 0.7 + 0.1 * u(rng)},
                                {x0 + 1.9 + 0.1 * u(rng), y0 + 2.1 + 0.1 * u(rng)}};
    const bool crease = trial % 2 == 1;
    const int shared = (trial / 2) % 3;
    auto on = [&](int line) { return P(lines[line][0], lines[line][1], z(rng)); };
    // a on lines 0 and 1; b on 0 and 1 (one side) or 1 and 2 (across the crease)
    const int b_lines[2] = {crease ? 1 : 0, crease ? 2 : 1};
    std::array<P, 3> a{on(0), on(1), on(rng() % 2 ? 0 : 1)};
    std::array<P, 3> b{on(b_lines[0]), on(b_lines[1]), on(b_lines[rng() % 2])};
    std::array<std::uint64_t, 3> ib{4, 5, 6};
    // shared corners: b's first `shared` corners are a's, on a line b uses
    if (shared >= 1) {
      if (crease) a[1] = b[0];  // a's corner on line 1
      else b[0] = a[0];
      ib[0] = crease ? 2 : 1;
    }
    if (shared == 2) {
      if (crease) continue;  // an edge shared across the crease would need two points on line 1
      b[1] = a[1];
      ib[1] = 2;
    }
    const T x = detail::make_tri<InputKernel>(a[0], a[1], a[2], 1, 2, 3);
    const T y = detail::make_tri<InputKernel>(b[0], b[1], b[2], ib[0], ib[1], ib[2]);
    if (x.degenerate || y.degenerate) continue;
    // truth() wants the shared corners first, in order
    const T xs = shared == 1 && crease ? detail::make_tri<InputKernel>(a[1], a[2], a[0], 2, 3, 1) : x;
    const bool want = truth(xs, y, shared);
    INFO("trial " << trial << ", crease " << crease << ", shared " << shared);
    CHECK(detail::faces_intersect<InputKernel>(x, y) == want);
    CHECK(detail::faces_intersect<InputKernel>(y, x) == want);
    ++(want ? intersecting : apart)[crease][shared];
  }
  // Both answers occur in every configuration; across the crease, faces
  // share at most a corner.
  for (int c = 0; c < 2; ++c)
    for (int k = 0; k < (c ? 2 : 3); ++k) {
      INFO("crease " << c << ", shared " << k);
      CHECK(intersecting[c][k] > 10);
      CHECK(apart[c][k] > 10);
    }
}

TEST_CASE("triangle_pair: needles of one fan whose sides from the apex run along one line", "[inspect]") {
  // Where a side of each needle leaves the shared apex v along the same
  // line, no plane through v has the two strictly apart: the separation
  // cannot be shown, and the exact test must answer. One row per case,
  // each in random oblique planes, with rational points.
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Plane pl = random_plane(rng);
    const double s0 = u(rng), t0 = u(rng), th = 3 * u(rng), w = 0.05;
    const Point v = pl.at(s0, t0, 0);
    const Point a1 = pl.at(s0 + 2 * std::cos(th), t0 + 2 * std::sin(th), 0);
    const Point a2 = pl.at(s0 + 2 * std::cos(th + w), t0 + 2 * std::sin(th + w), 0);
    const Point ahead = v + (a2 - v) * (FT(1) / FT(3));   // on the side v a2
    const Point behind = v - (a2 - v) * (FT(1) / FT(3));  // on its line, beyond v
    const Point out = pl.at(s0 + 2 * std::cos(th + 2 * w), t0 + 2 * std::sin(th + 2 * w), 0);
    const Point back = pl.at(s0 - 2 * std::cos(th + 2 * w), t0 - 2 * std::sin(th + 2 * w), 0);
    const Tri x = detail::make_tri<Kernel>(v, a1, a2, 1, 2, 3);
    struct Row {
      Point b1, b2;
      bool meet;
      const char* why;
    };
    const Row rows[] = {
        {ahead, out, true, "a side along the other's side: they share a segment"},
        {behind, back, false, "a side along the other's, beyond the apex: only the apex is shared"},
    };
    for (const Row& row : rows) {
      const Tri y = detail::make_tri<Kernel>(v, row.b1, row.b2, 1, 4, 5);
      INFO(row.why << ", trial " << trial);
      REQUIRE(truth(x, y, 1) == row.meet);
      CHECK(detail::faces_intersect<Kernel>(x, y) == row.meet);
      CHECK(detail::faces_intersect<Kernel>(y, x) == row.meet);
    }
  }
}

TEST_CASE("triangle_pair: pairs in one axis-aligned plane, corners on a small grid, are decided as CGAL's predicates decide them",
          "[inspect]") {
  // Corners sharing one coordinate exactly (a CAD part's flat sides, the grid
  // surface rebuild extracts beside them) are decided in the plane of the
  // other two coordinates. Corners on a 5 x 5 grid make the contacts that
  // matter frequent: a corner on the other's edge, edges along one line,
  // coincident corners of distinct vertices, a side along the other's side
  // at the shared corner. Each axis; 0, 1 or 2 shared corners; each pair
  // asked in both orders and with its corners rotated.
  std::mt19937 rng(17);
  std::uniform_int_distribution<int> g(0, 4);
  using P = InputKernel::Point_3;
  using T = detail::Tri<InputKernel>;
  std::size_t intersecting[3] = {0, 0, 0}, apart[3] = {0, 0, 0};
  for (int trial = 0; trial < 9000; ++trial) {
    const int axis = trial % 3, shared = (trial / 3) % 3;
    auto on = [&]() {
      double c[3];
      c[axis] = 0.375;
      c[(axis + 1) % 3] = 0.25 * g(rng) - 0.5;
      c[(axis + 2) % 3] = 0.5 * g(rng) + 1;
      return P(c[0], c[1], c[2]);
    };
    std::array<P, 3> a{on(), on(), on()}, b{on(), on(), on()};
    std::array<std::uint64_t, 3> ib{4, 5, 6};
    for (int k = 0; k < shared; ++k) {  // truth() wants the shared corners first, in order
      b[std::size_t(k)] = a[std::size_t(k)];
      ib[std::size_t(k)] = std::uint64_t(k + 1);
    }
    const T x = detail::make_tri<InputKernel>(a[0], a[1], a[2], 1, 2, 3);
    const T y = detail::make_tri<InputKernel>(b[0], b[1], b[2], ib[0], ib[1], ib[2]);
    if (x.degenerate || y.degenerate) continue;
    const bool want = truth(x, y, shared);
    const int r = int(rng() % 3);
    auto rotated = [r](const T& t) {
      return detail::make_tri<InputKernel>(t.p[std::size_t(r)], t.p[std::size_t((r + 1) % 3)],
                                           t.p[std::size_t((r + 2) % 3)], t.id[std::size_t(r)],
                                           t.id[std::size_t((r + 1) % 3)], t.id[std::size_t((r + 2) % 3)]);
    };
    INFO("trial " << trial << ", axis " << axis << ", shared " << shared);
    CHECK(detail::faces_intersect<InputKernel>(x, y) == want);
    CHECK(detail::faces_intersect<InputKernel>(y, x) == want);
    CHECK(detail::faces_intersect<InputKernel>(rotated(x), y) == want);
    CHECK(detail::faces_intersect<InputKernel>(y, rotated(x)) == want);
    ++(want ? intersecting : apart)[shared];
  }
  for (int k = 0; k < 3; ++k) {
    INFO("shared " << k);
    CHECK(intersecting[k] > 100);
    CHECK(apart[k] > 100);
  }
}
