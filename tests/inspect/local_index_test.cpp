// The local query: after moving vertices, "what do these faces intersect now?"
// must equal a global recount restricted to those faces.
#include <catch2/catch.hpp>

#include <random>
#include <set>

#include "polyheal/inspect/local_index.h"
#include "polyheal/inspect/self_intersections.h"
#include "polyheal/io/read.h"
#include "polyheal/mesh/convert.h"
#include "support/builders.h"

using namespace polyheal;

namespace {

using PairSet = std::set<std::pair<std::size_t, std::size_t>>;

std::vector<face_descriptor> faces_around(const Mesh& m, vertex_descriptor v) {
  std::vector<face_descriptor> out;
  for (face_descriptor f : CGAL::faces_around_target(m.halfedge(v), m))
    if (f != Mesh::null_face()) out.push_back(f);
  return out;
}

/// Global recount (soup pass on the mesh's exact double coordinates), keeping
/// the pairs that involve one of `faces`.
PairSet global_pairs_touching(const Mesh& m, const std::vector<face_descriptor>& faces) {
  const Soup s = mesh_to_soup(m);  // faces in mesh order: index i == face i (no removals here)
  std::set<std::size_t> asked;
  for (face_descriptor f : faces) asked.insert(static_cast<std::size_t>(f));
  PairSet out;
  for (const FacePair& p : find_self_intersections(s))
    if (asked.count(p.first) || asked.count(p.second)) out.insert({p.first, p.second});
  return out;
}

PairSet local_pairs(const LocalIndex& index, const std::vector<face_descriptor>& faces) {
  PairSet out;
  for (const auto& [f, g] : index.intersections(faces)) {
    const std::size_t a = static_cast<std::size_t>(f), b = static_cast<std::size_t>(g);
    CHECK(out.insert({std::min(a, b), std::max(a, b)}).second);  // each pair once
  }
  return out;
}

}  // namespace

TEST_CASE("local_index: move a vertex, ask again, compare with a global recount", "[inspect][smoke]") {
  Mesh m;
  REQUIRE(soup_to_mesh(read_soup(test::fixture("tube_edge2.42.off")), m).ok);
  LocalIndex index(m);
  CHECK(index.size() == m.number_of_faces());

  // Push one inner-wall vertex (radius 4.8) outwards through the outer wall.
  vertex_descriptor inner = *m.vertices().begin();
  for (vertex_descriptor v : m.vertices()) {
    const Point& p = m.point(v);
    if (CGAL::to_double(p.x() * p.x() + p.y() * p.y()) < 24 && CGAL::to_double(p.z()) > 4) {
      inner = v;
      break;
    }
  }
  const std::vector<face_descriptor> star = faces_around(m, inner);
  CHECK(local_pairs(index, star).empty());
  const Point old = m.point(inner);
  m.point(inner) = Point(old.x() * 1.1, old.y() * 1.1, old.z());
  index.update(star);
  const PairSet moved = local_pairs(index, star);
  CHECK_FALSE(moved.empty());
  CHECK(moved == global_pairs_touching(m, star));
  CHECK(index.intersects(star));

  // Move it back: clean again.
  m.point(inner) = old;
  index.update(star);
  CHECK(local_pairs(index, star).empty());
  CHECK_FALSE(index.intersects(star));
}

TEST_CASE("local_index: random vertex moves agree with global recounts", "[inspect]") {
  Mesh m;
  REQUIRE(soup_to_mesh(read_soup(test::fixture("tube_edge3.0.off")), m).ok);
  LocalIndex index(m);
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::size_t> pick(0, m.number_of_vertices() - 1);
  std::uniform_real_distribution<double> jitter(-0.6, 0.6);
  // 400 moves re-insert ~2400 leaves: past the rebuild of the balanced tree
  // (after 2 x 220 + 1024 insertions), so queries before and after it count.
  for (int step = 0; step < 400; ++step) {
    const vertex_descriptor v(static_cast<Mesh::size_type>(pick(rng)));
    const Point& p = m.point(v);
    m.point(v) = Point(p.x() + jitter(rng), p.y() + jitter(rng), p.z() + jitter(rng));
    const std::vector<face_descriptor> star = faces_around(m, v);
    index.update(star);
    INFO("step " << step);
    CHECK(local_pairs(index, star) == global_pairs_touching(m, star));
  }
}

TEST_CASE("local_index: a removed face is no longer reported", "[inspect]") {
  Mesh m;
  REQUIRE(soup_to_mesh(read_soup(test::fixture("tube_edge3.0.off")), m).ok);
  LocalIndex index(m);
  std::vector<face_descriptor> all(m.faces().begin(), m.faces().end());
  const auto pairs = index.intersections(all);
  REQUIRE_FALSE(pairs.empty());
  const face_descriptor gone = pairs.front().second;
  index.remove(gone);
  CHECK(index.size() == m.number_of_faces() - 1);
  for (const auto& [f, g] : index.intersections({pairs.front().first})) CHECK(g != gone);
}
