// The global pass against CGAL's own PMP::self_intersections on manifold
// fixtures, and the parallel pass against the sequential one.
#include <catch2/catch.hpp>

#include <set>

#include <CGAL/Polygon_mesh_processing/self_intersections.h>

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

}  // namespace

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
  // segment tree: both must find what the full pass finds among the pairs
  // touching a flagged face (mannequin-devil's 1643 pairs).
  const Soup s = read_soup(test::fixture("mannequin-devil.off"));
  const std::vector<FacePair> all = find_self_intersections(s);
  REQUIRE(!all.empty());
  for (const std::size_t stride : {std::size_t(7), std::size_t(2000)}) {
    INFO("every " << stride << "th face of an intersecting pair flagged");
    std::vector<char> only(s.face_count(), 0);
    std::size_t flagged = 0;
    for (std::size_t i = stride / 2; i < all.size(); i += stride) {  // the later face: partners before and after
      flagged += !only[all[i].second];
      only[all[i].second] = 1;
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
