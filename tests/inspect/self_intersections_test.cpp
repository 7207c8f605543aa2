// The global pass against CGAL's own PMP::self_intersections on manifold
// fixtures, and the parallel pass against the sequential one.
#include <catch2/catch.hpp>

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
