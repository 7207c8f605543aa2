// polyheal distances (repair/detail/distance.h): the point-triangle distance
// every tolerance test and Hausdorff measurement is built on, and the bounds
// that let the bounded-error Hausdorff distance stop bisecting.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>

#include <tbb/global_control.h>

#include "polyheal/mesh/mesh.h"
#include "polyheal/io/read.h"
#include "polyheal/repair/detail/distance.h"
#include "polyheal/repair/detail/winding.h"
#include "support/builders.h"

using namespace polyheal;

namespace {

/// The rectangle [x0, x1] x [y0, y1] at height z as CAD tessellators leave it:
/// a fan from the top-left corner to n points along the bottom side and a
/// fan from the bottom-right corner to n points along the top side, so
/// nearly every triangle is a needle (n = 200 on a 4 x 1 cell: 0.02 wide,
/// up to 4 long).
void add_fan_cell(Soup& s, double x0, double x1, double y0, double y1, double z, int n) {
  const Index base = static_cast<Index>(s.points.size());
  for (int i = 0; i <= n; ++i) s.points.push_back({x0 + (x1 - x0) * i / n, y0, z});  // bottom: base + i
  for (int i = 0; i <= n; ++i) s.points.push_back({x0 + (x1 - x0) * i / n, y1, z});  // top: base + n + 1 + i
  const Index top0 = base + static_cast<Index>(n) + 1, bottom_n = base + static_cast<Index>(n);
  for (int i = 0; i < n; ++i) s.add_triangle(top0, base + Index(i), base + Index(i) + 1);
  for (int i = 0; i < n; ++i) s.add_triangle(bottom_n, top0 + Index(i) + 1, top0 + Index(i));
}

/// A 10 x 2 plate at z = 0 with the square hole [4, 6] x [0.5, 1.5]: the
/// eight cells of a 3 x 3 grid around it, each tessellated by add_fan_cell.
/// Neighbouring cells meet along sides made of the same points (welded).
Soup plate_with_hole(int n) {
  Soup s;
  const double xs[4] = {0, 4, 6, 10}, ys[4] = {0, 0.5, 1.5, 2};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (i != 1 || j != 1) add_fan_cell(s, xs[i], xs[i + 1], ys[j], ys[j + 1], 0.0, n);
  return s;
}

/// The same plate, two triangles per cell; filled: two triangles in all,
/// over the hole too (their centroids lie on the plate, not over the hole).
Soup coarse_plate(bool filled) {
  Soup s;
  if (filled) return test::soup({{0, 0, 0}, {10, 0, 0}, {10, 2, 0}, {0, 2, 0}}, {{0, 1, 2}, {0, 2, 3}});
  const double xs[4] = {0, 4, 6, 10}, ys[4] = {0, 0.5, 1.5, 2};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      if (i == 1 && j == 1) continue;
      const Index b = static_cast<Index>(s.points.size());
      s.points.push_back({xs[i], ys[j], 0});
      s.points.push_back({xs[i + 1], ys[j], 0});
      s.points.push_back({xs[i + 1], ys[j + 1], 0});
      s.points.push_back({xs[i], ys[j + 1], 0});
      s.add_triangle(b, b + 1, b + 2);
      s.add_triangle(b, b + 2, b + 3);
    }
  return s;
}

/// The surface triangle nearest p (cover_bound takes its plane).
std::size_t nearest_triangle(const detail::SurfaceDistance& d, const Point3d& p) { return d.nearest(p).second; }

}  // namespace

TEST_CASE("distance: point-triangle distances agree with exact ones in every region", "[repair][distance]") {
  // The tolerance test and the Hausdorff distance measure in doubles; the
  // nearest point's region (vertex, edge, face) is chosen by signs of dot
  // products. Checked against exact rational distances for points around
  // well-shaped triangles, needles, caps and a zero-area triangle.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  const std::vector<std::array<Point3d, 3>> triangles{
      {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}},
      {{{0, 0, 0}, {1, 0, 0}, {0.5, 1e-3, 0}}},            // a cap
      {{{0, 0, 0}, {1, 0, 0}, {1, 1e-3, 1e-4}}},           // a needle
      {{{0.3, -0.2, 0.7}, {-1.1, 0.4, 0.2}, {0.6, 1.3, -0.9}}},
      {{{0, 0, 0}, {1, 1, 1}, {2, 2, 2}}},                 // zero area: its edges
  };
  for (const auto& t : triangles) {
    const Kernel::Triangle_3 exact(Point(t[0][0], t[0][1], t[0][2]), Point(t[1][0], t[1][1], t[1][2]),
                                   Point(t[2][0], t[2][1], t[2][2]));
    for (int k = 0; k < 2000; ++k) {
      const Point3d p{u(rng), u(rng), u(rng)};
      const Point q(p[0], p[1], p[2]);
      const double want = exact.is_degenerate()
                              ? CGAL::to_double(std::min({CGAL::squared_distance(q, Kernel::Segment_3(exact[0], exact[1])),
                                                          CGAL::squared_distance(q, Kernel::Segment_3(exact[1], exact[2])),
                                                          CGAL::squared_distance(q, Kernel::Segment_3(exact[2], exact[0]))}))
                              : CGAL::to_double(CGAL::squared_distance(q, exact));
      const double got = detail::squared_distance_to_triangle(p, t[0], t[1], t[2]);
      INFO("point " << p[0] << " " << p[1] << " " << p[2]);
      CHECK(std::abs(got - want) <= 1e-12 * (1.0 + want));
    }
  }
}

TEST_CASE("distance: a piece over a planar fan region is bounded by its height, not by one needle",
          "[repair][distance]") {
  // One row per configuration: a triangle above the plate with the hole,
  // whether its projection lies in the plate (then the bound is its largest
  // corner height), and why.
  const Soup plate = plate_with_hole(200);
  const detail::SurfaceDistance d(plate);
  struct Row {
    std::array<Point3d, 3> piece;
    double bound;  // expected; infinity: must not be bounded
    const char* why;
  };
  constexpr double kNone = std::numeric_limits<double>::infinity();
  const Row rows[] = {
      {{{{0.5, 0.2, 0}, {3.5, 0.3, 0}, {2, 1.8, 0}}}, 0, "in the plate, over some 400 needles"},
      {{{{0.5, 0.2, 0.01}, {3.5, 0.3, 0.02}, {2, 1.8, 0.03}}}, 0.03, "the same, lifted: its highest corner"},
      {{{{0.5, 0.1, -0.01}, {9.5, 0.2, -0.01}, {5, 0.45, -0.01}}}, 0.01, "across the three cells below the hole, under the plate"},
      {{{{0, 0, 0}, {4, 0, 0}, {0, 2, 0}}}, 0, "corners on the plate's vertices, sides along its rim"},
      {{{{6, 0.5, 0}, {10, 0.5, 0}, {6, 1.5, 0}}}, 0, "a side along the hole's rim, from outside"},
      {{{{3.5, 0.2, 0}, {7, 0.2, 0}, {5, 1.9, 0}}}, kNone, "over part of the hole"},
      {{{{2, 0.2, 0}, {5, 0.2, 0}, {2, 1.8, 0}}}, kNone, "over a corner of the hole, its centroid on the plate"},
      {{{{1, 0.05, 0}, {9, 0.05, 0}, {5, 1.99, 0}}}, kNone, "over the whole hole (its rim inside the piece)"},
      {{{{-1, 0.5, 0}, {2, 0.5, 0}, {1, 1.5, 0}}}, kNone, "past the plate's rim"},
      {{{{4.5, 0.6, 0}, {5.5, 0.6, 0}, {5, 1.4, 0}}}, kNone, "inside the hole"},
  };
  for (const Row& row : rows) {
    INFO(row.why);
    // The needle nearest the first corner gives the plane (any of the plate's would).
    const std::size_t t = nearest_triangle(d, {row.piece[0][0] + 1e-3, row.piece[0][1] + 1e-3, 0});
    const double got = d.cover_bound(row.piece, t, 1.0);
    if (row.bound == kNone) {
      CHECK(got == kNone);
    } else {
      // (plus twice the 1e-9-of-its-size margin at corners it allows for rounding)
      double longest = 0;
      for (int k = 0; k < 3; ++k) {
        const Point3d &a = row.piece[k], &b = row.piece[(k + 1) % 3];
        longest = std::max(longest, std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]));
      }
      CHECK(got <= row.bound + 2e-9 * longest + 1e-12);
      CHECK(got >= row.bound - 1e-12);
      // A true upper bound: no point of the piece is farther from the plate.
      for (double a = 0; a <= 1; a += 0.125)
        for (double b = 0; a + b <= 1; b += 0.125) {
          Point3d p;
          for (int k = 0; k < 3; ++k)
            p[k] = row.piece[0][k] + a * (row.piece[1][k] - row.piece[0][k]) + b * (row.piece[2][k] - row.piece[0][k]);
          CHECK(std::sqrt(d.squared_distance(p)) <= got + 1e-12);
        }
    }
  }
  // A limit below the bound gives up.
  CHECK(d.cover_bound(rows[1].piece, nearest_triangle(d, {0.501, 0.201, 0}), 0.02) == kNone);
}

TEST_CASE("distance: a piece above a tilted fine plate is bounded by its height there",
          "[repair][distance]") {
  // The triangles under a piece lie in the prism it sweeps along the base
  // plane's normal, which cover_bound searches by its box: on a plate at
  // no axis (normal with every component) of small triangles (0.05), the
  // ones under a piece lifted off it are shifted from the piece's own box
  // by the lift along each axis; the bound must still find them all.
  const double c1 = std::cos(0.6), s1 = std::sin(0.6), c2 = std::cos(0.4), s2 = std::sin(0.4);
  auto tilt = [&](const Point3d& p) {  // about x by 0.6, then about z by 0.4
    const Point3d q{p[0], c1 * p[1] - s1 * p[2], s1 * p[1] + c1 * p[2]};
    return Point3d{c2 * q[0] - s2 * q[1], s2 * q[0] + c2 * q[1], q[2]};
  };
  Soup plate;
  const int n = 80;  // 4 x 4 in cells of 0.05
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) plate.points.push_back(tilt({0.05 * i, 0.05 * j, 0}));
  for (Index i = 0; i < Index(n); ++i)
    for (Index j = 0; j < Index(n); ++j) {
      const Index a = i * (n + 1) + j, b = a + n + 1;
      plate.add_triangle(a, b, b + 1);
      plate.add_triangle(a, b + 1, a + 1);
    }
  const detail::SurfaceDistance d(plate);
  for (const double lift : {0.1, 0.4}) {
    INFO("lifted by " << lift);
    const std::array<Point3d, 3> piece{tilt({1, 1, lift}), tilt({3, 1.2, lift}), tilt({1.5, 3, lift})};
    const std::size_t t = nearest_triangle(d, tilt({1.02, 1.02, 0}));
    const double got = d.cover_bound(piece, t, 1.0);
    CHECK(got >= lift - 1e-9);
    CHECK(got <= lift + 1e-8);  // (and the margin cover_bound adds for rounding)
  }
}

TEST_CASE("distance: a chord across a curved strip surface is bounded by the gap, not split to one strip",
          "[repair][distance]") {
  // A cylinder patch of radius 10 around the x axis tessellated as CAD
  // strips (40 facets of 0.01 rad, 10 long, each cut by its diagonal: 100:1
  // needles), and pieces whose corners lie on it and span many strips, as
  // an input facet does over a surface tessellated anew. No strip is near
  // a whole piece and no plane holds them, so only the gap between the
  // strips and the piece's plane over the piece bounds it; the bound must
  // be a true one and close to the true largest distance.
  const double R = 10;
  Soup strips;
  auto at = [&](double x, double angle) { return Point3d{x, R * std::sin(angle), R * std::cos(angle)}; };
  for (int i = 0; i <= 40; ++i) {
    strips.points.push_back(at(0, -0.2 + 0.01 * i));
    strips.points.push_back(at(10, -0.2 + 0.01 * i));
  }
  for (Index i = 0; i < 40; ++i) {
    strips.add_triangle(2 * i, 2 * i + 1, 2 * i + 3);
    strips.add_triangle(2 * i, 2 * i + 3, 2 * i + 2);
  }
  const detail::SurfaceDistance d(strips);
  const std::array<Point3d, 3> pieces[] = {
      {at(1, -0.1), at(9, -0.05), at(5, 0.1)},      // across 20 strips
      {at(0.5, -0.15), at(9.5, -0.149), at(5, -0.12)},  // a thin one along 3 strips
  };
  for (const auto& piece : pieces) {
    double largest = 0;  // the true largest distance, sampled
    for (double a = 0; a <= 1; a += 1.0 / 64)
      for (double b = 0; a + b <= 1; b += 1.0 / 64) {
        Point3d p;
        for (int k = 0; k < 3; ++k) p[k] = piece[0][k] + a * (piece[1][k] - piece[0][k]) + b * (piece[2][k] - piece[0][k]);
        largest = std::max(largest, std::sqrt(d.squared_distance(p)));
      }
    const std::size_t t = nearest_triangle(d, piece[0]);
    const double got = d.cover_bound(piece, t, 1.0);
    INFO("largest sampled " << largest << ", bound " << got);
    CHECK(got >= largest - 1e-12);
    // along the plane's normal rather than to the nearest point (up to
    // 0.2 rad between them), and over strips of sagitta 1.25e-4
    CHECK(got <= largest / std::cos(0.25) + 1.25e-4);
    CHECK(d.cover_bound(piece, t, 0.5 * largest) == std::numeric_limits<double>::infinity());
  }
}

TEST_CASE("distance: Hausdorff between fan and coarse tessellations of a plate sees the hole", "[repair][distance]") {
  // The same plate twice (needle fans, two triangles per cell): distance 0.
  // With the hole filled in the coarse one: 0.5, the distance from the
  // hole's centre to its rim, which a bound claiming that the two big
  // triangles lie over the fan plate would hide.
  const Soup fans = plate_with_hole(200);
  const double error = 1e-3;
  const std::array<double, 2> same = detail::one_sided_distances(fans, coarse_plate(false), error);
  CHECK(same[0] <= 1e-12);
  CHECK(same[1] <= 1e-12);
  const std::array<double, 2> filled = detail::one_sided_distances(fans, coarse_plate(true), error);
  CHECK(filled[0] <= 1e-12);                // every point of the fans is on the filled plate
  CHECK(filled[1] >= 0.5 - error - 1e-12);  // the filled hole's centre is 0.5 from the fans
  CHECK(filled[1] <= 0.5 + 1e-12);
}

TEST_CASE("distance: a triangle added at a corner of the input is measured against input beside it, not only "
          "input its box meets",
          "[repair][distance]") {
  // The input: a triangle in z = 0 with a corner at the origin, a wall at
  // x = 0.3 (its box does not meet the added triangle's, at x = 0), and 60
  // small triangles far away (so the measure indexes only the input the
  // added triangle can reach: within its longest edge of it). The added
  // triangle rises from the origin to z = 2 along x = 0: every point of it
  // is within 0.3 of the wall, and its top 2 from the first triangle. Measured
  // against the input near its own box only, the wall would be missed (2).
  Soup input = test::soup({{0, 0, 0}, {-1, 0, 0}, {0, -1, 0}, {0.3, -5, -1}, {0.3, 5, -1}, {0.3, 0, 5}},
                          {{0, 1, 2}, {3, 4, 5}});
  for (int i = 0; i < 60; ++i) {
    const Index b = static_cast<Index>(input.points.size());
    const double x = 100 + i;
    input.points.push_back({x, 0, 0});
    input.points.push_back({x + 0.5, 0, 0});
    input.points.push_back({x, 0.5, 0});
    input.add_triangle(b, b + 1, b + 2);
  }
  const double error = 1e-4;
  for (const Point3d& origin : {Point3d{0, 0, 0}, Point3d{1e-9, 0, 0}}) {  // on the input; not on it (all indexed)
    Soup output = input;
    const Index b = static_cast<Index>(output.points.size());
    output.points.push_back(origin);
    output.points.push_back({0, 0, 2});
    output.points.push_back({0, 0.2, 2});
    output.add_triangle(b, b + 1, b + 2);
    const std::array<double, 2> d = detail::one_sided_distances(input, output, error);
    INFO("added triangle from (" << origin[0] << ", 0, 0): " << d[1]);
    CHECK(d[0] <= 1e-12);  // the input is all in the output
    CHECK(d[1] >= 0.3 - error - 1e-9);
    CHECK(d[1] <= 0.3 + 1e-9);
    CHECK(detail::one_sided_distance(output, input, error) == d[1]);
  }
}

TEST_CASE("distance: faces in both soups count once per copy", "[repair][distance]") {
  // A face twice in one soup and once in the other: the copy left over is
  // at distance 0 (the same face is in the other soup); a face only in one
  // soup is measured.
  const Soup one = test::soup({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 1, 2}});
  Soup two = one;
  two.add_triangle(0, 1, 2);
  two.add_triangle(2, 1, 0);  // the same face, turned: the same triangle for distances
  std::array<double, 2> d = detail::one_sided_distances(one, two, 1e-6);
  CHECK(d[0] == 0.0);
  CHECK(d[1] == 0.0);
  two.add_triangle(0, 1, 3);  // standing on the first face's edge: its apex is 1 from it
  d = detail::one_sided_distances(one, two, 1e-6);
  CHECK(d[0] == 0.0);
  CHECK(d[1] >= 1.0 - 1e-6);
  CHECK(d[1] <= 1.0 + 1e-12);
}

TEST_CASE("distance: Hausdorff with a bound on one direction measures it only when the bound can matter",
          "[repair][distance]") {
  // a: a unit triangle and a second one 2 above it; b: the first, and a
  // triangle standing on its edge with its apex 1 from it. a -> b is
  // sqrt 2 (the lifted triangle's corner above (0, 1)), b -> a 1 (the apex).
  const Soup a = test::soup({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 2}, {1, 0, 2}, {0, 1, 2}}, {{0, 1, 2}, {3, 4, 5}});
  const Soup b = test::soup({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 1, 2}, {0, 1, 3}});
  const double error = 1e-6;
  const std::array<double, 2> d = detail::one_sided_distances(a, b, error);
  REQUIRE(d[0] > 1.4);
  REQUIRE(d[1] >= 1.0 - error);
  const double full = detail::hausdorff_distance(a, b, error);
  // b -> a at most 1 (true) or 1.2: below a -> b, the same answer unmeasured
  CHECK(detail::hausdorff_distance(a, b, error, 1.0) == full);
  CHECK(detail::hausdorff_distance(a, b, error, 1.2) == full);
  // the other way round b -> a is the larger direction: a bound above what
  // a -> b measures (its own distance, 1) makes it measured
  const double back = detail::hausdorff_distance(b, a, error);
  REQUIRE(back > 1.4);
  CHECK(detail::hausdorff_distance(b, a, error, 3.0) == back);
  CHECK(detail::hausdorff_distance(b, a, error, HUGE_VAL) == back);
}

TEST_CASE("distance: Hausdorff of a removed interior finds its deepest point", "[repair][distance]") {
  // A sphere of radius 1 with a second one of radius 0.5 inside it, against
  // the outer sphere alone: what a union leaves out, 0.5 deep. One vertex
  // of the inner sphere is pulled in to radius 0.15 and its ring to 0.2: a
  // pit whose bottom is the deepest point (from inside, the distance to the
  // outer surface is largest nearest the centre). Most inner triangles
  // finish on the first pass over one corner per grid cell; the pit's
  // bottom stands in its cell behind a ring vertex (lexicographically
  // first: the pit points along -x), 0.05 shallower, so only the Lipschitz
  // terms of that pass keep its triangles.
  const Soup outer = test::icosphere(1.0, 3);
  Soup inner = test::icosphere(0.5, 3);
  const Point3d towards{-1 / std::sqrt(1.25), 0.3 / std::sqrt(1.25), 0.4 / std::sqrt(1.25)};
  Index pit = 0;
  auto along = [&](const Point3d& p) { return p[0] * towards[0] + p[1] * towards[1] + p[2] * towards[2]; };
  for (Index v = 0; v < inner.points.size(); ++v)
    if (along(inner.points[v]) > along(inner.points[pit])) pit = v;
  std::vector<char> ring(inner.points.size(), 0);
  for (std::size_t f = 0; f < inner.face_count(); ++f) {
    const FaceView face = inner.face(f);
    if (std::find(face.begin(), face.end(), pit) != face.end())
      for (Index v : face) ring[v] = 1;
  }
  for (Index v = 0; v < inner.points.size(); ++v)
    if (ring[v]) {
      const double k = v == pit ? 0.3 : 0.4;
      inner.points[v] = {k * inner.points[v][0], k * inner.points[v][1], k * inner.points[v][2]};
    }
  const double error = 1e-3;
  const std::array<double, 2> d = detail::one_sided_distances(test::concat(outer, inner), outer, error);
  const double deepest = std::sqrt(detail::SurfaceDistance(outer).squared_distance(inner.points[pit]));
  INFO("got " << d[0] << ", the pit's bottom lies " << deepest << " deep");
  CHECK(deepest > 0.83);
  CHECK(d[0] >= deepest - 1e-12);
  CHECK(d[0] <= deepest + error);
  CHECK(d[1] <= 1e-12);  // the outer sphere is in both
}

TEST_CASE("distance: nearest-triangle, within and box queries agree with a search of every triangle",
          "[repair][distance]") {
  // The index splits long triangles into pieces (the needle fans of the
  // plate, up to 4 long beside 0.02-wide ones) and prunes by box distance;
  // neither may change an answer. Random well-shaped triangles are mixed in.
  Soup s = plate_with_hole(50);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 11.0), small(-0.5, 0.5);
  for (int k = 0; k < 300; ++k) {
    const Point3d c{u(rng), u(rng) / 5, small(rng)};
    const Index b = static_cast<Index>(s.points.size());
    for (int j = 0; j < 3; ++j) s.points.push_back({c[0] + small(rng), c[1] + small(rng), c[2] + small(rng)});
    s.add_triangle(b, b + 1, b + 2);
  }
  const detail::SurfaceDistance d(s);
  auto corner = [&](std::size_t f, int k) { return s.points[s.face(f)[k]]; };
  detail::SurfaceDistance::Recent recent;
  for (int k = 0; k < 3000; ++k) {
    const Point3d p{u(rng), u(rng) / 5, small(rng)};
    double want = std::numeric_limits<double>::infinity();
    for (std::size_t f = 0; f < s.face_count(); ++f)
      want = std::min(want, detail::squared_distance_to_triangle(p, corner(f, 0), corner(f, 1), corner(f, 2)));
    const auto [got, t] = d.nearest(p);
    INFO("point " << p[0] << " " << p[1] << " " << p[2]);
    // (the index keeps corners in a canonical order: the last bit may differ)
    const double slack = 1e-12 * (1 + want);
    CHECK(std::abs(got - want) <= slack);
    CHECK(std::abs(detail::squared_distance_to_triangle(p, corner(t, 0), corner(t, 1), corner(t, 2)) - want) <= slack);
    CHECK(std::abs(d.nearest(p, std::size_t(k) % s.face_count()).first - want) <= slack);  // any hint
    // "Is a triangle within r?" with either kind of hint: the last triangle
    // found, or the recent ones (kept across all these queries).
    for (double r2 : {0.0004, 0.01, 0.04}) {
      if (std::abs(want - r2) <= slack) continue;  // (the last bit may differ)
      std::size_t hint = std::size_t(k) % s.face_count();
      CHECK(d.any_within(p, r2, hint) == (want <= r2));
      CHECK(d.any_within(p, r2, recent) == (want <= r2));
    }
  }
  for (int k = 0; k < 300; ++k) {
    const Point3d c{u(rng), u(rng) / 5, small(rng)};
    const double r = 0.05 + 0.2 * (small(rng) + 0.5);
    const Point3d lo{c[0] - r, c[1] - r, c[2] - r}, hi{c[0] + r, c[1] + r, c[2] + r};
    std::vector<std::size_t> got = d.triangles_near(lo, hi);
    std::sort(got.begin(), got.end());
    CHECK(std::adjacent_find(got.begin(), got.end()) == got.end());  // each triangle once (in no particular order)
    const CGAL::Bbox_3 box(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    for (std::size_t f = 0; f < s.face_count(); ++f) {
      const InputKernel::Point_3 a(corner(f, 0)[0], corner(f, 0)[1], corner(f, 0)[2]),
          b(corner(f, 1)[0], corner(f, 1)[1], corner(f, 1)[2]), e(corner(f, 2)[0], corner(f, 2)[1], corner(f, 2)[2]);
      const bool listed = std::binary_search(got.begin(), got.end(), f);
      INFO("box around " << c[0] << " " << c[1] << " " << c[2] << ", triangle " << f);
      if (CGAL::do_intersect(box, InputKernel::Triangle_3(a, b, e))) CHECK(listed);  // it meets the box
      if (!CGAL::do_overlap(box, a.bbox() + b.bbox() + e.bbox())) CHECK(!listed);  // its box misses it
    }
  }

}

TEST_CASE("distance: an index large enough to be built in parallel answers as a search of every triangle does, "
          "and as one built by one thread",
          "[repair][distance]") {
  // 81920 triangles: the index's top levels are built in parallel, each
  // half into the node ids it would take in one thread's pre-order.
  const Soup s = test::icosphere(1.0, 6);
  REQUIRE(s.face_count() == 81920);
  const detail::SurfaceDistance parallel(s);
  std::optional<detail::SurfaceDistance> serial;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    serial.emplace(s);
  }
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> u(-1.3, 1.3);
  auto corner = [&](std::size_t f, int k) { return s.points[s.face(f)[k]]; };
  for (int k = 0; k < 2000; ++k) {
    const Point3d p{u(rng), u(rng), u(rng)};
    const auto got = parallel.nearest(p);
    CHECK(got == serial->nearest(p));
    if (k % 10) continue;
    double want = std::numeric_limits<double>::infinity();
    for (std::size_t f = 0; f < s.face_count(); ++f)
      want = std::min(want, detail::squared_distance_to_triangle(p, corner(f, 0), corner(f, 1), corner(f, 2)));
    CHECK(std::abs(got.first - want) <= 1e-12 * (1 + want));
  }
}

TEST_CASE("distance: a wall removed inside a union counts as removed, not as moved", "[repair][distance]") {
  // Two unit cubes touching face to face, against their union (the 2 x 1 x 1
  // box): skipping what lies inside the union, nothing of the input is far
  // from it. The shared wall is inside up to its rim, which lies on the
  // union's surface, so pieces along the rim keep splitting until the split
  // budget runs out; what is left then counts with its size. Depth first,
  // the budget went on one corner of the wall and a quarter of it counted
  // (0.35); largest piece first, what is left is small.
  const Soup cubes = test::concat(test::box({0, 0, 0}, {1, 1, 1}), test::box({1, 0, 0}, {2, 1, 1}));
  const Soup united = test::box({0, 0, 0}, {2, 1, 1});
  auto inside = [](const Point3d& p) { return p[0] > 0 && p[0] < 2 && p[1] > 0 && p[1] < 1 && p[2] > 0 && p[2] < 1; };
  const double error = 1e-3;
  const double d = detail::one_sided_distance_skipping(cubes, united, error, inside);
  INFO("distance from what is outside the union: " << d);
  CHECK(d >= 0);
  CHECK(d <= 5 * error);
  // without skipping, the wall's centre is half a unit from the union's surface
  CHECK(detail::one_sided_distances(cubes, united, error)[0] >= 0.5 - 1e-12);
  // The pieces are stepped in parallel, in batches: on one thread the very
  // same result.
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    CHECK(detail::one_sided_distance_skipping(cubes, united, error, inside) == d);
  }
}

TEST_CASE("distance: input wholly inside the other surface, just under it all over, counts nothing", "[repair][distance]") {
  // A sphere just inside a slightly larger one (the same tessellation): every
  // piece of the inner one is skipped, and crosses nothing of the outer one,
  // so it is skipped whole. Bisected instead until its pieces were smaller
  // than the error bound, it ran out of splits and counted what was left with
  // its size (a rebuilt chair inside its shell "lost" 3% of the diagonal).
  Soup outer = test::icosphere(1.0, 3);
  for (Point3d& p : outer.points)
    for (double& x : p) x *= 1.01;
  const Soup inner = test::icosphere(1.0, 3);
  auto inside = [](const Point3d& p) { return p[0] * p[0] + p[1] * p[1] + p[2] * p[2] < 1.005 * 1.005; };
  const double error = 1e-4;
  CHECK(detail::one_sided_distance_skipping(inner, outer, error, inside) == 0);
  CHECK(detail::one_sided_distances(inner, outer, error)[0] > 0.005);  // the surfaces are apart
}

TEST_CASE("distance: skipping the inside of a torus, large triangles across it measure as dense sampling does",
          "[repair][distance]") {
  // Triangles much larger than the tube (R 3, r 1) with corners inside it
  // or near it: what lies outside is reached through the hole and past the
  // tube, so the farthest point is often inside a triangle whose corners
  // are all skipped, or along a piece that straddles the surface — where the
  // bisection stops on the bound of what can lie between corners (every
  // point within longest edge / sqrt(3) of a corner, and within |x - c| of
  // the surface for a skipped corner c). The measure must agree with a dense
  // sampling of each triangle: no lower than it by more than the error
  // bound, no higher than its spacing allows.
  const Soup torus = read_soup(test::fixture("torus.off"));
  std::vector<std::array<Index, 3>> tris;
  for (std::size_t f = 0; f < torus.face_count(); ++f) {
    const FaceView v = torus.face(f);
    tris.push_back({v[0], v[1], v[2]});
  }
  const detail::WindingNumber winding(torus.points, tris);
  const detail::SurfaceDistance to(torus);
  auto inside = [&](const Point3d& p) { return winding(p) >= 0.5; };
  const double error = 1e-3;
  std::vector<std::array<Point3d, 3>> cases;
  const double kPi = 3.14159265358979323846;
  auto on_core = [&](double degrees, double radius, double z) {
    const double a = degrees * kPi / 180;
    return Point3d{radius * std::cos(a), radius * std::sin(a), z};
  };
  cases.push_back({on_core(90, 3, 0), on_core(210, 3, 0), on_core(330, 3, 0)});  // all corners inside: the hole
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(0, 360), radius(2.3, 3.7), height(-0.6, 0.6), far(3.7, 4.6);
  for (int n = 0; n < 24; ++n) {
    const double a = angle(rng);
    cases.push_back({on_core(a, radius(rng), height(rng)), on_core(a + 100 + 60 * (n % 3), radius(rng), height(rng)),
                     on_core(a + 200 + 40 * (n % 4), n % 2 ? far(rng) : radius(rng), height(rng))});
  }
  constexpr int kGrid = 240;
  for (const auto& c : cases) {
    double sampled = 0, spacing = 0;
    for (int k = 0; k < 3; ++k)
      spacing = std::max(spacing, std::sqrt((c[k][0] - c[(k + 1) % 3][0]) * (c[k][0] - c[(k + 1) % 3][0]) +
                                            (c[k][1] - c[(k + 1) % 3][1]) * (c[k][1] - c[(k + 1) % 3][1]) +
                                            (c[k][2] - c[(k + 1) % 3][2]) * (c[k][2] - c[(k + 1) % 3][2])) /
                                      kGrid);
    for (int i = 0; i <= kGrid; ++i)
      for (int j = 0; i + j <= kGrid; ++j) {
        const double u = double(i) / kGrid, v = double(j) / kGrid, w = 1 - u - v;
        Point3d p;
        for (int k = 0; k < 3; ++k) p[k] = w * c[0][k] + u * c[1][k] + v * c[2][k];
        if (!inside(p)) sampled = std::max(sampled, std::sqrt(to.squared_distance(p)));
      }
    const Soup one = test::soup({c[0], c[1], c[2]}, {{0, 1, 2}});
    const double measured = detail::one_sided_distance_skipping(one, torus, error, inside);
    INFO("corners (" << c[0][0] << ", " << c[0][1] << ", " << c[0][2] << ") (" << c[1][0] << ", " << c[1][1] << ", "
                     << c[1][2] << ") (" << c[2][0] << ", " << c[2][1] << ", " << c[2][2] << ")");
    INFO("measured " << measured << ", sampled " << sampled << ", spacing " << spacing);
    CHECK(measured >= sampled - error);
    CHECK(measured <= sampled + spacing);
  }
}

TEST_CASE("distance: a box query lists a triangle cut into pieces once", "[repair][distance]") {
  // 200 small triangles and 3 needles 1000 times longer: the index cuts each
  // needle into pieces (up to 64), and a box around everything meets them all.
  Soup s;
  for (int k = 0; k < 200; ++k) {
    const Index b = static_cast<Index>(s.points.size());
    const double x = 0.02 * k;
    s.points.push_back({x, 0, 0});
    s.points.push_back({x + 0.01, 0, 0});
    s.points.push_back({x, 0.01, 0});
    s.add_triangle(b, b + 1, b + 2);
  }
  for (int k = 0; k < 3; ++k) {
    const Index b = static_cast<Index>(s.points.size());
    s.points.push_back({0, 1.0 + k, 0});
    s.points.push_back({10, 1.0 + k, 0});
    s.points.push_back({0, 1.01 + k, 0});
    s.add_triangle(b, b + 1, b + 2);
  }
  const detail::SurfaceDistance d(s);
  std::vector<std::size_t> all = d.triangles_near({-1, -1, -1}, {11, 5, 1});
  std::sort(all.begin(), all.end());
  CHECK(all.size() == s.face_count());
  CHECK(std::adjacent_find(all.begin(), all.end()) == all.end());
  // a box around one needle's middle only: that needle, once
  const std::vector<std::size_t> one = d.triangles_near({4, 1.0, -1}, {6, 1.005, 1});
  CHECK(one == std::vector<std::size_t>{200});
}
