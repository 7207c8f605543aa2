// polyheal clean_soup: the soup-level stage of `repair`. Each case breaks a
// closed cube in one combinatorial way and requires a certified clean cube
// back whose faces are the input's, corner for corner (no coordinate moves).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <set>

#include "polyheal/inspect/report.h"
#include "polyheal/repair/clean_soup.h"
#include "support/builders.h"

using namespace polyheal;

namespace {

/// The unit cube as 12 triangles, outward, every face with its own three
/// vertices (an STL-like soup: welding is needed before anything else).
Soup stl_cube(double shift = 0) {
  const Soup cube = test::box({shift, shift, shift}, {1 + shift, 1 + shift, 1 + shift});
  Soup s;
  for (std::size_t f = 0; f < cube.face_count(); ++f) {
    const Index base = Index(s.points.size());
    for (int k = 0; k < 3; ++k) s.points.push_back(cube.points[cube.face(f)[k]]);
    s.add_triangle(base, base + 1, base + 2);
  }
  return s;
}

/// The corner positions of every face, rotation-normalised, with orientation.
std::multiset<std::array<Point3d, 3>> oriented_faces(const Soup& s) {
  std::multiset<std::array<Point3d, 3>> out;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    std::array<Point3d, 3> t{s.points[s.face(f)[0]], s.points[s.face(f)[1]], s.points[s.face(f)[2]]};
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    out.insert(t);
  }
  return out;
}

void check_clean_cube(const CleanSoupResult& r, const Soup& reference) {
  const Report rep = inspect(r.soup);
  CHECK(rep.certified_clean());
  CHECK(rep.signed_volume > 0);
  // Every face kept from the input is an input face in the input's orientation.
  const auto ref = oriented_faces(reference);
  for (std::size_t f = 0; f < r.soup.face_count(); ++f) {
    if (r.source[f] < 0) continue;
    std::array<Point3d, 3> t{r.soup.points[r.soup.face(f)[0]], r.soup.points[r.soup.face(f)[1]],
                             r.soup.points[r.soup.face(f)[2]]};
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    CHECK(ref.count(t) == 1);
  }
}

}  // namespace

TEST_CASE("clean_soup: an STL-like cube is welded into a clean solid, faces unchanged", "[clean_soup]") {
  const Soup cube = stl_cube();
  CHECK(cube.points.size() == 36);
  const CleanSoupResult r = clean_soup(cube);
  CHECK(r.report.identical_vertices_welded == 36 - 8);
  CHECK(r.report.reoriented_faces == 0);
  CHECK(r.soup.face_count() == 12);
  check_clean_cube(r, cube);
}

TEST_CASE("clean_soup: a flipped face is turned back, the component's majority and volume decide", "[clean_soup]") {
  Soup cube = stl_cube();
  std::swap(cube.indices[3 * 5 + 1], cube.indices[3 * 5 + 2]);  // face 5 reversed
  CHECK_FALSE(inspect(cube).oriented);
  const CleanSoupResult r = clean_soup(cube);
  CHECK(r.report.reoriented_faces == 1);
  check_clean_cube(r, stl_cube());
}

TEST_CASE("clean_soup: a consistently inward shell keeps its orientation (a cavity is not flipped)", "[clean_soup]") {
  Soup inner = test::tetrahedron(0.25, 0.25, 0.25);
  for (std::size_t f = 0; f < inner.face_count(); ++f) std::swap(inner.indices[3 * f + 1], inner.indices[3 * f + 2]);
  const CleanSoupResult r = clean_soup(inner);
  CHECK(r.report.reoriented_faces == 0);
  CHECK(inspect(r.soup).signed_volume < 0);
}

TEST_CASE("clean_soup: duplicates — same-orientation copies keep one, a reversed stray copy goes", "[clean_soup]") {
  Soup cube = stl_cube();
  const Soup reference = cube;
  // Face 0 twice more in its orientation; face 2 once reversed: a pair whose
  // winding numbers cancel, but the cube around it needs face 2 as it was.
  for (int rep = 0; rep < 2; ++rep) cube.add_triangle(cube.indices[0], cube.indices[1], cube.indices[2]);
  cube.add_triangle(cube.indices[6], cube.indices[8], cube.indices[7]);
  // A face repeating an index.
  cube.add_triangle(0, 0, 1);
  const CleanSoupResult r = clean_soup(cube);
  CHECK(r.report.duplicate_faces_dropped == 3);
  CHECK(r.report.cancelled_faces == 0);
  CHECK(r.report.opposite_copies_kept == 1);
  CHECK(r.report.repeated_index_faces == 1);
  CHECK(r.report.holes == 0);  // no face was lost, so nothing is filled
  CHECK(r.soup.face_count() == 12);
  CHECK(std::count(r.source.begin(), r.source.end(), -1) == 0);
  check_clean_cube(r, reference);
}

TEST_CASE("clean_soup: reversed stray copies of adjacent faces all go, each face kept as it was", "[clean_soup]") {
  // Every face of the cube given a reversed copy but one: each stray copy's
  // neighbours are themselves cancelled pairs at first, so the faces come
  // back one after the other from the face that has none.
  Soup cube = stl_cube();
  const Soup reference = cube;
  for (std::size_t f = 1; f < 12; ++f) {
    const FaceView v = reference.face(f);
    cube.add_triangle(v[0], v[2], v[1]);
  }
  const CleanSoupResult r = clean_soup(cube);
  CHECK(r.report.opposite_copies_kept == 11);
  CHECK(r.report.cancelled_faces == 0);
  CHECK(r.report.holes == 0);
  CHECK(r.soup.face_count() == 12);
  CHECK(std::count(r.source.begin(), r.source.end(), -1) == 0);
  check_clean_cube(r, reference);
}

TEST_CASE("clean_soup: the wall two touching solids share cancels (a union, not a stray copy)", "[clean_soup]") {
  // The unit cube and its mirror image across x = 1 (faces reversed to stay
  // outward): the wall x = 1 appears once in each orientation, and each
  // solid uses every wall edge once, so the wall is two sheets, not a face
  // with a stray copy. It cancels, leaving the closed 2 x 1 x 1 box.
  const Soup a = stl_cube();
  Soup both = a;
  for (std::size_t f = 0; f < a.face_count(); ++f) {
    const Index base = Index(both.points.size());
    for (const Index v : a.face(f)) both.points.push_back({2 - a.points[v][0], a.points[v][1], a.points[v][2]});
    both.add_triangle(base, base + 2, base + 1);
  }
  CHECK_FALSE(inspect(both).manifold);
  const CleanSoupResult r = clean_soup(both);
  CHECK(r.report.cancelled_faces == 4);
  CHECK(r.report.opposite_copies_kept == 0);
  CHECK(r.report.holes == 0);
  const Report rep = inspect(r.soup);
  CHECK(rep.certified_clean());
  CHECK(r.soup.face_count() == 20);
  CHECK(rep.signed_volume == Approx(2.0));
}

TEST_CASE("clean_soup: a missing face is filled from existing vertices, reported as new", "[clean_soup]") {
  Soup cube = stl_cube();
  Soup open;
  open.points = cube.points;
  for (std::size_t f = 0; f < 12; ++f)
    if (f != 3) open.add_triangle(cube.face(f)[0], cube.face(f)[1], cube.face(f)[2]);
  CHECK_FALSE(inspect(open).closed);
  const CleanSoupResult r = clean_soup(open);
  CHECK(r.report.holes == 1);
  CHECK(r.report.holes_filled == 1);
  CHECK(r.report.hole_faces == 1);
  CHECK(std::count(r.source.begin(), r.source.end(), -1) == 1);
  check_clean_cube(r, cube);

  CleanSoupOptions no_fill;
  no_fill.fill_holes = false;
  const CleanSoupResult left = clean_soup(open, no_fill);
  CHECK(left.report.holes_filled == 0);
  CHECK_FALSE(inspect(left.soup).closed);
}

TEST_CASE("clean_soup: two holes touching at a vertex are filled one by one, not bridged", "[clean_soup]") {
  // An icosphere missing two faces that share one vertex and no edge: the
  // vertex is a pinch between the holes. Each hole is a triangle, so the
  // only fill within the input's vertices is the missing face itself.
  const Soup sphere = test::icosphere(1.0, 2);
  std::size_t first = 0, second = 0;
  for (std::size_t f = 1; f < sphere.face_count() && second == 0; ++f) {
    int shared = 0;
    for (Index i : sphere.face(0))
      for (Index j : sphere.face(f)) shared += i == j;
    if (shared == 1) second = f;
  }
  REQUIRE(second != 0);
  Soup open;
  open.points = sphere.points;
  for (std::size_t f = 0; f < sphere.face_count(); ++f)
    if (f != first && f != second) open.add_triangle(sphere.face(f)[0], sphere.face(f)[1], sphere.face(f)[2]);
  REQUIRE_FALSE(inspect(open).manifold);  // the pinch

  const CleanSoupResult r = clean_soup(open);
  CHECK(r.report.holes == 2);
  CHECK(r.report.holes_filled == 2);
  CHECK(r.report.hole_faces == 2);
  CHECK(inspect(r.soup).certified_clean());
  CHECK(test::faces_by_position(r.soup) == test::faces_by_position(sphere));
}

TEST_CASE("clean_soup: a near weld closes a crack the exact weld cannot, and says how far it moved", "[clean_soup]") {
  Soup cube = stl_cube();
  for (std::size_t f = 6; f < 12; ++f)  // half the faces' copies of each corner nudged by 1e-7
    for (Index i : cube.face(f)) cube.points[i][0] += 1e-7;
  CleanSoupOptions o;
  o.fill_holes = false;
  CHECK_FALSE(inspect(clean_soup(cube, o).soup).closed);
  o.weld = 1e-6;
  const CleanSoupResult r = clean_soup(cube, o);
  CHECK(r.report.near_vertices_welded > 0);
  CHECK(r.report.max_weld_move <= 2e-7);
  CHECK(r.report.holes == 0);
  CHECK(inspect(r.soup).certified_clean());
}

TEST_CASE("clean_soup: two cubes touching at a corner: the pinch point is split, coordinates unchanged", "[clean_soup]") {
  const Soup a = stl_cube(), b = stl_cube(1.0);  // shifted by (1,1,1): they meet at one corner
  Soup two = test::concat(a, b);
  CHECK_FALSE(inspect(two).manifold);  // a pinch vertex at (1,1,1)
  const CleanSoupResult r = clean_soup(two);
  CHECK(r.report.split_vertices >= 1);
  CHECK(r.soup.face_count() == 24);
  CHECK(oriented_faces(r.soup) == oriented_faces(two));
}

namespace {

/// The welded unit cube with its top face re-triangulated through a vertex
/// m on the edge (0,0,1)-(1,0,1) that the front face does not have: the
/// crack a CAD export leaves at a T-junction (a boundary loop of zero
/// width: edges 4-m-5 on one side, 4-5 on the other).
Soup t_junction_cube(const Point3d& m) {
  Soup s;
  s.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}, m};
  const int t[13][3] = {{0, 2, 1}, {0, 3, 2}, {4, 8, 6}, {8, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                        {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  for (const auto& f : t) s.add_triangle(Index(f[0]), Index(f[1]), Index(f[2]));
  return s;
}

double area(const Soup& s) {
  double a = 0;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const Point3d &p = s.points[s.face(f)[0]], &q = s.points[s.face(f)[1]], &r = s.points[s.face(f)[2]];
    const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    a += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  }
  return a;
}

}  // namespace

TEST_CASE("clean_soup: a T-junction crack closes by splitting the face across it, no coordinate moved",
          "[clean_soup]") {
  CleanSoupOptions o;
  o.fill_holes = false;  // the crack must close by itself, not by a fill

  SECTION("a vertex exactly on the edge (tolerance 0)") {
    const Soup in = t_junction_cube({0.5, 0, 1});
    CHECK_FALSE(inspect(in).closed);
    const CleanSoupResult r = clean_soup(in, o);
    CHECK(r.report.t_junctions == 1);
    CHECK(r.report.holes == 0);
    CHECK(r.soup.face_count() == 14);  // the front face 0-5-4 became 0-5-m, 0-m-4
    const Report rep = inspect(r.soup);
    CHECK(rep.certified_clean());
    CHECK(rep.signed_volume > 0);
    CHECK(area(r.soup) == Approx(6.0).epsilon(1e-15));
    // Every point of the output is an input point, bit for bit.
    for (const Point3d& p : r.soup.points) CHECK(std::count(in.points.begin(), in.points.end(), p) == 1);
  }

  SECTION("a vertex 1e-12 off the edge: closed within a tolerance above that, left open below") {
    const Soup in = t_junction_cube({0.5, 1e-12, 1});  // inside the top face, just off its front edge
    o.t_junction = 1e-13;
    const CleanSoupResult strict = clean_soup(in, o);
    CHECK(strict.report.t_junctions == 0);
    CHECK_FALSE(inspect(strict.soup).closed);
    o.t_junction = 1e-9;
    const CleanSoupResult r = clean_soup(in, o);
    CHECK(r.report.t_junctions == 1);
    CHECK(r.report.near_vertices_welded == 0);  // m is far from every corner
    CHECK(inspect(r.soup).certified_clean());
  }

  SECTION("copies of a corner closer than the tolerance weld: a crack of zero length") {
    Soup in = stl_cube();
    for (std::size_t f = 6; f < 12; ++f)
      for (Index i : in.face(f)) in.points[i][1] += 1e-13;
    CHECK_FALSE(inspect(clean_soup(in, o).soup).closed);  // tolerance 0: identical points only
    o.t_junction = 1e-9;
    const CleanSoupResult r = clean_soup(in, o);
    CHECK(r.report.near_vertices_welded > 0);
    CHECK(r.report.max_weld_move <= 2e-13);
    CHECK(inspect(r.soup).certified_clean());
  }
}
