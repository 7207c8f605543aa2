// The adaptive overlay grid's tetrahedral mesh (detail/kuhn_mesh): Kuhn's
// triangulation of cubes, bisected locally by Maubach's rule, must stay a
// conforming triangulation of the cubes — every interior face shared by
// exactly two leaf tetrahedra, the leaves filling the cubes' volume exactly,
// no sliver — whatever is refined, and whatever cubes are added afterwards.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <random>
#include <set>

#include "polyheal/repair/detail/kuhn_mesh.h"

using polyheal::detail::KuhnMesh;

namespace {

using Face = std::array<std::uint32_t, 3>;

std::int64_t volume6(const KuhnMesh& m, const KuhnMesh::Tet& t) {  // 6 x volume, fine lattice units
  const auto &p = m.corner(t.v[0]), &q = m.corner(t.v[1]), &r = m.corner(t.v[2]), &s = m.corner(t.v[3]);
  const std::int64_t u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  const std::int64_t v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
  const std::int64_t w[3] = {s[0] - p[0], s[1] - p[1], s[2] - p[2]};
  return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
}

double squared_length(const KuhnMesh& m, std::uint32_t a, std::uint32_t b) {
  double s = 0;
  for (int x = 0; x < 3; ++x) s += double(m.corner(a)[x] - m.corner(b)[x]) * double(m.corner(a)[x] - m.corner(b)[x]);
  return s;
}

/// The checks every refinement must pass. Returns the deepest leaf level.
int check_conforming(const KuhnMesh& m) {
  std::map<Face, int> faces;
  std::int64_t volume = 0;
  std::size_t flat = 0, misoriented = 0;
  int deepest = 0;
  double worst_ratio = 1;
  auto face_of = [](const KuhnMesh::Tet& t, int f) {
    Face face;
    int n = 0;
    for (int x = 0; x < 4; ++x)
      if (x != f) face[n++] = t.v[x];
    std::sort(face.begin(), face.end());
    return face;
  };
  for (const KuhnMesh::Tet& t : m.tets()) {
    if (!t.leaf) continue;
    const std::int64_t v6 = volume6(m, t);
    flat += v6 == 0;
    misoriented += (v6 > 0 ? 1 : -1) != m.orientation(t);
    volume += v6 > 0 ? v6 : -v6;
    deepest = std::max(deepest, int(t.level));
    double lo = 1e300, hi = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        lo = std::min(lo, squared_length(m, t.v[a], t.v[b]));
        hi = std::max(hi, squared_length(m, t.v[a], t.v[b]));
      }
    worst_ratio = std::max(worst_ratio, hi / lo);
    for (int f = 0; f < 4; ++f) ++faces[face_of(t, f)];
  }
  CHECK(flat == 0);
  CHECK(misoriented == 0);
  // The leaves tile the cubes: their volumes add up to the cubes'.
  const std::int64_t s = m.scale();
  CHECK(volume == std::int64_t(m.cube_count()) * 6 * s * s * s);
  // Face to face: an interior face has a leaf on each side; a face with one
  // leaf lies on a cube face with no cube across it.
  std::size_t overused = 0, open_inside = 0;
  for (const KuhnMesh::Tet& t : m.tets()) {
    if (!t.leaf) continue;
    for (int f = 0; f < 4; ++f) {
      const int uses = faces.at(face_of(t, f));
      overused += uses > 2;
      KuhnMesh::Coord across;
      if (uses == 1 && (!m.across_cube_face(t, f, across) || m.find_cube(across[0], across[1], across[2]) >= 0))
        ++open_inside;
    }
  }
  CHECK(overused == 0);
  CHECK(open_inside == 0);
  // No sliver: Kuhn's tetrahedron has edges 1, sqrt 2, sqrt 3; its
  // descendants keep the longest within twice the shortest.
  CHECK(worst_ratio <= 4.0 + 1e-12);
  return deepest;
}

}  // namespace

TEST_CASE("kuhn mesh: the six Kuhn tetrahedra of a cube, and of a block of cubes, are conforming", "[rebuild][kuhn]") {
  KuhnMesh m(2);
  m.add_cube(5, 5, 5);
  CHECK(m.corner_count() == 8);
  CHECK(std::count_if(m.tets().begin(), m.tets().end(), [](const KuhnMesh::Tet& t) { return t.leaf; }) == 6);
  check_conforming(m);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) m.add_cube(4 + i, 4 + j, 4 + k);
  CHECK(m.cube_count() == 27);
  CHECK(m.corner_count() == 64);
  check_conforming(m);
}

TEST_CASE("kuhn mesh: one tetrahedron bisected to the finest level leaves a conforming mesh", "[rebuild][kuhn]") {
  // Each row: halvings, which of the centre cube's six tetrahedra is refined.
  for (int halvings : {1, 2, 3})
    for (int which = 0; which < 6; ++which) {
      KuhnMesh m(halvings);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          for (int k = 0; k < 3; ++k) m.add_cube(10 + i, 10 + j, 10 + k);
      const std::uint32_t centre = std::uint32_t(m.find_cube(11, 11, 11));
      std::uint32_t target = 0;
      int seen = 0;
      for (std::uint32_t t = 0; t < m.tets().size(); ++t)
        if (m.tets()[t].cube == centre && seen++ == which) target = t;
      // Then, level by level, the first leaf of the centre cube at that
      // level: a chain of bisections down to the finest level.
      m.bisect({target});
      for (int level = 1; level < m.max_level(); ++level)
        for (std::uint32_t t = 0; t < m.tets().size(); ++t)
          if (m.tets()[t].leaf && m.tets()[t].level == level && m.tets()[t].cube == centre) {
            m.bisect({t});
            break;
          }
      const int deepest = check_conforming(m);
      CHECK(deepest <= m.max_level());
    }
}

TEST_CASE("kuhn mesh: random local refinement, then cubes added beside refined ones, stays conforming",
          "[rebuild][kuhn]") {
  std::mt19937 rng(12345);
  for (int round = 0; round < 4; ++round) {
    KuhnMesh m(3);
    // An irregular sparse set of cubes (a blob with holes).
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j)
        for (int k = 0; k < 5; ++k)
          if ((i * 7 + j * 3 + k * 5 + round) % 4 != 0) m.add_cube(20 + i, 20 + j, 20 + k);
    for (int pass = 0; pass < 9; ++pass) {
      std::vector<std::uint32_t> pick;
      for (std::uint32_t t = 0; t < m.tets().size(); ++t)
        if (m.tets()[t].leaf && rng() % 5 == 0) pick.push_back(t);
      m.bisect(pick);
    }
    const int deepest = check_conforming(m);
    CHECK(deepest <= m.max_level());
    // Cubes added next to refined ones are bisected to match them.
    const std::size_t before = m.cube_count();
    for (int i = -1; i <= 5; ++i)
      for (int j = -1; j <= 5; ++j) m.add_cube(20 + i, 20 + j, 19);
    CHECK(m.cube_count() > before);
    check_conforming(m);
  }
}
