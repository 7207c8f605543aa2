// Soup -> Surface_mesh: builds valid oriented 2-manifolds, explains the rest.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include <CGAL/intersections.h>

#include "polyheal/io/read.h"
#include "polyheal/mesh/convert.h"
#include "polyheal/repair/detail/plane_meet.h"
#include "support/builders.h"

using namespace polyheal;

namespace {
bool mentions(const MeshBuildResult& r, const std::string& what) {
  for (const std::string& p : r.problems)
    if (p.find(what) != std::string::npos) return true;
  return false;
}
}  // namespace

TEST_CASE("convert: a closed tetrahedron becomes a valid mesh with provenance", "[mesh][smoke]") {
  Mesh m;
  const MeshBuildResult r = soup_to_mesh(test::tetrahedron(), m);
  REQUIRE(r.ok);
  CHECK(m.number_of_faces() == 4);
  CHECK(m.is_valid(false));
  auto origin = *face_origin_map(m);
  std::int64_t sum = 0;
  for (face_descriptor f : m.faces()) sum += origin[f];
  CHECK(sum == 0 + 1 + 2 + 3);
  CHECK(mesh_to_soup(m).points == test::tetrahedron().points);
}

TEST_CASE("convert: says exactly why a soup is not an oriented 2-manifold", "[mesh]") {
  Mesh m;
  SECTION("a flipped face") {
    Soup s = test::tetrahedron();
    std::swap(s.indices[1], s.indices[2]);
    const MeshBuildResult r = soup_to_mesh(s, m);
    CHECK_FALSE(r.ok);
    CHECK(mentions(r, "disagree in orientation"));
  }
  SECTION("an edge of three faces") {
    const Soup s = test::soup({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}},
                              {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
    const MeshBuildResult r = soup_to_mesh(s, m);
    CHECK_FALSE(r.ok);
    CHECK(mentions(r, "edge (0, 1) is non-manifold: shared by 3 faces (0, 1, 2)"));
  }
  SECTION("two tetrahedra touching at one vertex") {
    // The tetrahedron and its point reflection through the shared corner (0,0,0).
    const Soup s = test::soup({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}},
                              {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3},
                               {0, 4, 5}, {0, 6, 4}, {0, 5, 6}, {4, 6, 5}});
    const MeshBuildResult r = soup_to_mesh(s, m);
    CHECK_FALSE(r.ok);
    CHECK(mentions(r, "vertex 0 is non-manifold"));
  }
  CHECK(m.number_of_faces() == 0);
}

TEST_CASE("convert: every manifold fixture builds", "[mesh][corpus]") {
  for (const char* f : {"tube_edge2.42.off", "tube_edge3.0.off", "torus_knot_20k.off", "cad_cylinder.off"}) {
    INFO(f);
    Mesh m;
    CHECK(soup_to_mesh(read_soup(test::fixture(f)), m).ok);
    CHECK(m.is_valid(false));
  }
}

TEST_CASE("convert: exact coordinates round to the nearest double", "[mesh]") {
  Mesh m;
  REQUIRE(soup_to_mesh(test::tetrahedron(), m).ok);
  const vertex_descriptor v = *m.vertices().begin();
  // 1/3, -2/3 and 0.1/3 are not doubles; their nearest doubles are what IEEE
  // division of the same operands returns (correctly rounded).
  m.point(v) = Point(Kernel::FT(1) / 3, Kernel::FT(-2) / 3, Kernel::FT(0.1) / 3);
  // An exact value within 1e-5 relative of a double but not equal to it: the
  // lazy approximation alone would not give the nearest double.
  const Kernel::FT third = Kernel::FT(1) / 3;
  m.point(*std::next(m.vertices().begin())) = Point(third * third * third, 1e300 / Kernel::FT(7), 0);
  const Soup s = mesh_to_soup(m);
  CHECK(s.points[0][0] == 1.0 / 3);
  CHECK(s.points[0][1] == -2.0 / 3);
  CHECK(s.points[0][2] == 0.1 / 3);
  CHECK(s.points[1][0] == 1.0 / 27);
  CHECK(s.points[1][1] == 1e300 / 7);
}

TEST_CASE("convert: exact values halfway between doubles round to even, subnormals as IEEE does", "[mesh]") {
  auto exact = [](double x) { return Kernel::FT(x); };
  const Kernel::FT half_ulp = exact(std::ldexp(1.0, -53));  // half the spacing of doubles in [1, 2)
  const Kernel::FT tiny = exact(std::ldexp(1.0, -1074));    // the least subnormal
  CHECK(nearest_double(exact(1) + half_ulp) == 1.0);                         // tie: 1 has the even mantissa
  CHECK(nearest_double(-(exact(1) + half_ulp)) == -1.0);
  CHECK(nearest_double(exact(1) + 3 * half_ulp) == 1.0 + std::ldexp(1.0, -51));  // tie the other way
  CHECK(nearest_double(exact(1) + half_ulp + exact(std::ldexp(1.0, -100))) == 1.0 + std::ldexp(1.0, -52));
  CHECK(nearest_double(exact(1) + half_ulp - exact(std::ldexp(1.0, -100))) == 1.0);
  CHECK(nearest_double(tiny * 3 / 2) == std::ldexp(1.0, -1073));  // tie between 1 and 2 subnormal steps
  CHECK(nearest_double(tiny / 2) == 0.0);                         // tie between 0 and one step
  CHECK(nearest_double(tiny * 3 / 4) == std::ldexp(1.0, -1074));
  CHECK(nearest_double(-tiny / 4) == 0.0);
  CHECK(std::signbit(nearest_double(-tiny / 4)));
}

TEST_CASE("convert: pinch copies share one identity, every other vertex, old or new, is itself", "[mesh]") {
  // Two tetrahedra touching at one corner, the origin: a pinch point whose
  // two fans get a vertex each.
  const Soup touching = test::concat(test::tetrahedron(), test::tetrahedron(-1, 0, 0));
  Mesh m;
  std::size_t split = 0;
  REQUIRE(soup_to_mesh_splitting_pinches(touching, m, &split).ok);
  REQUIRE(split == 1);
  mark_split_pinches(m);
  const auto identity = vertex_identity_map(m);
  const auto pinned = vertex_pinned_map(m);
  REQUIRE(identity);
  REQUIRE(pinned);
  std::vector<vertex_descriptor> at_origin;
  for (vertex_descriptor v : m.vertices())
    if (m.is_isolated(v)) continue;  // the welded-away twin of the origin stays, unused
    else if (m.point(v) == Point(0, 0, 0)) at_origin.push_back(v);
    else CHECK(vertex_identity(identity, v) == static_cast<std::uint32_t>(v));
  REQUIRE(at_origin.size() == 2);
  CHECK(vertex_identity(identity, at_origin[0]) == vertex_identity(identity, at_origin[1]));
  CHECK(((*pinned)[at_origin[0]] && (*pinned)[at_origin[1]]));
  // A vertex added afterwards (as slicing does) is itself, not a copy of
  // another: the property's default must not alias it to vertex 0.
  const vertex_descriptor added = m.add_vertex(Point(5, 5, 5));
  CHECK(vertex_identity(identity, added) == static_cast<std::uint32_t>(added));
}

TEST_CASE("convert: a new edge to a pinch copy duplicates its twin's edge in the file", "[mesh]") {
  // Two tetrahedra touching at the origin: copies o1 (first fan) and o2.
  // An edge o2-w to a neighbour w of o1 welds onto o1-w in the file.
  const Soup touching = test::concat(test::tetrahedron(), test::tetrahedron(-1, 0, 0));
  Mesh m;
  REQUIRE(soup_to_mesh_splitting_pinches(touching, m).ok);
  mark_split_pinches(m);
  const auto identity = vertex_identity_map(m);
  const PinchCopies copies = pinch_copies(m);
  REQUIRE(copies.size() == 1);
  const std::vector<vertex_descriptor>& o = copies.begin()->second;
  REQUIRE(o.size() == 2);  // the welded-away twin of the origin is isolated: not a copy
  for (int k = 0; k < 2; ++k) {
    const vertex_descriptor own = o[k], twin = o[1 - k];
    for (vertex_descriptor w : CGAL::vertices_around_target(m.halfedge(own), m)) {
      CHECK_FALSE(copies_share_edge(m, identity, copies, own, w));  // the edge itself
      CHECK(copies_share_edge(m, identity, copies, twin, w));
      CHECK(copies_share_edge(m, identity, copies, w, twin));
    }
  }
  // Without split pinches nothing is shared.
  Mesh plain;
  REQUIRE(soup_to_mesh(test::tetrahedron(), plain).ok);
  const vertex_descriptor v = *plain.vertices().begin();
  for (vertex_descriptor w : CGAL::vertices_around_target(plain.halfedge(v), plain))
    CHECK_FALSE(copies_share_edge(plain, vertex_identity_map(plain), pinch_copies(plain), v, w));
}

TEST_CASE("rebuild: sharpening's meeting points are Epeck's constructions, correctly rounded", "[rebuild]") {
  // Random facets (and nearly parallel ones, whose meeting points are far
  // and need long numbers), against the Epeck plane intersection and line
  // projection the sharpening used before, rounded by nearest_point3d.
  std::mt19937_64 rng(43);
  std::uniform_real_distribution<double> u(-10, 10), tiny(-1e-9, 1e-9);
  auto random_triangle = [&] { return detail::Triangle3d{{{u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}}}; };
  auto nearly = [&](const detail::Triangle3d& t) {  // t's corners moved by 1e-9 at most
    detail::Triangle3d s = t;
    for (Point3d& p : s)
      for (double& x : p) x += tiny(rng);
    return s;
  };
  auto plane = [](const detail::Triangle3d& t) {
    auto P = [&](int k) { return Point(t[k][0], t[k][1], t[k][2]); };
    return Kernel::Plane_3(P(0), P(1), P(2));
  };
  std::size_t points = 0, none = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const detail::Triangle3d a = random_triangle();
    const detail::Triangle3d b = trial % 4 == 1 ? nearly(a) : random_triangle();
    const detail::Triangle3d c = trial % 4 == 2 ? nearly(b) : random_triangle();
    const Point3d p{u(rng), u(rng), u(rng)};
    Point3d ours;
    const detail::Meeting three = detail::planes_meet(a, b, c, ours);
    const auto hit = CGAL::intersection(plane(a), plane(b), plane(c));
    const Point* q = hit ? boost::get<Point>(&*hit) : nullptr;
    REQUIRE(three == (q ? detail::Meeting::point : detail::Meeting::none));
    if (q) CHECK(ours == nearest_point3d(*q));
    const detail::Meeting two = detail::nearest_on_planes_line(a, b, p, ours);
    const auto line = CGAL::intersection(plane(a), plane(b));
    const Kernel::Line_3* l = line ? boost::get<Kernel::Line_3>(&*line) : nullptr;
    REQUIRE(two == (l ? detail::Meeting::point : detail::Meeting::none));
    if (l) CHECK(ours == nearest_point3d(l->projection(Point(p[0], p[1], p[2]))));
    points += three == detail::Meeting::point;
    none += three == detail::Meeting::none;
  }
  CHECK(points > 300);
  // parallel planes meet in no point; a facet without a normal is told apart
  const detail::Triangle3d flat{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}, lifted{{{0, 0, 1}, {1, 0, 1}, {0, 1, 1}}},
      side{{{0, 0, 0}, {0, 1, 0}, {0, 0, 1}}}, segment{{{0, 0, 0}, {1, 1, 1}, {2, 2, 2}}};
  Point3d out;
  CHECK(detail::planes_meet(flat, lifted, side, out) == detail::Meeting::none);
  CHECK(detail::nearest_on_planes_line(flat, lifted, {0, 0, 0}, out) == detail::Meeting::none);
  CHECK(detail::nearest_on_planes_line(flat, side, {0.5, 3, 7}, out) == detail::Meeting::point);
  CHECK(out == Point3d{0, 3, 0});
  CHECK(detail::planes_meet(flat, side, segment, out) == detail::Meeting::degenerate);
}
