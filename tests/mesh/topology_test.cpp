// sheets_to_leave_out: which sheets hang off the rest (walls between solids;
// with flaps, fins and flaps with free edges) and may be left out so that a
// surface bounds a volume — and that a hole or the solid itself never is.
#include <catch2/catch.hpp>

#include <random>

#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>

#include "polyheal/mesh/topology.h"
#include "support/builders.h"

using namespace polyheal;

namespace {

/// The unit box, its face `missing` (if any) left out, and a fin: a
/// triangle on the box's edge (0,1), its third corner outside the box.
Soup box_with(int missing, bool fin, bool second_fin_face = false) {
  const Soup box = test::box({0, 0, 0}, {1, 1, 1});
  Soup s;
  s.points = box.points;
  for (std::size_t f = 0; f < box.face_count(); ++f)
    if (int(f) != missing) s.add_triangle(box.face(f)[0], box.face(f)[1], box.face(f)[2]);
  if (fin) {
    s.points.push_back({0.5, -0.3, -0.3});  // 8
    s.add_triangle(1, 0, 8);
    if (second_fin_face) {  // the flap goes on across the fin's free edge 0-8
      s.points.push_back({-0.2, -0.6, -0.4});  // 9
      s.add_triangle(0, 9, 8);
    }
  }
  return s;
}

}  // namespace

TEST_CASE("sheets_to_leave_out: a fin on a closed box goes, the box stays", "[mesh]") {
  SheetsLeftOut r = sheets_to_leave_out(box_with(-1, true), true);
  CHECK(r.faces == std::vector<std::size_t>{12});
  CHECK(r.imbalance == 0);
  r = sheets_to_leave_out(box_with(-1, true, true), true);
  CHECK(r.faces == std::vector<std::size_t>{12, 13});
  CHECK(r.imbalance == 0);
  // Without flaps only walls go (every rim edge with 3+ uses): a fin stays,
  // and the edge named is the fin's smallest unbalanced one, (0, 1).
  r = sheets_to_leave_out(box_with(-1, true), false);
  CHECK(r.faces.empty());
  CHECK(r.imbalance == 3);
  CHECK((r.unbalanced_a == 0 && r.unbalanced_b == 1 && r.unbalanced_by == 1));
}

TEST_CASE("sheets_to_leave_out: a hole stays a hole, with or without a fin beside it", "[mesh]") {
  // The box without its top face 2: the rest is one sheet with free edges
  // only; it hangs off nothing.
  SheetsLeftOut r = sheets_to_leave_out(box_with(2, false), true);
  CHECK(r.faces.empty());
  CHECK(r.imbalance == 3);
  // With the fin: the fin goes; then the box's rim edge (0,1) is used by
  // nothing outside it, so the box, free along its hole, is not a flap.
  r = sheets_to_leave_out(box_with(2, true), true);
  CHECK(r.faces == std::vector<std::size_t>{11});
  CHECK(r.imbalance == 3);
}

TEST_CASE("is_polygon_mesh: decides as CGAL's is_polygon_soup_a_polygon_mesh on random small soups", "[mesh]") {
  // Triangles on a handful of vertices, random orientations: pinched
  // vertices, edges used three times or twice one way, repeated indices and
  // closed or open fans all come up.
  std::mt19937 rng(23);
  std::size_t meshes = 0, others = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const int n = 4 + int(rng() % 4), faces = 1 + int(rng() % 7);
    std::vector<std::vector<std::size_t>> polys;
    Soup soup;
    soup.points.resize(std::size_t(n));
    for (int f = 0; f < faces; ++f) {
      std::vector<std::size_t> p{rng() % n, rng() % n, rng() % n};
      if (trial % 3 && (p[0] == p[1] || p[1] == p[2] || p[0] == p[2])) continue;  // mostly proper triangles
      polys.push_back(p);
      soup.add_triangle(Index(p[0]), Index(p[1]), Index(p[2]));
    }
    if (polys.empty()) continue;
    const bool want = CGAL::Polygon_mesh_processing::is_polygon_soup_a_polygon_mesh(polys);
    INFO("trial " << trial);
    CHECK(is_polygon_mesh(analyze_topology(soup)) == want);
    ++(want ? meshes : others);
  }
  CHECK(meshes > 300);
  CHECK(others > 300);
}
