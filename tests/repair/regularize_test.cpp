// polyheal regularize (Jung, Shin & Choi): each case checks the written
// file with the exact oracle (inspect(), independent of the regularizer's own
// bookkeeping), the enclosed volume against the solids' union computed here,
// that the output lies on the input surface, and for overlapping closed
// meshes that TetGen accepts the output where it refused the input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include <tbb/global_control.h>

#include "polyheal/inspect/report.h"
#include "polyheal/io/read.h"
#include "polyheal/io/write.h"
#include "polyheal/mesh/errors.h"
#include "polyheal/mesh/vec3.h"
#include "polyheal/repair/detail/distance.h"
#include "polyheal/repair/regularize.h"
#include "support/builders.h"

using namespace polyheal;

namespace {

using Box = std::array<Point3d, 2>;  // min, max corners

/// A closed box, outward (or, with `inward`, facing in: a cavity's wall).
Soup box(const Box& b, bool inward = false) { return test::box(b[0], b[1], inward); }

double volume(const Box& b) { return (b[1][0] - b[0][0]) * (b[1][1] - b[0][1]) * (b[1][2] - b[0][2]); }

/// The intersection of two boxes (empty: zero volume).
Box meet(const Box& a, const Box& b) {
  Box m;
  for (int k = 0; k < 3; ++k) {
    m[0][k] = std::max(a[0][k], b[0][k]);
    m[1][k] = std::max(m[0][k], std::min(a[1][k], b[1][k]));
  }
  return m;
}

/// Writes the output to scratch(`name`) and reads it back: the tests check
/// the file, as the CLI does.
Soup written(const RegularizeResult& result, const std::string& name, std::string* path = nullptr) {
  const std::string p = test::scratch(name);
  write_soup(result.soup, p);
  if (path) *path = p;
  return read_soup(p);
}

/// Largest distance from an output vertex to the input surface: the output
/// must lie on the input (up to rounding the points on intersection curves).
double off_surface(const Soup& input, const Soup& output) {
  const detail::SurfaceDistance d(input);
  double m = 0;
  for (const Point3d& p : output.points) m = std::max(m, std::sqrt(d.squared_distance(p)));
  return m;
}

}  // namespace

TEST_CASE("regularize: two overlapping boxes become their union, untouched faces kept bit for bit") {
  const Box a{{{0, 0, 0}, {2, 2, 2}}}, b{{{1, 0.5, 0.25}, {3, 2.5, 2.75}}};
  const Soup in = test::concat(box(a), box(b));
  REQUIRE(inspect(in).self_intersections.size() > 0);
  const RegularizeResult r = regularize(in);
  const Soup out = written(r, "regularize_boxes.off");
  const Report rep = inspect(out);
  CHECK(rep.certified_clean());
  CHECK(rep.components == 1);
  CHECK(rep.signed_volume == Approx(volume(a) + volume(b) - volume(meet(a, b))).epsilon(1e-12));
  CHECK(off_surface(in, out) < 1e-12);
  // an input face that meets nothing and lies outside the other box is output as it was
  const auto kept = test::faces_by_position(out);
  std::size_t expected = 0, found = 0;
  const std::set<std::size_t> crossing = [&] {
    std::set<std::size_t> s;
    for (const FacePair& p : inspect(in).self_intersections) s.insert({p.first, p.second});
    return s;
  }();
  for (std::size_t f = 0; f < in.face_count(); ++f) {
    if (crossing.count(f)) continue;
    const Box& other = f < 12 ? b : a;
    Point3d c{0, 0, 0};
    for (Index v : in.face(f))
      for (int k = 0; k < 3; ++k) c[k] += in.points[v][k] / 3;
    bool inside = true;
    for (int k = 0; k < 3; ++k) inside = inside && c[k] > other[0][k] && c[k] < other[1][k];
    if (inside) continue;
    ++expected;
    const Soup one = test::soup({in.points[in.face(f)[0]], in.points[in.face(f)[1]], in.points[in.face(f)[2]]},
                                {{0, 1, 2}});
    found += kept.count(*test::faces_by_position(one).begin());
  }
  CHECK(expected > 0);
  CHECK(found == expected);
  CHECK(r.report.faces_kept == expected);
}

TEST_CASE("regularize: three boxes with a triple overlap and edges through face diagonals") {
  const Box a{{{0, 0, 0}, {2, 2, 2}}}, b{{{1, 0.5, 0.25}, {3, 2.5, 2.75}}}, c{{{0.5, 1.25, -0.5}, {2.5, 3.25, 1.5}}};
  const Soup in = test::concat(test::concat(box(a), box(b)), box(c));
  const RegularizeResult r = regularize(in);
  const Soup out = written(r, "regularize_three_boxes.off");
  const Report rep = inspect(out);
  CHECK(rep.certified_clean());
  const double expected = volume(a) + volume(b) + volume(c) - volume(meet(a, b)) - volume(meet(a, c)) -
                          volume(meet(b, c)) + volume(meet(meet(a, b), c));
  CHECK(rep.signed_volume == Approx(expected).epsilon(1e-12));
  CHECK(off_surface(in, out) < 1e-12);
}

TEST_CASE("regularize: two tetrahedra whose every face crosses the other are seeded by lines of their own") {
  // A stella octangula, the second tetrahedron moved a little off the
  // first's mirror image (no edge through an edge): every one of the 8
  // triangles crosses the other solid, so no intersection-free triangle can
  // seed the growth and all 8 are classified from seeds among their
  // sub-triangles (split_unreached counts them).
  auto tetrahedron = [](const std::array<Point3d, 4>& p) {  // facing outwards
    Soup s;
    s.points.assign(p.begin(), p.end());
    s.add_triangle(0, 1, 2);
    s.add_triangle(0, 3, 1);
    s.add_triangle(0, 2, 3);
    s.add_triangle(1, 3, 2);
    if (inspect(s).signed_volume < 0)
      for (std::size_t f = 0; f < s.face_count(); ++f) std::swap(s.indices[s.offsets[f] + 1], s.indices[s.offsets[f] + 2]);
    return s;
  };
  const std::array<Point3d, 4> a{{{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}}};
  const std::array<Point3d, 4> b{{{-1.01, -0.98, -1.02}, {-0.97, 1.03, 0.99}, {1.02, -1.01, 0.98}, {0.99, 0.97, -1.03}}};
  const Soup in = test::concat(tetrahedron(a), tetrahedron(b));
  const Report before = inspect(in);
  REQUIRE(before.closed);
  REQUIRE(before.oriented);
  std::set<std::size_t> crossing;
  for (const FacePair& p : before.self_intersections) crossing.insert({p.first, p.second});
  REQUIRE(crossing.size() == 8);  // every triangle crosses the other solid
  const RegularizeResult r = regularize(in);
  const Soup out = written(r, "regularize_stella.off");
  const Report rep = inspect(out);
  CHECK(rep.certified_clean());
  CHECK(rep.components == 1);
  // the union: more than either solid (each 8/3), less than both
  CHECK(rep.signed_volume > 2.7);
  CHECK(rep.signed_volume < before.signed_volume);
  CHECK(r.report.triangles_split == 8);
  CHECK(r.report.split_unreached == 8);
  CHECK(r.report.seeds >= 1);
  CHECK(r.report.unclassified == 0);
  CHECK(r.report.orientation_conflicts == 0);
  CHECK(r.report.components_removed == 0);
  CHECK(off_surface(in, out) < 1e-12);
}

TEST_CASE("regularize: a solid inside another is removed (and counted), a cavity is kept") {
  const Box big{{{0, 0, 0}, {4, 4, 4}}}, small{{{1, 1.5, 1.25}, {2, 2.5, 2.25}}};
  SECTION("enclosed solid") {
    const RegularizeResult r = regularize(test::concat(box(big), box(small)));
    const Report rep = inspect(written(r, "regularize_enclosed.off"));
    CHECK(rep.certified_clean());
    CHECK(rep.components == 1);
    CHECK(rep.signed_volume == Approx(64).epsilon(1e-12));
    CHECK(r.report.components_removed == 1);
  }
  SECTION("cavity") {
    const RegularizeResult r = regularize(test::concat(box(big), box(small, true)));
    const Report rep = inspect(written(r, "regularize_cavity.off"));
    CHECK(rep.certified_clean());
    CHECK(rep.components == 2);
    CHECK(rep.signed_volume == Approx(63).epsilon(1e-12));
    CHECK(r.report.components_removed == 0);
  }
  SECTION("a cavity crossing the outer wall opens a notch") {
    const Box notch{{{3, 1.5, 1.25}, {5, 2.5, 2.25}}};
    const RegularizeResult r = regularize(test::concat(box(big), box(notch, true)));
    const Report rep = inspect(written(r, "regularize_notch.off"));
    // winding number: 1 in the big box, 0 where the inward box overlaps it,
    // -1 outside the big box inside the inward one: only the notch is cut
    CHECK(rep.certified_clean());
    CHECK(rep.signed_volume == Approx(64 - volume(meet(big, notch))).epsilon(1e-12));
  }
}

TEST_CASE("regularize: a component crossing nothing is classified from whichever of its faces comes first") {
  // The component's winding number is cast from its first face (a half line
  // from that face's far side outwards, along its normal's dominant axis):
  // rotating the box's face list makes every side come first, so lines go
  // up and down each axis. The big box crosses another (the growth has work
  // of its own); the small one lies inside it (solid: removed; cavity: kept)
  // or outside both (kept).
  const Box big{{{0, 0, 0}, {4, 4, 4}}}, other{{{3, 1, 1}, {6, 3, 3}}};
  const Box inner{{{1, 1.5, 1.25}, {2, 2.5, 2.25}}}, outer{{{8, 1, 1}, {9, 2, 2}}};
  const double united = volume(big) + volume(other) - volume(meet(big, other));
  auto rotated = [](const Soup& s, std::size_t r) {
    Soup out;
    out.points = s.points;
    for (std::size_t n = 0; n < s.face_count(); ++n) {
      const FaceView v = s.face((n + r) % s.face_count());
      out.add_triangle(v[0], v[1], v[2]);
    }
    return out;
  };
  struct Case {
    const char* name;
    Box b;
    bool inward;
    double volume;       // of the union's output
    std::size_t removed; // components
  };
  for (const Case& c : {Case{"enclosed solid", inner, false, united, 1}, Case{"cavity", inner, true, united - 1, 0},
                        Case{"outside", outer, false, united + 1, 0}}) {
    const Soup small = box(c.b, c.inward);
    for (std::size_t r = 0; r < small.face_count(); ++r) {
      INFO(c.name << ", the box's face list rotated by " << r);
      const RegularizeResult res = regularize(test::concat(test::concat(box(big), box(other)), rotated(small, r)));
      const Report rep = inspect(written(res, "regularize_first_face.off"));
      CHECK(rep.certified_clean());
      CHECK(rep.signed_volume == Approx(c.volume).epsilon(1e-12));
      CHECK(res.report.components_removed == c.removed);
    }
  }
}

TEST_CASE("regularize: a clean mesh comes back face for face, bit for bit") {
  const Soup in = read_soup(test::fixture("torus.off"));
  const RegularizeResult r = regularize(in);
  CHECK(r.report.intersecting_pairs_in == 0);
  CHECK(r.report.triangles_split == 0);
  CHECK(test::faces_by_position(written(r, "regularize_clean.off")) == test::faces_by_position(in));
}

TEST_CASE("regularize: self-overlapping and overlapping closed meshes come out certified and TetGen meshes them") {
  for (const char* name : {"knot_tube_r1.2.off", "spheres_intersecting.off", "bones.off"}) {
    INFO(name);
    const Soup in = read_soup(test::fixture(name));
    REQUIRE(inspect(in).self_intersections.size() > 0);
    REQUIRE_FALSE(test::tetgen_meshes(test::fixture(name), std::string("regularize_in_") + name));
    const RegularizeResult r = regularize(in);
    std::string path;
    const Soup out = written(r, std::string("regularize_") + name, &path);
    const Report rep = inspect(out);
    CHECK(rep.certified_clean());
    CHECK(off_surface(in, out) < 1e-9 * r.report.bbox_diagonal);
    // the union encloses at least what the largest input component does and
    // at most what they all do
    CHECK(rep.signed_volume <= inspect(in).signed_volume + 1e-9);
    CHECK(r.report.partially_valid > 0);
    CHECK(test::tetgen_meshes(path, std::string("regularize_out_") + name));
  }
}

TEST_CASE("regularize: the output does not depend on the number of threads") {
  // Triangulations run on other threads while planning goes on, each once
  // what it reads is final; on one thread all of them run after planning.
  for (const char* name : {"knot_tube_r1.2.off", "bones.off"}) {
    INFO(name);
    const Soup in = read_soup(test::fixture(name));
    const RegularizeResult parallel = regularize(in);
    RegularizeResult serial;
    {
      tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
      serial = regularize(in);
    }
    REQUIRE(parallel.report.triangles_split > 0);
    CHECK(parallel.soup.points == serial.soup.points);
    CHECK(parallel.soup.indices == serial.soup.indices);
    CHECK(parallel.source_face == serial.source_face);
  }
}

TEST_CASE("regularize: coplanar overlaps, duplicate solids and touching faces (coincident sheets)") {
  SECTION("boxes sharing their top and bottom planes") {
    const Box a{{{0, 0, 0}, {2, 2, 2}}}, b{{{1, 0.5, 0}, {3, 2.5, 2}}};
    const Soup in = test::concat(box(a), box(b));
    const RegularizeResult r = regularize(in);
    const Report rep = inspect(written(r, "regularize_coplanar.off"));
    CHECK(rep.certified_clean());
    CHECK(rep.signed_volume == Approx(volume(a) + volume(b) - volume(meet(a, b))).epsilon(1e-12));
  }
  SECTION("a box given twice") {
    const Box a{{{0, 0, 0}, {1, 2, 3}}};
    const RegularizeResult r = regularize(test::concat(box(a), box(a)));
    const Report rep = inspect(written(r, "regularize_twice.off"));
    CHECK(rep.certified_clean());
    CHECK(rep.signed_volume == Approx(6).epsilon(1e-12));
    CHECK(r.report.faces_out == 12);
  }
  SECTION("boxes touching face to face: the shared wall goes") {
    const Box a{{{0, 0, 0}, {1, 1, 1}}}, b{{{1, 0.25, 0.5}, {2, 0.75, 1.5}}};
    const RegularizeResult r = regularize(test::concat(box(a), box(b)));
    const Report rep = inspect(written(r, "regularize_touching.off"));
    CHECK(rep.certified_clean());
    CHECK(rep.components == 1);
    CHECK(rep.signed_volume == Approx(volume(a) + volume(b)).epsilon(1e-12));
  }
}

TEST_CASE("regularize: where the union's boundary pinches, each cone gets its own vertex, moved into it") {
  // two boxes touching at one corner (welded: one vertex of both)
  const Soup in = test::concat(box({{{0, 0, 0}, {1, 1, 1}}}), box({{{1, 1, 1}, {2, 3, 2}}}));
  REQUIRE_FALSE(inspect(in).manifold);
  const RegularizeResult r = regularize(in);
  const Report rep = inspect(written(r, "regularize_pinch.off"));
  CHECK(rep.certified_clean());
  CHECK(rep.components == 2);
  CHECK(r.report.pinches_split == 1);
  CHECK(r.report.pinch_displacement > 0);
  CHECK(r.report.pinch_displacement <= 0.01 + 1e-12);  // 1% of the shortest edge at the corner
  CHECK(r.report.max_distance_to_input <= r.report.pinch_displacement + 1e-12);
  // 1 + 2, less what the moved corners cut off (faces of area <= 2 at the
  // corner, moved by <= 0.01)
  CHECK(rep.signed_volume < 3);
  CHECK(rep.signed_volume > 3 - 3 * 2 * 0.01);
}

TEST_CASE("regularize: where the union's boundary touches itself along an edge, the sheets come apart") {
  // two boxes sharing one edge (welded: a non-manifold edge with four faces)
  const Soup in = test::concat(box({{{0, 0, 0}, {1, 1, 1}}}), box({{{1, 1, 0}, {2, 3, 1}}}));
  REQUIRE(inspect(in).nonmanifold_edges.size() == 1);
  const RegularizeResult r = regularize(in);
  const Report rep = inspect(written(r, "regularize_touching_edge.off"));
  CHECK(rep.certified_clean());
  CHECK(rep.components == 2);
  CHECK(r.report.pinches_split == 2);  // the edge's two ends, each split per sheet
  CHECK(rep.signed_volume < 3);
  CHECK(rep.signed_volume > 3 - 2 * 2 * 2 * 0.01);
}

TEST_CASE("regularize: where the sheets along an edge are joined at both its ends, its midpoint parts them") {
  // The cycloidal gear set (corpus): parts flush at their tops, walls
  // touching face to face. 10% of its faces split at a centroid lifted by
  // 1e-9 of their size: where a lifted wall meets a part's top edge, the
  // union's boundary touches itself along that edge through a cavity 1e-9
  // thick, and the sheets there are joined through the cavity's other edges
  // at both ends of it: no copy of an end parts them (63 such edges were
  // left, uncertified).
  const Soup gears = read_soup(test::fixture("corpus/trimesh__cycloidal.ply"));
  const Soup in = test::perturbed(gears, PerturbKind::near_coplanar, 7);
  const RegularizeResult r = regularize(in);
  const Report rep = inspect(written(r, "regularize_gears_lifted.off"));
  CHECK(rep.certified_clean());
  CHECK(r.report.pinched_edges_split > 0);
  CHECK(r.report.pinched_edges_split <= r.report.pinches_split);
  // the midpoints move into their cones by 1% of their shortest edge at most
  CHECK(r.report.max_distance_to_input <= r.report.pinch_displacement + 1e-12);
  CHECK(std::abs(rep.signed_volume - inspect(regularize(gears).soup).signed_volume) < 1e-3);
}

TEST_CASE("regularize: quad faces are fanned, and the output names the quad each face came from") {
  auto quad_box = [](const Box& b) {
    const auto& [lo, hi] = b;
    Soup s;
    s.points = {{lo[0], lo[1], lo[2]}, {hi[0], lo[1], lo[2]}, {hi[0], hi[1], lo[2]}, {lo[0], hi[1], lo[2]},
                {lo[0], lo[1], hi[2]}, {hi[0], lo[1], hi[2]}, {hi[0], hi[1], hi[2]}, {lo[0], hi[1], hi[2]}};
    for (const std::array<Index, 4>& q : std::vector<std::array<Index, 4>>{
             {0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}})
      s.add_face(q.begin(), q.end());
    return s;
  };
  const Box a{{{0, 0, 0}, {2, 2, 2}}}, b{{{1, 0.5, 0.25}, {3, 2.5, 2.75}}};
  const Soup in = test::concat(quad_box(a), quad_box(b));
  const RegularizeResult r = regularize(in);
  CHECK(r.report.polygons_fanned == 12);
  const Report rep = inspect(written(r, "regularize_quads.off"));
  CHECK(rep.certified_clean());
  CHECK(rep.signed_volume == Approx(volume(a) + volume(b) - volume(meet(a, b))).epsilon(1e-12));
  for (std::size_t s : r.source_face) CHECK(s < in.face_count());
  CHECK(r.report.max_distance_to_input < 1e-12);
}

TEST_CASE("regularize: faces with a repeated corner index are left out (they bound nothing)") {
  // as trimesh's capsule has at its poles: (a, a, b) uses a -> b and b -> a
  // once each, and the "edge" a -> a is no edge (it was refused as one)
  Soup in = box({{{0, 0, 0}, {1, 1, 1}}});
  in.add_triangle(0, 0, 1);
  in.add_triangle(6, 2, 6);
  const RegularizeResult r = regularize(in);
  CHECK(r.report.zero_area_faces == 2);
  const Soup out = written(r, "regularize_repeated_index.off");
  CHECK(inspect(out).certified_clean());
  CHECK(test::faces_by_position(out) == test::faces_by_position(box({{{0, 0, 0}, {1, 1, 1}}})));
}

TEST_CASE("regularize: a zero-area face closing a T-junction is left out, and the T-junction split (§3.1)") {
  // a box whose top is split by an exactly collinear face at a T-junction
  Soup in = box({{{0, 0, 0}, {1, 1, 1}}});
  in.points.push_back({0.5, 0, 1});  // on the edge from corner 4 to corner 5
  in.indices[3 * 2 + 0] = 8;         // face {4, 5, 6} becomes {8, 5, 6} ...
  in.add_triangle(4, 8, 6);          // ... plus {4, 8, 6}
  in.add_triangle(4, 5, 8);          // and the zero-area {4, 5, 8} closing the T-junction
  REQUIRE(inspect(in).degenerate_faces.size() == 1);
  REQUIRE_FALSE(inspect(in).certified_clean());
  const RegularizeResult r = regularize(in);
  CHECK(r.report.zero_area_faces == 1);
  const Report rep = inspect(written(r, "regularize_tjunction.off"));
  CHECK(rep.certified_clean());
  CHECK(rep.signed_volume == Approx(1).epsilon(1e-12));
  CHECK(r.report.max_distance_to_input == 0);
}

namespace {

/// `s` without the faces whose corners all lie in the plane x = `x`.
Soup without_faces_at(const Soup& s, double x) {
  Soup out;
  out.points = s.points;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const FaceView v = s.face(f);
    if (s.points[v[0]][0] == x && s.points[v[1]][0] == x && s.points[v[2]][0] == x) continue;
    out.add_triangle(v[0], v[1], v[2]);
  }
  return out;
}

/// The faces of `s` in the plane x = `x`, turned over when `flip`.
Soup faces_at(const Soup& s, double x, bool flip) {
  Soup out;
  out.points = s.points;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const FaceView v = s.face(f);
    if (s.points[v[0]][0] == x && s.points[v[1]][0] == x && s.points[v[2]][0] == x)
      flip ? out.add_triangle(v[0], v[2], v[1]) : out.add_triangle(v[0], v[1], v[2]);
  }
  return out;
}

bool any_face_at(const Soup& s, double x) { return faces_at(s, x, false).face_count() > 0; }

}  // namespace

TEST_CASE("regularize: walls and faces doubled in one direction are left out first (convex pieces glued)") {
  // Two unit boxes side by side, glued along x = 1 the way a convex
  // decomposition's pieces are: neither surface balances on its own rim there.
  const Box a{{{0, 0, 0}, {1, 1, 1}}}, b{{{1, 0, 0}, {2, 1, 1}}};
  const Soup sides = test::concat(without_faces_at(box(a), 1), without_faces_at(box(b), 1));
  SECTION("one cap left between them: a one-sided wall") {
    const Soup in = test::concat(sides, faces_at(box(a), 1, false));
    const RegularizeResult r = regularize(in);
    CHECK(r.report.walls_left_out == 2);
    const Soup out = written(r, "regularize_wall.off");
    const Report rep = inspect(out);
    CHECK(rep.certified_clean());
    CHECK(rep.components == 1);
    CHECK(rep.signed_volume == Approx(2).epsilon(1e-12));
    CHECK_FALSE(any_face_at(out, 1));
    CHECK(r.report.faces_kept == 20);
  }
  SECTION("both caps, turned the same way: the shared face given twice in one direction") {
    const Soup in = test::concat(test::concat(sides, faces_at(box(a), 1, false)), faces_at(box(b), 1, true));
    const RegularizeResult r = regularize(in);
    CHECK(r.report.walls_left_out == 4);
    const Soup out = written(r, "regularize_doubled_cap.off");
    const Report rep = inspect(out);
    CHECK(rep.certified_clean());
    CHECK(rep.signed_volume == Approx(2).epsilon(1e-12));
    CHECK_FALSE(any_face_at(out, 1));
  }
  SECTION("a box set flush into another (sharing its face at x = 0, welded): the nested box's faces are the wall") {
    // Both the nested box's five exposed sides and the block's five around
    // them hang off the shared rim and balance it; only the first lies
    // inside what is kept. Either order of the two in the file.
    const Soup block = box({{{0, 0, 0}, {1, 1, 1}}}), part = without_faces_at(box({{{0, 0, 0}, {0.5, 1, 1}}}), 0);
    for (const Soup& in : {test::concat(block, part), test::concat(part, block)}) {
      const RegularizeResult r = regularize(in);
      CHECK(r.report.walls_left_out == 10);
      const Soup out = written(r, "regularize_flush_part.off");
      const Report rep = inspect(out);
      CHECK(rep.certified_clean());
      CHECK(rep.signed_volume == Approx(1).epsilon(1e-12));  // the block, not the part
      CHECK(r.report.faces_kept == 12);
    }
  }
  SECTION("the corpus case: V-HACD's deer_bound (one wall, one doubled face), and TetGen meshes the output") {
    const Soup in = read_soup(test::fixture("deer_bound.off"));
    REQUIRE_FALSE(test::tetgen_meshes(test::fixture("deer_bound.off"), "regularize_in_deer_bound.off"));
    const RegularizeResult r = regularize(in);
    CHECK(r.report.walls_left_out == 6);
    std::string path;
    const Soup out = written(r, "regularize_deer_bound.off", &path);
    CHECK(inspect(out).certified_clean());
    CHECK(off_surface(in, out) < 1e-9 * r.report.bbox_diagonal);
    CHECK(r.report.faces_kept > in.face_count() * 9 / 10);
    CHECK(test::tetgen_meshes(path, "regularize_out_deer_bound.off"));
  }
}

TEST_CASE("regularize: a surface facing inwards encloses nothing") {
  const RegularizeResult r = regularize(box({{{0, 0, 0}, {1, 1, 1}}}, true));
  CHECK(r.soup.face_count() == 0);
  CHECK(r.report.components_removed == 1);
  CHECK_FALSE(r.report.certified);
}

TEST_CASE("regularize: refuses what it does not handle, naming the problem") {
  SECTION("open mesh") {
    Soup open = box({{{0, 0, 0}, {1, 1, 1}}});
    open.indices.resize(open.indices.size() - 3);
    open.offsets.pop_back();
    CHECK_THROWS_WITH(regularize(open), Catch::Contains("not closed"));
  }
  SECTION("a face turned the wrong way is not a wall") {
    Soup turned = box({{{0, 0, 0}, {1, 1, 1}}});
    std::swap(turned.indices[1], turned.indices[2]);
    CHECK_THROWS_WITH(regularize(turned), Catch::Contains("not closed"));
  }
  SECTION("a fin on a closed box (two edges with one use) is not a wall") {
    Soup fin = box({{{0, 0, 0}, {1, 1, 1}}});
    fin.points.push_back({0.5, -1, 0.5});
    fin.add_triangle(0, 1, Index(fin.points.size() - 1));
    CHECK_THROWS_WITH(regularize(fin), Catch::Contains("not closed"));
  }
}

TEST_CASE("regularize for STL: the union rounded to floats is certified as the file holds it") {
  // self_intersectA as a binary STL of it reads: the union's points on its
  // intersection curves, rounded to floats, make faces intersect (12 pairs).
  const std::string stl = test::scratch("reg_float_in.stl");
  WriteOptions w;
  w.allow_overwrite = true;
  write_soup(read_soup(test::fixture("corpus/manifold__self_intersectA.obj")), stl, w);
  const Soup in = read_soup(stl);
  auto written_stl = [&](const RegularizeResult& r, const std::string& name) {
    const std::string p = test::scratch(name);
    write_soup(r.soup, p, w);
    return inspect(read_soup(p));
  };
  RegularizeOptions doubles;
  const RegularizeResult d = regularize(in, doubles);
  REQUIRE(d.report.certified);
  REQUIRE_FALSE(written_stl(d, "reg_float_d.stl").certified_clean());  // at stake
  RegularizeOptions floats;
  floats.float_coordinates = true;
  const RegularizeResult f = regularize(in, floats);
  CHECK(f.report.float_pairs > 0);
  for (const Point3d& p : f.soup.points)
    for (double c : p) CHECK(nearest_float(c) == c);
  CHECK(f.report.certified);
  CHECK(written_stl(f, "reg_float_f.stl").certified_clean());
  CHECK(off_surface(in, f.soup) < 1e-5 * d.report.bbox_diagonal);  // still on the input, up to the moves
}


TEST_CASE("regularize: the certificate searches only written faces no earlier whole search covered, and finds "
          "what a changed file has") {
  // The knot tube's output faces mostly have a corner on an intersection
  // curve: the rounding check searches the whole rounded surface and keeps
  // it for the certificate. The drum's are mostly its input's own faces:
  // the rounding check searches only the others, and the input (searched
  // whole to begin with) is the certificate's base.
  for (const auto& [name, base_is_input] : {std::pair{"knot_tube_r1.2.off", false}, std::pair{"drum.off", true}}) {
    INFO(name);
    const Soup in = read_soup(test::fixture(name));
    RegularizeOptions o;
    o.certify = false;
    const RegularizeResult r = regularize(in, o);
    REQUIRE(r.scanned);
    CHECK((r.scanned->soup.face_count() == in.face_count()) == base_is_input);
    CHECK(r.scanned->pairs == inspect(r.scanned->soup).self_intersections);  // all its pairs, exactly
    const Soup out = written(r, std::string("regularize_scanned_") + name);
    REQUIRE(out.face_count() > 1000);
    RegularizeReport rep = r.report;
    certify(in, out, r.source_face, rep, r.scanned);
    CHECK(rep.certified);
    CHECK(rep.certificate_searched < out.face_count() / 2);
    CHECK(rep.out.self_intersections == inspect(out).self_intersections);

    // The file changed after the check (a face re-cornered through the
    // solid, a vertex moved): the certificate finds the pairs the whole
    // search finds.
    Soup changed = out;
    Index far = 0;
    for (Index v = 0; v < changed.points.size(); ++v)
      if (squared_norm(sub(changed.points[v], changed.points[0])) >
          squared_norm(sub(changed.points[far], changed.points[0])))
        far = v;
    changed.indices[2] = far;
    changed.points[changed.indices[40]] = mul(add(changed.points[changed.indices[40]], changed.points[far]), 0.5);
    const Report full = inspect(changed);
    REQUIRE(full.self_intersections.size() > 0);
    RegularizeReport again = r.report;
    certify(in, changed, r.source_face, again, r.scanned);
    CHECK_FALSE(again.certified);
    CHECK(again.certificate_searched > 0);
    CHECK(again.out.self_intersections == full.self_intersections);
  }
}
