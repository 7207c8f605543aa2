// The exact oracle on hand-built configurations: intersection semantics,
// topology, shape classes. Table-driven; each configuration is checked under
// every cyclic rotation of both faces, both orientations and both face orders.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "polyheal/inspect/nesting.h"
#include "polyheal/inspect/report.h"
#include "polyheal/io/read.h"
#include "polyheal/io/write.h"
#include "support/builders.h"

using namespace polyheal;

namespace {

struct PairCase {
  const char* what;
  std::array<Point3d, 3> a, b;
  std::size_t pairs;       // intersecting pairs expected
  std::size_t degenerate;  // degenerate faces expected
};

/// Two triangles as a soup; corners at identical positions are welded by the
/// oracle, so shared vertices come from shared coordinates.
Soup two_triangles(const std::array<Point3d, 3>& a, const std::array<Point3d, 3>& b) {
  Soup s;
  for (const auto& p : a) s.points.push_back(p);
  for (const auto& p : b) s.points.push_back(p);
  s.add_triangle(0, 1, 2);
  s.add_triangle(3, 4, 5);
  return s;
}

std::array<Point3d, 3> rotate(std::array<Point3d, 3> t, int k) {
  std::rotate(t.begin(), t.begin() + k, t.end());
  return t;
}
std::array<Point3d, 3> flip(std::array<Point3d, 3> t) { return {t[0], t[2], t[1]}; }

}  // namespace

TEST_CASE("inspect: triangle pair semantics of PMP::self_intersections", "[inspect][smoke]") {
  const std::vector<PairCase> cases = {
      // Touch at a shared vertex only, in different planes.
      {"vertex contact", {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}, {{{0, 0, 0}, {-1, 0, 1}, {0, -1, 1}}}, 0, 0},
      // Share an edge and lie flat side by side.
      {"flat across an edge", {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}, {{{1, 0, 0}, {0, 0, 0}, {0, -1, 0}}}, 0, 0},
      // Share an edge and fold onto each other (coplanar, same side).
      {"folded across an edge", {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}, {{{1, 0, 0}, {0, 0, 0}, {0.5, 2, 0}}}, 1, 0},
      // Share an edge at a 90 degree dihedral angle.
      {"edge, right angle", {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}, {{{1, 0, 0}, {0, 0, 0}, {0, 0, 1}}}, 0, 0},
      // No shared vertex, one pierces the other.
      {"crossing", {{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}}}, {{{0.5, 0.5, -1}, {0.5, 0.5, 1}, {3, 3, 0.5}}}, 1, 0},
      // No shared vertex, coplanar and partly overlapping.
      {"coplanar overlap", {{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}}}, {{{1, 1, 0}, {-1, 1, 0}, {1, -1, 0}}}, 1, 0},
      // Coplanar, one strictly inside the other.
      {"one inside the other", {{{0, 0, 0}, {4, 0, 0}, {0, 4, 0}}}, {{{1, 1, 0}, {2, 1, 0}, {1, 2, 0}}}, 1, 0},
      // Disjoint, parallel planes.
      {"parallel apart", {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}, {{{0, 0, 1}, {1, 0, 1}, {0, 1, 1}}}, 0, 0},
      // A zero-area triangle (collinear corners) lying inside another face.
      {"sliver inside a face", {{{0, 0, 0}, {4, 0, 0}, {0, 4, 0}}}, {{{1, 1, 0}, {2, 1, 0}, {3, 1, 0}}}, 1, 1},
      // A zero-area triangle next to a face, not touching it.
      {"sliver beside a face", {{{0, 0, 0}, {4, 0, 0}, {0, 4, 0}}}, {{{1, 1, 1}, {2, 1, 1}, {3, 1, 1}}}, 0, 1},
      // Shared vertex, and the opposite edge of one pierces the other.
      {"vertex + piercing edge", {{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}}}, {{{0, 0, 0}, {1, 0.2, -1}, {0.2, 1, 1}}}, 1, 0},
      // Shared vertex, coplanar, overlapping wedges.
      {"vertex + coplanar overlap", {{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}}}, {{{0, 0, 0}, {2, 1, 0}, {1, 2, 0}}}, 1, 0},
      // Shared vertex, coplanar, wedges apart.
      {"vertex + coplanar apart", {{{0, 0, 0}, {2, 0, 0}, {2, 1, 0}}}, {{{0, 0, 0}, {1, 2, 0}, {0, 2, 0}}}, 0, 0},
      // Touching at a point that is a vertex of one and interior to an edge of the other.
      {"vertex on an edge", {{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}}}, {{{1, 0, 0}, {1, -1, 1}, {1, -1, -1}}}, 1, 0},
      // Same three corners: a duplicate face.
      {"duplicate", {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}, {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}, 1, 0},
  };
  for (const PairCase& c : cases)
    for (int ka = 0; ka < 3; ++ka)
      for (int kb = 0; kb < 3; ++kb)
        for (int flips = 0; flips < 4; ++flips)
          for (bool swap : {false, true}) {
            auto a = rotate(c.a, ka), b = rotate(c.b, kb);
            if (flips & 1) a = flip(a);
            if (flips & 2) b = flip(b);
            const Soup s = swap ? two_triangles(b, a) : two_triangles(a, b);
            const Report r = inspect(s);
            INFO(c.what << " rotations " << ka << "," << kb << " flips " << flips << " swapped " << swap);
            CHECK(r.self_intersections.size() == c.pairs);
            CHECK(r.degenerate_faces.size() == c.degenerate);
          }
}

TEST_CASE("inspect: a closed tetrahedron is certified clean", "[inspect][smoke]") {
  const Report r = inspect(test::tetrahedron());
  CHECK(r.certified_clean());
  CHECK_FALSE(r.tetgen_ready());  // not decided without the segment search
  InspectOptions io;
  io.tetgen_segments = true;
  CHECK(inspect(test::tetrahedron(), io).tetgen_ready());
  CHECK(r.components == 1);
  CHECK(r.boundary_edges.empty());
  CHECK(r.signed_volume == Approx(1.0 / 6));
}

TEST_CASE("inspect: topology defects", "[inspect]") {
  SECTION("a tetrahedron with one face flipped") {
    Soup s = test::tetrahedron();
    std::swap(s.indices[1], s.indices[2]);
    const Report r = inspect(s);
    CHECK(r.misoriented_edges.size() == 3);
    CHECK_FALSE(r.oriented);
    CHECK(r.closed);
    CHECK(r.self_intersections.empty());
    CHECK_FALSE(r.certified_clean());
  }
  SECTION("a non-manifold edge of three faces") {
    const Soup s = test::soup({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}},
                              {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
    const Report r = inspect(s);
    REQUIRE(r.nonmanifold_edges.size() == 1);
    CHECK(r.nonmanifold_edges[0].faces.size() == 3);
    CHECK_FALSE(r.manifold);
  }
  SECTION("an open tetrahedron: one boundary loop of three edges") {
    Soup s = test::tetrahedron();
    s.indices.resize(9);
    s.offsets.resize(4);
    const Report r = inspect(s);
    CHECK(r.boundary_edges.size() == 3);
    CHECK(r.boundary_loops == 1);
    CHECK_FALSE(r.closed);
  }
  SECTION("two tetrahedra, unwelded copies of each point, an isolated point") {
    Soup s = test::concat(test::tetrahedron(), test::tetrahedron(3, 0, 0));
    s.points.push_back({9, 9, 9});
    s.points.push_back(s.points[0]);  // an identical twin of a used point
    const Report r = inspect(s);
    CHECK(r.components == 2);
    CHECK(r.isolated_vertices == 1);
    CHECK(r.merged_identical_vertices == 1);
    CHECK(r.certified_clean());
  }
  SECTION("a duplicated face") {
    Soup s = test::tetrahedron();
    s.add_triangle(1, 2, 3);
    const Report r = inspect(s);
    CHECK(r.duplicate_faces.size() == 1);
    CHECK(r.nonmanifold_edges.size() == 3);
    CHECK_FALSE(r.certified_clean());
  }
}

TEST_CASE("inspect: caps, needles and degenerate faces decided exactly", "[inspect]") {
  struct Row {
    const char* what;
    std::array<Point3d, 3> t;
    std::size_t degenerate, caps, needles;
  };
  // Apex angle of an isosceles triangle (0,0,0)-(2,0,0)-(1,h,0) is 2*atan(1/h).
  const double h176 = std::tan((90.0 - 88.0) * 3.14159265358979323846 / 180.0);  // apex 176 deg
  const double h174 = std::tan((90.0 - 87.0) * 3.14159265358979323846 / 180.0);  // apex 174 deg
  const std::vector<Row> rows = {
      {"exactly collinear", {{{0, 0, 0}, {1, 1, 1}, {3, 3, 3}}}, 1, 0, 0},
      {"repeated corner", {{{0, 0, 0}, {1, 0, 0}, {0, 0, 0}}}, 1, 0, 0},
      {"tiny but not collinear", {{{0, 0, 0}, {1, 0, 0}, {0.5, 1e-300, 0}}}, 0, 1, 0},
      {"cap at 176 degrees", {{{0, 0, 0}, {2, 0, 0}, {1, h176, 0}}}, 0, 1, 0},
      {"not a cap at 174 degrees", {{{0, 0, 0}, {2, 0, 0}, {1, h174, 0}}}, 0, 0, 1},  // base angles 3 deg
      {"needle at 4 degrees", {{{0, 0, 0}, {1, 0, 0}, {0, 0.0699, 0}}}, 0, 0, 1},
      {"fine right triangle", {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}, 0, 0, 0},
  };
  for (const Row& row : rows) {
    INFO(row.what);
    Soup s;
    s.points.assign(row.t.begin(), row.t.end());
    s.add_triangle(0, 1, 2);
    const Report r = inspect(s);
    CHECK(r.degenerate_faces.size() == row.degenerate);
    CHECK(r.caps.size() == row.caps);
    CHECK(r.needles.size() == row.needles);
  }
}

TEST_CASE("inspect: intersecting pairs at unwelded near-duplicate corners are told apart as cracks", "[inspect]") {
  // A unit square split along its diagonal, the second triangle's copy of
  // the corner (1, 1, 0) moved along x: its diagonal edge then passes into
  // the first triangle, a coplanar overlap either way. One ulp off is a
  // crack (as a CAD STL export leaves them); a hundredth is not.
  const double ulp = std::nextafter(1.0, 2.0);
  for (const auto& [x, crack] : {std::pair{ulp, true}, {1.01, false}}) {
    INFO("copy at x = " << x);
    const Soup s = test::soup({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {x, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 3, 4}});
    const Report r = inspect(s);
    REQUIRE(r.self_intersections.size() == 1);
    CHECK(r.crack_pairs == (crack ? 1u : 0u));
    CHECK(r.crack_vertex_pairs == (crack ? 1u : 0u));
    InspectOptions off;
    off.crack_ratio = 0;
    CHECK(inspect(s, off).crack_pairs == 0);
  }
  // The clean square has no pair, so no crack either.
  const Report clean = inspect(test::soup({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}}));
  CHECK(clean.self_intersections.empty());
  CHECK(clean.crack_pairs == 0);
}

TEST_CASE("inspect: TetGen's tolerances are reported apart from exact defects", "[inspect]") {
  // Two faces sharing an edge, folded to 0.05 degrees but not coplanar.
  const double t = std::tan(0.05 * 3.14159265358979323846 / 180.0);
  const Soup s = test::soup({{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, 1, t}}, {{0, 1, 2}, {1, 0, 3}});
  const Report r = inspect(s);
  CHECK(r.self_intersections.empty());
  CHECK(r.sharp_folds.size() == 1);
  InspectOptions wide;
  wide.tetgen_fold_angle = 0.01;
  CHECK(inspect(s, wide).sharp_folds.empty());

  // Nearly collinear at TetGen's 1e-8: |ab x ac| = h against 1e-8 * longest edge^2 = 1e-8, exactly.
  for (const auto& [h, nearly] : {std::pair{1e-9, true}, {0.99e-8, true}, {1.01e-8, false}, {1e-7, false}}) {
    INFO("height " << h);
    const Soup sliver = test::soup({{0, 0, 0}, {1, 0, 0}, {0.5, h, 0}}, {{0, 1, 2}});
    const Report q = inspect(sliver);
    CHECK(q.nearly_degenerate_faces.size() == (nearly ? 1u : 0u));
    CHECK(q.degenerate_faces.empty());
  }
}

TEST_CASE("inspect: a vertex within TetGen's tolerance of an edge it is not on stops TetGen, and is reported",
          "[inspect][tetgen]") {
  // Two disjoint tetrahedra; a corner of the second lies off the first's
  // edge (0,0,0)-(1,0,0) by h * sqrt(2) (outside it: no exact intersection).
  // TetGen (-T 1e-8) cannot recover that edge as a segment below ~1e-8.
  for (const auto& [h, near] : {std::pair{1e-9, true}, {1e-7, false}}) {
    INFO("offset " << h);
    const Soup s = test::concat(test::tetrahedron(),
                                test::soup({{0, -1, -1}, {1, -1, -1}, {0.5, -h, -h}, {0.5, -1, 0}},
                                           {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}));
    InspectOptions io;
    io.tetgen_segments = true;
    const Report r = inspect(s, io);
    REQUIRE(r.certified_clean());
    CHECK(r.vertices_near_edges.size() == (near ? 1u : 0u));
    CHECK(r.tetgen_ready() == !near);
    if (near) {
      CHECK(r.vertices_near_edges[0].vertex == 6);
      CHECK(r.vertices_near_edges[0].a == 0);
      CHECK(r.vertices_near_edges[0].b == 1);
    }
    const std::string p = test::scratch(near ? "near_edge.off" : "far_edge.off");
    write_soup(s, p);
    // TetGen with its defaults (-p; -Y, which keeps the surface as given and
    // recovers no segment, meshes both).
    CHECK(test::tetgen_meshes(p, near ? "tg_near_edge.off" : "tg_far_edge.off", "-pQ") == !near);
  }
}

TEST_CASE("inspect: a nearly flat quad whose flip TetGen makes would cut another face is reported, and stops TetGen",
          "[inspect][tetgen]") {
  // A pyramid whose top is two faces, (p, q, r) and (q, p, s), folded by
  // atan(h): below 0.1 degrees TetGen (-p) merges them into one facet and
  // flips pq to rs when s lies inside the circle through p, q, r (here r
  // does: centre (2, 1.5), radius 2.5; s at 0.5 from it). The flipped
  // diagonal rs rises to h / 2 above pq's midpoint; a small tetrahedron's
  // bottom face slants from z = 1e-4 to 8e-4 just above it: clear of the
  // pyramid, cut by the flipped surface.
  struct Case {
    const char* name;
    double h;     // the fold: s = (2, -1, h)
    double ry;    // r = (2, ry, 0)
    double lift;  // added to the small tetrahedron's z
    bool hazard;
  };
  int n = 0;
  for (const Case& c : {Case{"flipped diagonal cuts a face", 1e-3, 1, 0, true},
                        Case{"coplanar: the flip changes nothing", 0, 1, 0, false},
                        Case{"Delaunay quad: TetGen keeps pq", 1e-3, 4.5, 0, false},
                        Case{"the face clear of the flipped diagonal", 1e-3, 1, 1e-2, false}}) {
    INFO(c.name);
    const Soup pyramid = test::soup({{0, 0, 0}, {4, 0, 0}, {2, c.ry, 0}, {2, -1, c.h}, {2, 0, -1}},
                                    {{0, 1, 2}, {1, 0, 3}, {2, 1, 4}, {0, 2, 4}, {3, 0, 4}, {1, 3, 4}});
    const double z = c.lift;
    const Soup small = test::soup({{1.9, -0.05, 1e-4 + z}, {2.1, -0.05, 1e-4 + z}, {2.0, 0.05, 8e-4 + z}, {2, 0, 0.5}},
                                  {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}});
    const Soup s = test::concat(pyramid, small);
    InspectOptions io;
    io.tetgen_segments = true;
    const Report r = inspect(s, io);
    REQUIRE(r.certified_clean());
    REQUIRE(r.sharp_folds.empty());
    CHECK(r.flip_hazards.size() == (c.hazard ? 1u : 0u));
    if (c.hazard) CHECK(r.flip_hazards[0] == FacePair{0, 1});
    CHECK(r.tetgen_ready() == !c.hazard);
    const std::string name = "flip_" + std::to_string(++n) + ".off", path = test::scratch(name);
    write_soup(s, path);
    CHECK(test::tetgen_meshes(path, "tg_" + name, "-pQ") == !c.hazard);
  }
}

TEST_CASE("inspect: edges passing closer than TetGen's shortest edge are reported, and stop TetGen",
          "[inspect][tetgen]") {
  // Two faces sharing corner 4, from a surface `rebuild` made of
  // manifold__openscad-nonmanifold-crash (fixtures/corpus), with two far
  // points giving it that surface's bounding box (diagonal ~31, so TetGen's
  // shortest edge is ~3.1e-7). Edge 3-1 of the first and edge 4-2 of the
  // second pass within ~1e-16 of each other (exactly apart: the four points
  // are coplanar to 2e-19, the pair test finds no intersection); TetGen
  // splits them at Steiner points that land on each other and aborts
  // ("very small input feature size"). Moved 1e-6 apart along their common
  // normal (more than the shortest edge), neither is reported and TetGen
  // meshes them.
  const std::vector<Point3d> p = {{-18.030730171908104, 2.3263691842875893, -205.46079155666953},
                                  {-18.041955058990563, 2.337601092623986, -205.32686727720267},
                                  {-18.041955450731763, 2.3488263714476445, -205.32686688546147},
                                  {-18.0, 2.3068709207158804, -205.3688223361932},
                                  {-18.030730171908104, 2.3151347778433182, -205.33809216428511}};
  auto minus = [](const Point3d& a, const Point3d& b) { return Point3d{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
  const Point3d u = minus(p[1], p[3]), v = minus(p[2], p[4]);
  Point3d n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (double& x : n) x /= len;
  int k = 0;
  for (const double shift : {0.0, 1e-6}) {
    INFO("second face moved by " << shift);
    std::vector<Point3d> q = p;
    for (int i : {0, 2, 4})
      for (int c = 0; c < 3; ++c) q[i][c] += shift * n[c];
    q.push_back({q[0][0] + 22, q[0][1], q[0][2]});
    q.push_back({q[0][0], q[0][1] + 22, q[0][2]});
    Soup s;
    s.points = q;
    s.add_triangle(1, 4, 3);
    s.add_triangle(0, 4, 2);
    InspectOptions io;
    io.tetgen_segments = true;
    const Report r = inspect(s, io);
    REQUIRE(r.self_intersections.empty());
    REQUIRE(r.vertices_near_edges.empty());
    REQUIRE(r.close_vertices.empty());
    const bool near = shift == 0;
    REQUIRE(r.edges_near_edges.size() == (near ? 1u : 0u));
    if (near) {
      CHECK(r.edges_near_edges[0].e == std::array<Index, 2>{1, 3});
      CHECK(r.edges_near_edges[0].f == std::array<Index, 2>{2, 4});
    }
    const std::string name = "edges_near_" + std::to_string(++k) + ".off", path = test::scratch(name);
    write_soup(s, path);
    CHECK(test::tetgen_meshes(path, "tg_" + name, "-pQ") == !near);
  }
}

TEST_CASE("inspect: a vertex closer than TetGen's shortest edge to a face is reported", "[inspect][tetgen]") {
  // A tetrahedron whose bottom face lies in z = 0 and another standing on it
  // apex down, the apex h above the bottom face's interior (the first's top
  // is at z = -1: the bottom face is its top face here). TetGen's shortest
  // edge is 1e-8 x the diagonal (~3.5e-8); found on rebuild's surface of
  // vhacd__hornbug, a grid vertex 1e-19 over a kept input face, where
  // tetgen -p aborts recovering a facet (it meshes this small case).
  for (const auto& [h, near] : {std::pair{1e-12, true}, {1e-3, false}}) {
    INFO("height " << h);
    const Soup below = test::soup({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, -1}},
                                  {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}});
    const Soup above = test::soup({{0.5, 0.5, h}, {0, 0, 1}, {2, 0, 1}, {0, 2, 1}},
                                  {{1, 2, 3}, {0, 2, 1}, {0, 3, 2}, {0, 1, 3}});
    const Soup s = test::concat(below, above);
    InspectOptions io;
    io.tetgen_segments = true;
    const Report r = inspect(s, io);
    REQUIRE(r.certified_clean());
    REQUIRE(r.vertices_near_faces.size() == (near ? 1u : 0u));
    if (near) {
      CHECK(r.vertices_near_faces[0].vertex == 4);
      CHECK(r.vertices_near_faces[0].face == 0);
    }
    CHECK(r.edges_near_edges.empty());
    CHECK(r.tetgen_ready() == !near);
  }
}

TEST_CASE("inspect: the sign of the enclosed volume, exactly, for the whole surface and per component", "[inspect]") {
  const Report out = inspect(test::box({0, 0, 0}, {1, 1, 1}));
  CHECK(out.volume_sign == 1);
  CHECK(out.inward_components == 0);
  const Report in = inspect(test::box({0, 0, 0}, {1, 1, 1}, true));
  CHECK(in.certified_clean());  // a consistent orientation: not a defect
  CHECK(in.volume_sign == -1);
  CHECK(in.inward_components == 1);
  // a cavity: the whole encloses positive volume, one component negative
  const Report cavity = inspect(test::concat(test::box({0, 0, 0}, {3, 3, 3}), test::box({1, 1, 1}, {2, 2, 2}, true)));
  CHECK(cavity.volume_sign == 1);
  CHECK(cavity.inward_components == 1);
  // A millimetre box 1e8 from the origin: about the origin each determinant
  // is ~1e24 and the volume 1e-9 (the long double sum gave 97756); the sign
  // is exact, and the measured volume is summed about the bbox centre.
  for (const bool inward : {false, true}) {
    const Report far = inspect(test::box({1e8, 1e8, 1e8}, {1e8 + 1e-3, 1e8 + 1e-3, 1e8 + 1e-3}, inward));
    REQUIRE(far.closed);
    CHECK(far.volume_sign == (inward ? -1 : 1));
    const double side = (1e8 + 1e-3) - 1e8;  // the double box's side, exactly (Sterbenz)
    CHECK(far.signed_volume == Approx((inward ? -1 : 1) * side * side * side).epsilon(1e-9));
  }
  // two triangles back to back: closed and oriented, volume exactly zero
  const Report flat = inspect(test::soup({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 1}}));
  CHECK(flat.closed);
  CHECK(flat.volume_sign == 0);
  CHECK(flat.inward_components == 0);
  // open: not asked
  const Report open = inspect(test::soup({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 2, 1}}));
  CHECK(open.volume_sign == 0);
}

namespace {

/// Per component of `n`, in the order of `parts`' first faces: turned?
std::vector<int> turned_by_part(const Nesting& n, const std::vector<std::size_t>& first_faces) {
  std::vector<int> t;
  for (std::size_t f : first_faces) t.push_back(n.turned[n.face_component[f]]);
  return t;
}

}  // namespace

TEST_CASE("nesting: inside-out components are those with negative volume inside no other and cavities are left",
          "[inspect]") {
  const Soup outer = test::box({0, 0, 0}, {3, 3, 3}), inner = test::box({1, 1, 1}, {2, 2, 2});
  SECTION("one box inside out") {
    const Soup s = reversed(outer);
    const Report r = inspect(s);
    CHECK(r.nesting_checked);
    CHECK(r.inside_out_components == 1);
    const Nesting n = nesting(s);
    CHECK(turned_by_part(n, {0}) == std::vector<int>{1});
    const Report after = inspect(turned_outward(s, n));
    CHECK(after.certified_clean());
    CHECK(after.volume_sign == 1);
    CHECK(after.inward_components == 0);
    CHECK_FALSE(after.nesting_checked);  // nothing faces inwards: not asked
  }
  SECTION("a cavity: nothing to turn") {
    const Soup s = test::concat(outer, reversed(inner));
    const Report r = inspect(s);
    CHECK(r.nesting_checked);
    CHECK(r.inside_out_components == 0);
    CHECK(r.cavities == 1);
    CHECK(turned_by_part(nesting(s), {0, 12}) == std::vector<int>{0, 0});
  }
  SECTION("decided beside the self-intersection pass, kept only where that certifies the surface") {
    // in parallel the nesting is decided before the intersections are known
    for (const bool parallel : {true, false}) {
      InspectOptions o;
      o.parallel = parallel;
      const Report cavity = inspect(test::concat(outer, reversed(inner)), o);
      CHECK(cavity.nesting_checked);
      CHECK(cavity.cavities == 1);
      // the inner box reaching through the outer one's wall
      const Soup through = test::concat(outer, reversed(test::box({1, 1, 1}, {2, 2, 4})));
      const Report crossing = inspect(through, o);
      CHECK_FALSE(crossing.self_intersections.empty());
      CHECK(crossing.inward_components == 1);
      CHECK_FALSE(crossing.nesting_checked);
      CHECK(crossing.cavities == 0);
    }
  }
  SECTION("a hollow box inside out: both shells turn, the cavity comes back") {
    const Soup s = test::concat(reversed(outer), inner);
    const Nesting n = nesting(s);
    CHECK(n.inside_out_count == 1);
    CHECK(turned_by_part(n, {0, 12}) == std::vector<int>{1, 1});
    const Report after = inspect(turned_outward(s, n));
    CHECK(after.volume_sign == 1);
    CHECK(after.cavities == 1);
    CHECK(after.inside_out_components == 0);
  }
  SECTION("an inside-out shell around a cavity: the cavity is already one, only the shell turns") {
    const Soup s = test::concat(reversed(outer), reversed(inner));
    const Nesting n = nesting(s);
    CHECK(n.inside_out_count == 1);
    CHECK(n.cavity_count == 1);
    CHECK(turned_by_part(n, {0, 12}) == std::vector<int>{1, 0});
  }
  SECTION("an island in a cavity of an inside-out solid: every depth faces its way") {
    const Soup island = test::box({1.4, 1.4, 1.4}, {1.6, 1.6, 1.6});
    const Soup s = test::concat(test::concat(reversed(outer), inner), reversed(island));
    const Nesting n = nesting(s);
    CHECK(turned_by_part(n, {0, 12, 24}) == std::vector<int>{1, 1, 1});
    const Nesting after = nesting(turned_outward(s, n));
    CHECK(after.volume_sign == std::vector<int>{1, -1, 1});
  }
  SECTION("crossing components: an inverted box mostly outside the other turns, a cavity through a wall stays") {
    // [1,3]^3 inverted across [0,2]^3's corner: an eighth of its area inside
    const Soup overlap = test::concat(test::box({0, 0, 0}, {2, 2, 2}), reversed(test::box({1, 1, 1}, {3, 3, 3})));
    REQUIRE_FALSE(inspect(overlap).self_intersections.empty());
    const Nesting n = nesting(overlap, true);
    CHECK(n.inside_out_count == 1);
    CHECK(n.cavity_count == 0);
    CHECK(turned_by_part(n, {0, 12}) == std::vector<int>{0, 1});
    // a cavity 3.5 high in a box 4 high, through its top: 8 of 36 area units outside
    const Soup through = test::concat(test::box({0, 0, 0}, {4, 4, 4}), reversed(test::box({1, 1, 1}, {3, 3, 4.5})));
    REQUIRE_FALSE(inspect(through).self_intersections.empty());
    const Nesting c = nesting(through, true);
    CHECK(c.inside_out_count == 0);
    CHECK(c.cavity_count == 1);
    CHECK(turned_by_part(c, {0, 12}) == std::vector<int>{0, 0});
    // the cavity turned out by its depth rule: a box inside out around it
    const Nesting both = nesting(reversed(through), true);
    CHECK(turned_by_part(both, {0, 12}) == std::vector<int>{1, 1});
  }
  SECTION("crossing components: how deep each crossing pair reaches, and the smaller part's size") {
    const Soup deep = test::concat(test::box({0, 0, 0}, {2, 2, 2}), test::box({1, 1, 1}, {3, 3, 3}));
    std::vector<Interpenetration> c = interpenetrations(deep, inspect(deep).self_intersections);
    REQUIRE(c.size() == 1);
    CHECK(c[0].depth == Approx(1.0));  // corner (2, 2, 2) in the other
    CHECK(c[0].part == Approx(std::sqrt(12.0)));
    // a third box grazing the first: a second pair, 0.1 deep, the grazing box the smaller
    const Soup graze = test::concat(deep, test::box({-0.9, 0.5, 0.5}, {0.1, 1.5, 1.5}));
    c = interpenetrations(graze, inspect(graze).self_intersections);
    REQUIRE(c.size() == 2);
    CHECK(c[1].depth == Approx(0.1));
    CHECK(c[1].part == Approx(std::sqrt(3.0)));
    // a component crossing itself: not a question of parts
    const Soup knot = read_soup(test::fixture("knot_tube_r1.2.off"));
    CHECK(interpenetrations(knot, inspect(knot).self_intersections).empty());
  }
  SECTION("an outward part inside a solid is left as it is (embedded, not a cavity gone wrong)") {
    const Soup s = test::concat(outer, inner);
    const Report r = inspect(s);
    CHECK(r.inward_components == 0);
    CHECK(r.inside_out_components == 0);
    CHECK(turned_by_part(nesting(s), {0, 12}) == std::vector<int>{0, 0});
  }
  SECTION("inside the bounding box is not inside: the exact test decides") {
    // A tetrahedron x, y, z >= 0, x + y + z <= 10; two inward boxes within
    // its bounding box, one inside it (a cavity), one beyond its slanted face.
    Soup tet = test::tetrahedron();
    for (Point3d& p : tet.points)
      for (double& x : p) x *= 10;
    const Soup cavity = reversed(test::box({1, 1, 1}, {2, 2, 2})), beyond = reversed(test::box({6, 6, 6}, {7, 7, 7}));
    const Soup s = test::concat(test::concat(tet, cavity), beyond);
    const Report r = inspect(s);
    REQUIRE(r.certified_clean());
    CHECK(r.inward_components == 2);
    CHECK(r.inside_out_components == 1);
    CHECK(r.cavities == 1);
    CHECK(turned_by_part(nesting(s), {0, 4, 16}) == std::vector<int>{0, 0, 1});
  }
  SECTION("self-intersecting: nesting is undefined, not asked") {
    const Soup s = test::concat(reversed(outer), reversed(test::box({2, 2, 2}, {4, 4, 4})));
    const Report r = inspect(s);
    REQUIRE(r.closed);
    REQUIRE(r.oriented);
    CHECK(r.inward_components == 2);
    CHECK_FALSE(r.self_intersections.empty());
    CHECK_FALSE(r.nesting_checked);
    CHECK(r.inside_out_components == 0);
  }
}

TEST_CASE("inspect_from: the report of a surface made from another, searching only its changed faces, is inspect()'s",
          "[inspect]") {
  // bones (366 pairs) with a corner of an intersecting face pushed out: the
  // faces round it are new, the pairs change; the rest come from bones'.
  const Soup base = read_soup(test::fixture("bones.off"));
  const Report base_report = inspect(base);
  REQUIRE(base_report.self_intersections.size() > 300);
  Soup edited = base;
  const Index moved = edited.face(base_report.self_intersections[100].first)[0];
  for (int k = 0; k < 3; ++k) edited.points[moved][k] *= 1.3;
  const Report full = inspect(edited);
  REQUIRE(full.self_intersections != base_report.self_intersections);  // at stake
  std::size_t searched = 0;
  const Report from = inspect_from(edited, base, base_report.self_intersections, {}, &searched);
  CHECK(from.self_intersections == full.self_intersections);
  CHECK(from.certified_clean() == full.certified_clean());
  CHECK(searched > 0);
  CHECK(searched < 20);

  // Identical points: the report pairs welded faces, so the whole soup is searched.
  Soup twin = edited;
  twin.points.push_back(twin.points[twin.face(0)[0]]);
  twin.indices[0] = static_cast<Index>(twin.points.size() - 1);
  const Report twin_from = inspect_from(twin, base, base_report.self_intersections, {}, &searched);
  CHECK(searched == twin.face_count());
  CHECK(twin_from.self_intersections == inspect(twin).self_intersections);
}
