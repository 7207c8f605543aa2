// The global pass against CGAL's own PMP::self_intersections on manifold
// fixtures, and the parallel pass against the sequential one.
#include <catch2/catch.hpp>

#include <optional>
#include <random>
#include <set>

#include <CGAL/Polygon_mesh_processing/self_intersections.h>

#include "polyheal/inspect/detail/triangle_pair.h"
#include "polyheal/inspect/report.h"
#include "polyheal/inspect/self_intersections.h"
#include "polyheal/io/read.h"
#include "polyheal/mesh/convert.h"
#include "support/builders.h"

using namespace polyheal;
namespace PMP = CGAL::Polygon_mesh_processing;

namespace {

/// CGAL's pair count on the fixture loaded as an Epick Surface_mesh.
std::size_t cgal_pairs(const Soup& soup) {
  using EMesh = CGAL::Surface_mesh<InputKernel::Point_3>;
  EMesh m;
  std::vector<EMesh::Vertex_index> v;
  for (const Point3d& p : soup.points) v.push_back(m.add_vertex({p[0], p[1], p[2]}));
  for (std::size_t f = 0; f < soup.face_count(); ++f) {
    FaceView fv = soup.face(f);
    REQUIRE(m.add_face(v[fv[0]], v[fv[1]], v[fv[2]]) != EMesh::null_face());
  }
  std::vector<std::pair<EMesh::Face_index, EMesh::Face_index>> pairs;
  PMP::self_intersections(m, std::back_inserter(pairs));
  return pairs.size();
}

/// Every intersecting pair by testing every pair of faces whose boxes meet
/// (closed boxes, exact on doubles): no broad phase to trust.
std::vector<FacePair> all_pairs_tested(const Soup& s) {
  std::vector<detail::Tri<InputKernel>> tris;
  std::vector<std::array<double, 6>> boxes;  // lo x y z, hi x y z
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const FaceView v = s.face(f);
    std::array<InputKernel::Point_3, 3> p;
    std::array<double, 6> b{HUGE_VAL, HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (int k = 0; k < 3; ++k) {
      const Point3d& q = s.points[v[k]];
      p[k] = {q[0], q[1], q[2]};
      for (int a = 0; a < 3; ++a) b[a] = std::min(b[a], q[a]), b[3 + a] = std::max(b[3 + a], q[a]);
    }
    tris.push_back(detail::make_tri<InputKernel>(p[0], p[1], p[2], v[0], v[1], v[2]));
    boxes.push_back(b);
  }
  std::vector<FacePair> out;
  for (std::size_t f = 0; f < tris.size(); ++f)
    for (std::size_t g = f + 1; g < tris.size(); ++g) {
      bool meet = true;
      for (int a = 0; a < 3 && meet; ++a) meet = boxes[f][a] <= boxes[g][3 + a] && boxes[g][a] <= boxes[f][3 + a];
      if (meet && detail::faces_intersect(tris[f], tris[g])) out.push_back({f, g});
    }
  return out;
}

/// `n` small triangles (sides up to `size`) strewn over the unit cube.
Soup strewn_triangles(std::size_t n, double size, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Soup s;
  for (std::size_t t = 0; t < n; ++t) {
    const Point3d c{unit(rng), unit(rng), unit(rng)};
    const Index first = static_cast<Index>(s.points.size());
    for (int k = 0; k < 3; ++k) s.points.push_back({c[0] + size * unit(rng), c[1] + size * unit(rng), c[2] + size * unit(rng)});
    s.add_triangle(first, first + 1, first + 2);
  }
  return s;
}

}  // namespace

TEST_CASE("self_intersections: the split-and-sweep broad phase finds what testing every pair finds",
          "[inspect]") {
  // The spatial split down to parts of 1024 boxes, each part swept along
  // its thinnest axis and each straddling set swept against the boxes near
  // it, on small triangles strewn over a cube (sequential: split from 1024
  // boxes; parallel: from 20000, below that one sweep). Where a sweep would
  // test too many pairs, CGAL's segment tree takes over: the parallel pass
  // over 6000 large strewn triangles (one sweep of them all), and, among
  // them, 1000 needles from the cube's centre (overlapping one another
  // along every axis) swept against the boxes beside a split (sequential).
  // A flat grid in the plane z = 0.3 overlaps itself along z: sweeps near
  // it choose another axis.
  Soup needles;
  needles.points.push_back({0.5, 0.5, 0.5});
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (Index k = 0; k < 1000; ++k) {
    const Point3d far{unit(rng), unit(rng), unit(rng)};
    needles.points.push_back(far);
    needles.points.push_back({far[0] + 1e-3, far[1], far[2] + 1e-3});
    needles.add_triangle(0, 1 + 2 * k, 2 + 2 * k);
  }
  Soup grid;
  constexpr int kCells = 30;
  for (int i = 0; i <= kCells; ++i)
    for (int j = 0; j <= kCells; ++j) grid.points.push_back({double(i) / kCells, double(j) / kCells, 0.3});
  for (int i = 0; i < kCells; ++i)
    for (int j = 0; j < kCells; ++j) {
      const Index a = Index(i * (kCells + 1) + j), b = a + 1, c = a + kCells + 1, d = c + 1;
      grid.add_triangle(a, b, d);
      grid.add_triangle(a, d, c);
    }
  const Soup strewn = strewn_triangles(6000, 0.12, 1);
  const std::vector<std::pair<const char*, Soup>> soups = {
      {"strewn triangles", strewn},
      {"strewn triangles, needles and a grid", test::concat(test::concat(strewn, needles), grid)},
      {"many strewn triangles", strewn_triangles(24000, 0.05, 2)},
  };
  for (const auto& [name, s] : soups) {
    INFO(name);
    const std::vector<FacePair> expected = all_pairs_tested(s);
    CHECK(expected.size() > 1000);
    for (const bool parallel : {false, true}) {
      INFO((parallel ? "parallel" : "sequential"));
      SelfIntersectionOptions o;
      o.parallel = parallel;
      CHECK(find_self_intersections(s, o) == expected);
    }
  }
}

TEST_CASE("self_intersections: agrees with CGAL on manifold fixtures", "[inspect][corpus]") {
  // name, whether it must intersect (so the comparison is at stake both ways)
  const std::vector<std::pair<const char*, bool>> fixtures = {
      {"tube_edge3.0.off", true},          {"tube_edge2.42.off", false},
      {"tube_edge2.42_offset-0.15.off", true}, {"torus_knot_20k.off", false},
      {"spheres_intersecting.off", true},  {"bones.off", true},
      {"mannequin-devil.off", true},       {"cad_cylinder.off", false},
  };
  for (const auto& [name, intersecting] : fixtures) {
    INFO(name);
    const Soup s = read_soup(test::fixture(name));
    const std::vector<FacePair> ours = find_self_intersections(s);
    CHECK(ours.size() == cgal_pairs(s));
    CHECK(!ours.empty() == intersecting);
    CHECK(does_self_intersect(s) == intersecting);
  }
}

TEST_CASE("self_intersections: parallel and sequential passes find the same pairs", "[inspect]") {
  const Soup s = read_soup(test::fixture("mannequin-devil.off"));
  SelfIntersectionOptions seq;
  seq.parallel = false;
  const auto a = find_self_intersections(s, seq);
  const auto b = find_self_intersections(s);
  CHECK(a == b);
  CHECK(a.size() == 1643);  // the corpus manifest's independent exact count
}

TEST_CASE("self_intersections: a check of flagged faces finds exactly the pairs that meet one", "[inspect]") {
  // Few flagged faces are paired by direct box tests, many through the
  // segment tree, most of the soup by one scan of every box: each must find
  // what the full pass finds among the pairs touching a flagged face
  // (mannequin-devil's 1643 pairs).
  const Soup s = read_soup(test::fixture("mannequin-devil.off"));
  const std::vector<FacePair> all = find_self_intersections(s);
  REQUIRE(!all.empty());
  for (const std::size_t stride : {std::size_t(7), std::size_t(2000), std::size_t(0)}) {
    INFO((stride ? "every " + std::to_string(stride) + "th face of an intersecting pair flagged"
                 : std::string("two faces in three flagged")));
    std::vector<char> only(s.face_count(), 0);
    std::size_t flagged = 0;
    for (std::size_t i = stride / 2; stride && i < all.size(); i += stride) {  // the later face: partners before and after
      flagged += !only[all[i].second];
      only[all[i].second] = 1;
    }
    for (std::size_t f = 0; !stride && f < s.face_count(); ++f) {
      only[f] = f % 3 != 0;
      flagged += only[f];
    }
    std::vector<FacePair> expected;
    for (const FacePair& p : all)
      if (only[p.first] || only[p.second]) expected.push_back(p);
    SelfIntersectionOptions o;
    o.only = &only;
    CHECK(find_self_intersections(s, o) == expected);
    CHECK(does_self_intersect(s, o));
    CHECK(flagged > 0);
  }
}

TEST_CASE("self_intersections: the near-simplex searches of flagged faces find exactly the pairs that touch one",
          "[inspect]") {
  // At 0.2% of the diagonal mannequin-devil has thousands of vertex-face and
  // edge pairs closer than that; the searches restricted to flagged faces
  // (rebuild's check of a zip) must find what the full ones find among the
  // pairs whose face is flagged or whose vertex is a corner of one (vertex-
  // face), or with a flagged edge (edge pairs), by direct box tests (few
  // flagged) and through the segment tree (many).
  const Soup s = read_soup(test::fixture("mannequin-devil.off"));
  const double tol = 0.002 * bbox_diagonal(inspect(s));
  const std::vector<VertexNearFace> all_vf = find_vertices_near_faces(s, tol);
  std::vector<std::array<Index, 2>> edges;
  std::vector<std::size_t> face_of_edge;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const FaceView v = s.face(f);
    for (int k = 0; k < 3; ++k) {
      edges.push_back({v[k], v[(k + 1) % 3]});  // each edge twice (once per face): pairs of either copy
      face_of_edge.push_back(f);
    }
  }
  const std::vector<EdgeNearEdge> all_ee = find_edges_near_edges(s, edges, tol);
  REQUIRE(all_vf.size() > 1000);
  REQUIRE(all_ee.size() > 1000);
  for (const std::size_t stride : {std::size_t(5), std::size_t(3000)}) {
    INFO("every " << stride << "th face flagged");
    std::vector<char> only(s.face_count(), 0), corner(s.points.size(), 0), flagged_edge(edges.size(), 0);
    for (std::size_t f = stride / 2; f < s.face_count(); f += stride) only[f] = 1;
    for (std::size_t i = 0; i < edges.size(); ++i)
      if (only[face_of_edge[i]]) flagged_edge[i] = corner[edges[i][0]] = corner[edges[i][1]] = 1;
    std::vector<VertexNearFace> expected_vf;
    for (const VertexNearFace& p : all_vf)
      if (only[p.face] || corner[p.vertex]) expected_vf.push_back(p);
    const std::vector<VertexNearFace> vf = find_vertices_near_faces(s, tol, &only);
    REQUIRE(vf.size() == expected_vf.size());
    for (std::size_t i = 0; i < vf.size(); ++i) {
      CHECK(vf[i].vertex == expected_vf[i].vertex);
      CHECK(vf[i].face == expected_vf[i].face);
    }
    // An edge pair is named by its sorted ends: flagged when either copy of
    // either edge is.
    std::set<std::array<Index, 2>> flagged_ends;
    for (std::size_t i = 0; i < edges.size(); ++i)
      if (flagged_edge[i]) flagged_ends.insert({std::min(edges[i][0], edges[i][1]), std::max(edges[i][0], edges[i][1])});
    std::vector<EdgeNearEdge> expected_ee;
    for (const EdgeNearEdge& p : all_ee)
      if (flagged_ends.count(p.e) || flagged_ends.count(p.f)) expected_ee.push_back(p);
    CHECK(find_edges_near_edges(s, edges, tol, true, &flagged_edge) == expected_ee);
    CHECK(!expected_vf.empty());
    CHECK(!expected_ee.empty());
  }
}

TEST_CASE("self_intersections: pairs found from an earlier surface's equal a full search of the edited one",
          "[inspect]") {
  // mannequin-devil (1643 pairs) edited as repairs edit: points renumbered
  // and faces reordered and turned (nothing changed), then faces removed
  // (some of them intersecting), a vertex moved (its faces changed), a face
  // given a copy (which meets it), a new fan and a quad added. The pairs
  // among faces kept as they were come from the earlier search, the rest
  // from a search of the changed faces: together what a full search finds.
  const Soup base = read_soup(test::fixture("mannequin-devil.off"));
  const std::vector<FacePair> base_pairs = find_self_intersections(base);
  REQUIRE(base_pairs.size() > 1000);
  Soup renumbered;  // points reversed, faces reversed in order and turned
  const Index n = static_cast<Index>(base.points.size());
  for (Index i = 0; i < n; ++i) renumbered.points.push_back(base.points[n - 1 - i]);
  for (std::size_t f = base.face_count(); f-- > 0;) {
    const FaceView v = base.face(f);
    renumbered.add_triangle(n - 1 - v[2], n - 1 - v[1], n - 1 - v[0]);
  }
  auto same_as_full = [&](const Soup& soup) {
    const std::optional<std::vector<FacePair>> from = find_self_intersections_from(soup, base, base_pairs, 0.5);
    REQUIRE(from);
    const std::vector<FacePair> full = find_self_intersections(soup);
    CHECK(full.size() > 100);
    CHECK(*from == full);
  };
  same_as_full(renumbered);

  Soup edited;
  edited.points = renumbered.points;
  std::vector<char> dropped(renumbered.face_count(), 0);
  for (std::size_t i = 0; i < base_pairs.size(); i += 37) dropped[renumbered.face_count() - 1 - base_pairs[i].first] = 1;
  for (std::size_t f = 0; f < renumbered.face_count(); f += 101) dropped[f] = 1;
  for (std::size_t f = 0; f < renumbered.face_count(); ++f)
    if (!dropped[f]) edited.add_face(renumbered.face(f).begin(), renumbered.face(f).end());
  // a vertex of an intersecting face pushed out: its faces are new
  const Index moved = renumbered.face(renumbered.face_count() - 1 - base_pairs[500].second)[0];
  for (int k = 0; k < 3; ++k) edited.points[moved][k] *= 1.05;
  const FaceView copied = edited.face(10);
  const std::array<Index, 3> copy{copied[0], copied[1], copied[2]};
  edited.add_triangle(copy[2], copy[1], copy[0]);  // a copy, turned
  const Index c = static_cast<Index>(edited.points.size());
  edited.points.push_back({0, 0, 0});  // a fan from the centre of the bounding box: it crosses the surface
  for (std::size_t f = 0; f < 40; ++f) {
    const FaceView v = edited.face(f * 300);
    edited.add_triangle(c, v[0], v[1]);
  }
  const std::array<Index, 4> quad{c, edited.face(7)[0], edited.face(7)[1], edited.face(7)[2]};
  edited.add_face(quad.begin(), quad.end());
  same_as_full(edited);
  // most faces changed: a full search is quicker, and nothing is returned
  Soup shifted = edited;
  for (Point3d& p : shifted.points) p[0] += 1e-3;
  CHECK_FALSE(find_self_intersections_from(shifted, base, base_pairs));
}
