// polyheal degenerate (Botsch & Kobbelt): every case ends with no zero-area
// face, cap or needle in the rounded output, the input's topology, no new
// self-intersection, and the surface within the tolerance of the input —
// each checked here independently of the pipeline's own report.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <tuple>
#include <vector>

#include "polyheal/inspect/report.h"
#include "polyheal/io/read.h"
#include "polyheal/io/write.h"
#include "polyheal/mesh/errors.h"
#include "polyheal/mesh/mesh.h"
#include "polyheal/repair/degenerate.h"
#include "polyheal/repair/deintersect.h"
#include "polyheal/inspect/exact_predicates.h"
#include "polyheal/inspect/local_index.h"
#include "polyheal/mesh/convert.h"
#include "polyheal/repair/detail/distance.h"
#include "polyheal/repair/detail/shape_decimation.h"
#include "support/builders.h"

using namespace polyheal;

namespace {

/// V - E + F of a triangle soup, identical points counted once (as a
/// reader welds them), counting points that faces use.
long euler_characteristic(const Soup& s) {
  std::map<Point3d, Index> id;
  for (const Point3d& p : s.points) id.emplace(p, static_cast<Index>(id.size()));
  auto at = [&](Index i) { return id.at(s.points[i]); };
  std::set<std::pair<Index, Index>> edges;
  std::set<Index> used;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const FaceView face = s.face(f);
    for (std::size_t k = 0; k < face.size(); ++k) {
      const Index a = at(face[k]), b = at(face[(k + 1) % face.size()]);
      edges.insert({std::min(a, b), std::max(a, b)});
      used.insert(a);
    }
  }
  return long(used.size()) - long(edges.size()) + long(s.face_count());
}

/// The acceptance properties, on `output` (as it would be written).
void check_repaired(const Soup& input, const Soup& output, const DegenerateReport& r) {
  const Report in = inspect(input), out = inspect(output);
  INFO("faces " << input.face_count() << " -> " << output.face_count());
  // no zero-area face, cap or needle, decided exactly on the doubles
  CHECK(out.degenerate_faces.empty());
  CHECK(out.caps.empty());
  CHECK(out.needles.empty());
  // topology as the input's
  // as the input once repeated-index faces are gone; pinch vertices stay
  CHECK((out.manifold && out.oriented) == r.topology_in.manifold);
  CHECK(out.nonmanifold_vertices.size() <= in.nonmanifold_vertices.size());
  CHECK(out.nonmanifold_edges.empty());
  CHECK(out.oriented);
  CHECK(out.closed == in.closed);
  CHECK(out.components == in.components);
  CHECK(out.boundary_loops == in.boundary_loops);
  CHECK(euler_characteristic(output) == r.topology_in.euler);
  // no self-intersection the input did not have
  CHECK(out.self_intersections.size() <= in.self_intersections.size());
  if (in.self_intersections.empty()) CHECK(out.self_intersections.empty());
  // within the tolerance: the report's bounded Hausdorff distance, and an
  // independent spot check — every vertex of each lies near the other
  CHECK(r.hausdorff >= 0);
  CHECK(r.hausdorff + r.hausdorff_error_bound <= r.tolerance);
  const detail::SurfaceDistance to_input(input), to_output(output);
  for (const Point3d& p : output.points) CHECK(std::sqrt(to_input.squared_distance(p)) <= r.tolerance);
  for (const Point3d& p : input.points) CHECK(std::sqrt(to_output.squared_distance(p)) <= r.tolerance);
  CHECK(r.certified);
}

DegenerateResult run(const Soup& input, DegenerateOptions o = {}) {
  DegenerateResult result = remove_degenerate_faces(input, o);
  INFO("before: " << result.report.before.zero_area << " zero-area, " << result.report.before.caps << " caps, "
                  << result.report.before.needles << " needles");
  check_repaired(input, result.soup, result.report);
  return result;
}

/// Fig. 4 (A above BC, D below it, both almost on BC: two caps sharing their
/// long edge) inside a flat square, so the configuration is interior.
Soup fig4_in_a_square() {
  return test::soup({{0, 0, 0}, {10, 0, 0}, {4, 0.05, 0}, {7, -0.05, 0},  // B C A D
                     {-5, -5, 0}, {15, -5, 0}, {15, 5, 0}, {-5, 5, 0}},    // the square
                    {{0, 1, 2}, {0, 3, 1},                                // the two caps
                     {4, 5, 3}, {4, 3, 0}, {5, 6, 1}, {5, 1, 3}, {6, 7, 2}, {6, 2, 1}, {7, 4, 0}, {7, 0, 2}});
}

}  // namespace

TEST_CASE("degenerate: Fig. 4, two caps sharing their long edge, in an open flat mesh", "[repair][paper]") {
  const Soup input = fig4_in_a_square();
  const DegenerateResult r = run(input);
  CHECK(r.report.before.caps == 2);
  CHECK(inspect(input).boundary_loops == 1);  // an open mesh
}

TEST_CASE("degenerate: Fig. 1 fan cylinder, with and without --slice-grid", "[repair][paper]") {
  const Soup input = read_soup(test::fixture("cad_cylinder.off"));
  const DegenerateResult plain = run(input);
  CHECK(plain.report.before.caps == 4);
  CHECK(plain.report.before.needles == 376);
  DegenerateOptions grid;
  grid.slice_grid = 4;
  const DegenerateResult gridded = run(input, grid);
  CHECK(gridded.report.grid_slices + gridded.report.grid_slices_refused == 12);
  CHECK(gridded.report.grid_slices > 0);
  WARN("cad_cylinder: " << input.face_count() << " faces -> " << plain.soup.face_count() << " (peak "
                        << plain.report.peak_faces << "); with --slice-grid 4: " << gridded.soup.face_count()
                        << " (peak " << gridded.report.peak_faces << ")");
}

TEST_CASE("degenerate: a T-junction closed by an exactly collinear face", "[repair]") {
  // A tetrahedron whose bottom face was split at M, the midpoint of P0P1,
  // on one side only; the zero-area face (P1, P0, M) closes the crack.
  const Soup input = test::soup({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0, 2}, {1, 0, 0}},
                                {{2, 1, 4}, {2, 4, 0}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {1, 0, 4}});
  REQUIRE(inspect(input).degenerate_faces.size() == 1);
  REQUIRE(inspect(input).closed);
  const DegenerateResult r = run(input);
  CHECK(r.report.before.zero_area == 1);
  CHECK(r.report.collapses + r.report.flips >= 1);
  CHECK(inspect(r.soup).certified_clean());  // the crack is gone, nothing else changed
}

TEST_CASE("degenerate: a pinch vertex is split per fan, repaired around, and welded again", "[repair]") {
  // The T-junction tetrahedron and a small tetrahedron whose corner is its
  // apex (0,0,2): after welding, that vertex has two fans (non-manifold).
  const Soup tj = test::soup({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0, 2}, {1, 0, 0}},
                             {{2, 1, 4}, {2, 4, 0}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {1, 0, 4}});
  const Soup input = test::concat(tj, test::tetrahedron(0, 0, 2));
  REQUIRE(inspect(input).nonmanifold_vertices.size() == 1);
  REQUIRE(inspect(input).degenerate_faces.size() == 1);
  const DegenerateResult r = run(input);
  CHECK(r.report.pinched_vertices_split == 1);
  const Report out = inspect(r.soup);
  CHECK(out.nonmanifold_vertices.size() == 1);  // the pinch is still one point
  CHECK(out.components == 2);
  CHECK(out.self_intersections.empty());
}

TEST_CASE("degenerate: faces with a repeated vertex index are removed topologically", "[repair]") {
  Soup input = test::tetrahedron();
  input.add_triangle(0, 0, 1);
  input.add_triangle(2, 3, 3);
  const DegenerateResult r = run(input);
  CHECK(r.report.repeated_index_faces == 2);
  CHECK(r.soup.face_count() == 4);
  CHECK(inspect(r.soup).certified_clean());
}

TEST_CASE("degenerate: a clean mesh comes out unchanged", "[repair]") {
  const Soup input = read_soup(test::fixture("torus.off"));
  REQUIRE(inspect(input).caps.empty());
  REQUIRE(inspect(input).needles.empty());
  const DegenerateResult r = run(input);
  CHECK(r.soup.face_count() == input.face_count());
  CHECK(r.report.hausdorff == 0.0);
  CHECK(r.report.collapses + r.report.flips + r.report.cap_slices + r.report.needle_slices == 0);
}

TEST_CASE("degenerate: a non-manifold soup is refused", "[repair]") {
  Soup input = test::tetrahedron();
  input.add_triangle(0, 1, 2);  // a third face on edges of the tetrahedron
  input.points.push_back({5, 5, 5});
  input.add_triangle(0, 1, 4);
  CHECK_THROWS_AS(remove_degenerate_faces(input), UnsupportedInput);
}

namespace {

/// A fixture repaired, written, read back, and certified as it is on disk.
DegenerateResult repair_fixture_as_written(const char* name) {
  INFO(name);
  const Soup input = read_soup(test::fixture(name));
  const DegenerateResult r = run(input);
  CHECK(r.report.before.caps > 0);
  CHECK(r.report.before.needles > 0);
  std::string flat = name;
  std::replace(flat.begin(), flat.end(), '/', '_');
  const std::string path = test::scratch("degenerate_" + flat + ".off");
  write_soup(r.soup, path, WriteOptions{false, true});
  const Soup written = read_soup(path);
  DegenerateReport again = r.report;
  certify(input, written, again);
  check_repaired(input, written, again);
  // no face folded onto a neighbour below TetGen's 0.1 degrees: with split
  // points rounded early a fold no longer overlaps exactly (the fold guard)
  CHECK(inspect(written).sharp_folds.empty());
  WARN(name << ": " << input.face_count() << " faces, " << r.report.before.caps << " caps, "
            << r.report.before.needles << " needles -> " << written.face_count() << " faces (peak "
            << r.report.peak_faces << "), " << r.report.wedge_cuts << " cuts across " << r.report.wedge_tips
            << " wedge tips, Hausdorff " << r.report.hausdorff << " (tolerance " << r.report.tolerance << ")");
  return r;
}

}  // namespace

TEST_CASE("degenerate: CAD tessellations from the corpus, certified on the file as written", "[repair][corpus]") {
  // b9_mesh has one intersecting pair, which decimation removes; the needles
  // beside it need slices once it is gone (no slice cuts a face while it
  // intersects).
  for (const char* name : {"anchor.off", "thingi10k_65004.stl", "corpus/cgal__b9_mesh.off"})
    repair_fixture_as_written(name);
}

// A knife's blade: a prism over a triangle with a 3-degree tip, 1 thick. The
// top and bottom faces are each one needle whose short edge (0.52 across)
// is 50 times the tolerance: no collapse of it stays within the tolerance,
// the tip's corner lies between creases (nothing may move it), and halving
// cuts leave a band whose triangle has the tip's angle again. A series of
// cuts across it at distances from the tip falling geometrically removes it.
TEST_CASE("degenerate: a sharp corner between creases goes by a series of cuts (a blade)", "[repair][degenerate]") {
  const double half = 10 * std::tan(1.5 * M_PI / 180);  // 3 degrees at the tip
  const Soup input = test::soup({{0, 0, 0}, {10, half, 0}, {10, -half, 0}, {0, 0, -1}, {10, half, -1}, {10, -half, -1}},
                                {{0, 2, 1}, {3, 4, 5},                // top (up), bottom (down)
                                 {0, 1, 4}, {0, 4, 3},                // side through the tip and B
                                 {0, 3, 5}, {0, 5, 2},                // side through the tip and C
                                 {1, 2, 5}, {1, 5, 4}});              // the blunt end
  const DegenerateResult r = run(input);
  CHECK(r.report.before.needles >= 2);
  WARN("blade: " << input.face_count() << " faces -> " << r.soup.face_count() << " (" << r.report.wedge_cuts
                 << " cuts across " << r.report.wedge_tips << " wedge tips)");
  CHECK(r.report.wedge_tips >= 1);
}

// trimesh's fixed_top (a CAD export, dense needle fans) has a flat face with
// a corner of about 4 degrees between creases; it ended with that one needle
// before cut_wedge() (since stagger_strips() its path no longer reaches it).
TEST_CASE("degenerate: a CAD export with dense needle fans and a sharp corner (fixed_top)", "[repair][corpus]") {
  repair_fixture_as_written("corpus/trimesh__fixed_top.ply");
}
// ADIS16480 (7.4k faces, 3640 needles in dense CAD fans) ended with one such
// wedge tip too; since the decimator's choices no longer depend on which
// exact tests ran before (approx_point3d), its path reaches no stuck tip.
// Certified on the file as written either way.
TEST_CASE("degenerate: dense CAD needle fans are certified on the file as written (ADIS16480)", "[repair][corpus]") {
  repair_fixture_as_written("corpus/trimesh__ADIS16480.STL");
}

TEST_CASE("degenerate: collapses never join two pinch copies' edges (the file's topology stays)",
          "[repair][degenerate]") {
  // trimesh's angle_block (CAD STL, 33 pinch points), freed of its
  // intersections first. Collapsing a vertex into one copy of a pinch point
  // could give it an edge that another copy already had to a copy of the
  // same neighbour: one edge in the welded file, two fans merged, Euler
  // -37 -> -30 and a fifth boundary loop before the check in
  // shape_decimation.
  const Soup raw = read_soup(test::fixture("angle_block.stl"));
  // (Welded, its cracks and pinch points would close: identical points only.)
  const Soup in = remove_self_intersections(raw).soup;
  const SurfaceTopology before = topology_of(inspect(in));
  DegenerateOptions identical_only;
  identical_only.weld = 0;
  const DegenerateResult result = remove_degenerate_faces(in, identical_only);
  CHECK(result.report.pinched_vertices_split > 0);
  const std::string path = test::scratch("degenerate_angle_block.off");
  write_soup(result.soup, path);
  const Soup out = read_soup(path);
  CHECK(topology_of(inspect(out)) == before);
  CHECK(result.report.topology_out == result.report.topology_in);
}

TEST_CASE("degenerate: where the input self-intersects, nothing is cut and no pair is added", "[repair][degenerate]") {
  // trimesh's idler_riser as exported (CAD STL: 374 needles, 58 intersecting
  // pairs). No repair may touch an intersection, and slicing the faces that
  // intersect only multiplied the pairs (58 -> 1443) and left needles nothing
  // could remove (374 -> 967, faces 1572 -> 4763). Now every face that
  // intersects in the output is an input face, unchanged, and its partner
  // intersected it in the input; every bad face left is listed.
  // Its pairs are cracks between vertices 5e-16 apart, which the near weld
  // closes by default (next test); without it they are intersections like
  // any other.
  const Soup in = read_soup(test::fixture("corpus/trimesh__idler_riser.STL"));
  const Report before = inspect(in);
  REQUIRE_FALSE(before.self_intersections.empty());
  DegenerateOptions identical_only;
  identical_only.weld = 0;
  const DegenerateResult result = remove_degenerate_faces(in, identical_only);
  CHECK(result.report.near_vertices_welded == 0);
  const std::string path = test::scratch("degenerate_idler_riser.off");
  write_soup(result.soup, path);
  const Soup out = read_soup(path);
  const Report after = inspect(out);
  auto corners = [](const Soup& s, std::size_t f) {
    std::vector<Point3d> c;
    for (Index v : s.face(f)) c.push_back(s.points[v]);
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
    return c;
  };
  std::map<std::vector<Point3d>, std::size_t> input_face;
  for (std::size_t f = 0; f < in.face_count(); ++f) input_face.emplace(corners(in, f), f);
  std::set<std::pair<std::size_t, std::size_t>> pairs_in;
  for (const FacePair& p : before.self_intersections) pairs_in.insert({p.first, p.second});
  for (const FacePair& p : after.self_intersections) {
    const auto a = input_face.find(corners(out, p.first)), b = input_face.find(corners(out, p.second));
    REQUIRE(a != input_face.end());
    REQUIRE(b != input_face.end());
    CHECK(pairs_in.count({std::min(a->second, b->second), std::max(a->second, b->second)}) == 1);
  }
  CHECK(after.self_intersections.size() <= before.self_intersections.size());
  CHECK(topology_of(after) == topology_of(before));
  CHECK(out.face_count() <= in.face_count());
  const std::size_t bad_in = before.degenerate_faces.size() + before.caps.size() + before.needles.size();
  const std::size_t bad_out = after.degenerate_faces.size() + after.caps.size() + after.needles.size();
  CHECK(bad_out < bad_in / 2);
  CHECK(result.report.leftovers.size() == bad_out);
  CHECK(result.report.hausdorff + result.report.hausdorff_error_bound <= result.report.tolerance);
}

TEST_CASE("degenerate: a CAD STL's rounding cracks are welded first, and its needles then all go",
          "[repair][degenerate]") {
  // trimesh's CAD STLs as exported: vertices a few 1e-16 apart leave cracks
  // (boundary loops) whose two sides intersect exactly, so nothing could be
  // cut or collapsed there (idler_riser: 50 needles left, featuretype 863).
  // Welded within 1e-9 of the diagonal they are closed edges; every bad face
  // then goes, with the welded input's topology and within the tolerance of
  // the input as exported.
  for (const char* name : {"corpus/trimesh__idler_riser.STL", "angle_block.stl"}) {
    INFO(name);
    const Soup in = read_soup(test::fixture(name));
    const Report before = inspect(in);
    REQUIRE_FALSE(before.self_intersections.empty());
    REQUIRE(before.boundary_loops > 0);
    const DegenerateResult result = remove_degenerate_faces(in);
    const DegenerateReport& r = result.report;
    CHECK(r.near_vertices_welded > 0);
    CHECK_FALSE(r.weld_refused);
    CHECK(r.max_weld_move <= r.weld_distance);
    CHECK(r.weld_distance == Approx(1e-9 * r.bbox_diagonal));
    CHECK(r.self_intersections_welded == 0);
    const std::string path = test::scratch(std::string("degenerate_welded_") + (name[0] == 'c' ? "idler" : "block") + ".off");
    write_soup(result.soup, path);
    const Soup out = read_soup(path);
    DegenerateReport again = r;
    certify(in, out, again);
    CHECK(again.certified);
    const Report after = inspect(out);
    CHECK(after.degenerate_faces.empty());
    CHECK(after.caps.empty());
    CHECK(after.needles.empty());
    CHECK(after.self_intersections.empty());
    // closed now: the cracks were the boundary
    CHECK(after.closed);
    CHECK(after.boundary_loops == 0);
    CHECK(topology_of(after) == r.topology_in);
    CHECK(again.hausdorff + again.hausdorff_error_bound <= r.tolerance);
    // the exported input's vertices all lie near the output (the weld moved
    // them by at most max_weld_move)
    const detail::SurfaceDistance to_output(out);
    for (const Point3d& p : in.points) CHECK(std::sqrt(to_output.squared_distance(p)) <= r.tolerance);
  }
}

TEST_CASE("degenerate: a near weld that would make an edge non-manifold is not made", "[repair][degenerate]") {
  // Two boxes whose edges run 1e-12 apart: welded, four faces would share
  // that edge. The weld is refused and the two closed boxes stay as given.
  const double gap = 1e-12;
  const Soup in = test::concat(test::box({0, 0, 0}, {1, 1, 1}), test::box({1 + gap, 1 + gap, 0}, {2, 2, 1}));
  const DegenerateResult result = remove_degenerate_faces(in);
  const DegenerateReport& r = result.report;
  CHECK(r.weld_refused);
  CHECK(r.near_vertices_welded == 0);
  CHECK(r.max_displacement == 0);
  CHECK(r.topology_in == r.topology_unwelded);
  CHECK(r.topology_out == r.topology_in);
  CHECK(r.certified);
  CHECK(test::faces_by_position(result.soup) == test::faces_by_position(in));
}

TEST_CASE("degenerate with a fold angle: a spike folded onto its neighbours is collapsed (repair --for tetgen)",
          "[repair]") {
  // The unit cube with its top face as a 4 x 4 grid; the grid vertex at
  // (0.5, 0.5) is pushed across the edge (0.5, 0.25)-(0.75, 0.5) of its
  // star and 1e-6 above the top: the face over that edge turns over onto
  // its neighbour (folded at ~0 degrees; TetGen: "nearly self-intersecting
  // facets"), with no exact self-intersection and no bad angle.
  Soup s;
  auto at = [&](double x, double y, double z) {
    s.points.push_back({x, y, z});
    return Index(s.points.size() - 1);
  };
  Index top[5][5];
  for (int i = 0; i <= 4; ++i)
    for (int j = 0; j <= 4; ++j) top[i][j] = at(i / 4.0, j / 4.0, 1.0);
  s.points[top[2][2]] = {2.7 / 4.0, 1.3 / 4.0, 1.0 + 1e-6};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {  // outward (+z): counter-clockwise seen from above
      s.add_triangle(top[i][j], top[i + 1][j], top[i + 1][j + 1]);
      s.add_triangle(top[i][j], top[i + 1][j + 1], top[i][j + 1]);
    }
  // The other five sides, fanned from the top's border to the bottom square.
  const Index b00 = at(0, 0, 0), b10 = at(1, 0, 0), b11 = at(1, 1, 0), b01 = at(0, 1, 0);
  s.add_triangle(b00, b11, b10);
  s.add_triangle(b00, b01, b11);
  for (int k = 0; k < 4; ++k) {
    s.add_triangle(top[k + 1][0], top[k][0], k < 2 ? b00 : b10);     // y = 0
    s.add_triangle(top[4][k + 1], top[4][k], k < 2 ? b10 : b11);     // x = 1
    s.add_triangle(top[3 - k][4], top[4 - k][4], k < 2 ? b11 : b01); // y = 1
    s.add_triangle(top[0][3 - k], top[0][4 - k], k < 2 ? b01 : b00); // x = 0
  }
  s.add_triangle(top[2][0], b00, b10);
  s.add_triangle(top[4][2], b10, b11);
  s.add_triangle(top[2][4], b11, b01);
  s.add_triangle(top[0][2], b01, b00);
  const Report in = inspect(s);
  REQUIRE(in.certified_clean());     // exactly clean ...
  REQUIRE_FALSE(in.sharp_folds.empty());  // ... but not for TetGen

  DegenerateOptions o;
  o.cap_angle = 179.9;
  o.needle_angle = 0.1;
  o.certify = false;
  const Soup plain = remove_degenerate_faces(s, o).soup;
  CHECK(inspect(plain).sharp_folds.size() == in.sharp_folds.size());  // folds are not bad shapes

  o.fold_angle = 0.1;
  const DegenerateResult r = remove_degenerate_faces(s, o);
  InspectOptions io;
  io.tetgen_segments = true;
  const Report out = inspect(r.soup, io);
  CHECK(out.certified_clean());
  CHECK(out.sharp_folds.empty());
  CHECK(out.tetgen_ready());
  CHECK(r.report.collapses >= 1);
  CHECK(topology_of(out) == topology_of(in));
  CHECK(detail::hausdorff_distance(s, r.soup, 1e-7) < 1e-5);  // the bump was 1e-6 high
}

TEST_CASE("degenerate: a split point takes its doubles early only where that changes nothing the oracle checks",
          "[repair][degenerate]") {
  using detail::round_if_unchanged;
  const double cos_cap = std::cos(175.0 * M_PI / 180.0), cos_needle = std::cos(5.0 * M_PI / 180.0);
  const Kernel::FT tiny = Kernel::FT(std::ldexp(1.0, -600)) * Kernel::FT(std::ldexp(1.0, -600));  // rounds to 0
  auto mesh_of = [](const std::vector<Point>& pts, const std::vector<std::array<int, 3>>& faces) {
    Mesh m;
    std::vector<vertex_descriptor> v;
    for (const Point& p : pts) v.push_back(m.add_vertex(p));
    for (const auto& f : faces) m.add_face(v[f[0]], v[f[1]], v[f[2]]);
    return m;
  };
  SECTION("a point that rounds onto its face's base line would make the face degenerate: it stays exact") {
    Mesh m = mesh_of({Point(0, 0, 0), Point(1, 0, 0), Point(Kernel::FT(0.5), tiny, Kernel::FT(0))}, {{0, 1, 2}});
    LocalIndex index(m);
    const vertex_descriptor v(2);
    REQUIRE(approx_point3d(m.point(v))[1] == 0.0);
    CHECK_FALSE(round_if_unchanged(m, index, v, cos_cap, cos_needle));
    CHECK(m.point(v).y() == tiny);
  }
  SECTION("a point whose rounding makes its face a needle (angle at a just above 5 degrees, then below): exact") {
    // a = 0, b = (L, 0, 0), v = (L/2, y, 0): the angle at a is below the
    // needle angle iff y^2 < Y = (L/2)^2 (1 - c^2) / c^2 (c: the double
    // cosine the classification uses). Find L whose threshold sqrt(Y) lies
    // in the lower half of its double interval [h0, h1]: then y just below
    // the interval's midpoint is fine exactly and rounds down to h0, a needle.
    using FT = Kernel::FT;
    const FT c2 = FT(cos_needle) * FT(cos_needle);
    std::optional<std::pair<double, FT>> found;
    for (double L = 1.0; L < 2.0 && !found; L += 0.0137) {
      const FT Y = FT(L / 2) * FT(L / 2) * (FT(1) - c2) / c2;
      double h0 = std::sqrt(CGAL::to_double(Y));
      while (FT(h0) * FT(h0) >= Y) h0 = std::nextafter(h0, 0.0);
      while (FT(std::nextafter(h0, 1.0)) * FT(std::nextafter(h0, 1.0)) < Y) h0 = std::nextafter(h0, 1.0);
      const FT mid = (FT(h0) + FT(std::nextafter(h0, 1.0))) / FT(2);
      if (!(Y < mid * mid)) continue;  // the threshold is in the upper half
      FT delta = (mid - FT(h0)) / FT(2);
      while (!((mid - delta) * (mid - delta) > Y)) delta = delta / FT(2);
      found = std::make_pair(L, mid - delta);
    }
    REQUIRE(found);
    const auto [L, y] = *found;
    Mesh m = mesh_of({Point(0, 0, 0), Point(L, 0, 0), Point(FT(L / 2), y, FT(0))}, {{0, 1, 2}});
    LocalIndex index(m);
    const vertex_descriptor v(2);
    REQUIRE(classify_face(m, face_descriptor(0), cos_cap, cos_needle) == Shape::fine);
    const Point3d r = approx_point3d(m.point(v));
    REQUIRE(classify_triangle(Point(0, 0, 0), Point(L, 0, 0), Point(r[0], r[1], r[2]), cos_cap, cos_needle) ==
            Shape::needle);
    CHECK_FALSE(round_if_unchanged(m, index, v, cos_cap, cos_needle));
    CHECK(m.point(v).y() == y);
  }
  SECTION("a point just above a line through its face's base, whose doubles lie below it, would turn the face") {
    // a = 0, b = (3, 1, 0): the line y = x / 3; v = (1, 1/3 + 2^-80, 0) is
    // above it, and the double nearest its y is below 1/3. A cap before and
    // after (the shape rule allows that): only the normals catch it.
    using FT = Kernel::FT;
    const FT y = FT(1) / FT(3) + FT(std::ldexp(1.0, -80));
    Mesh m = mesh_of({Point(0, 0, 0), Point(3, 1, 0), Point(FT(1), y, FT(0))}, {{0, 1, 2}});
    LocalIndex index(m);
    const vertex_descriptor v(2);
    REQUIRE(FT(approx_point3d(m.point(v))[1]) < FT(1) / FT(3));
    CHECK_FALSE(round_if_unchanged(m, index, v, cos_cap, cos_needle));
    CHECK(m.point(v).y() == y);
  }
  SECTION("a point that rounds onto another face's edge would make them meet: it stays exact") {
    // apex just right of x = 0.5 at y = 1 (by far less than half an ulp);
    // the other face stands in the plane x = 0.5, above y = 1, its edge
    // through (0.5, 1, 0)
    const Kernel::FT x = Kernel::FT(0.5) + Kernel::FT(std::ldexp(1.0, -60)) / Kernel::FT(3);
    Mesh m = mesh_of({Point(0, 0, 0), Point(1, 0, 0), Point(x, Kernel::FT(1), Kernel::FT(0)), Point(0.5, 1, -1),
                      Point(0.5, 1, 1), Point(0.5, 2, 0)},
                     {{0, 1, 2}, {3, 4, 5}});
    LocalIndex index(m);
    REQUIRE(index.intersections({face_descriptor(0)}).empty());
    const vertex_descriptor v(2);
    REQUIRE(approx_point3d(m.point(v))[0] == 0.5);
    CHECK_FALSE(round_if_unchanged(m, index, v, cos_cap, cos_needle));
    CHECK(m.point(v).x() == x);
    CHECK(index.intersections({face_descriptor(0)}).empty());
  }
  SECTION("elsewhere it takes its nearest doubles, and the index follows") {
    const Kernel::FT third = Kernel::FT(1) / Kernel::FT(3);
    Mesh m = mesh_of({Point(0, 0, 0), Point(1, 0, 0), Point(third, Kernel::FT(1), third)}, {{0, 1, 2}});
    LocalIndex index(m);
    const vertex_descriptor v(2);
    CHECK(round_if_unchanged(m, index, v, cos_cap, cos_needle));
    CHECK(m.point(v) == Point(1.0 / 3.0, 1, 1.0 / 3.0));
    CHECK_FALSE(round_if_unchanged(m, index, v, cos_cap, cos_needle));  // already doubles
  }
  SECTION("all at once (round_all_if_unchanged): a slice's points move together where each would alone") {
    using FT = Kernel::FT;
    const std::vector<Point> pts{Point(0, 0, 0), Point(1, 0, 0), Point(FT(1) / FT(3), FT(1), FT(1) / FT(3)),
                                 Point(FT(2) / FT(3), FT(1), FT(1) / FT(7))};
    Mesh one = mesh_of(pts, {{0, 1, 2}, {1, 3, 2}}), all = mesh_of(pts, {{0, 1, 2}, {1, 3, 2}});
    LocalIndex one_index(one), all_index(all);
    const std::vector<vertex_descriptor> split{vertex_descriptor(2), vertex_descriptor(3)};
    CHECK(detail::round_all_if_unchanged(all, all_index, split, cos_cap, cos_needle) == std::optional<std::size_t>(2));
    for (vertex_descriptor v : split) CHECK(round_if_unchanged(one, one_index, v, cos_cap, cos_needle));
    for (vertex_descriptor v : split) CHECK(all.point(v) == one.point(v));
    CHECK(all_index.intersections({face_descriptor(0), face_descriptor(1)}).empty());
    CHECK(detail::round_all_if_unchanged(all, all_index, split, cos_cap, cos_needle) == std::optional<std::size_t>(0));
  }
  SECTION("all at once: one point that may not move stops them all (then they go one by one)") {
    // the first face's apex would round onto its base line (degenerate);
    // the second face's apex rounds as in the section above
    using FT = Kernel::FT;
    const Point third(FT(1) / FT(3), FT(1), FT(1) / FT(3) + FT(5));
    Mesh m = mesh_of({Point(0, 0, 0), Point(1, 0, 0), Point(FT(0.5), tiny, FT(0)), Point(0, 0, 5), Point(1, 0, 5), third},
                     {{0, 1, 2}, {3, 4, 5}});
    LocalIndex index(m);
    const std::vector<vertex_descriptor> split{vertex_descriptor(2), vertex_descriptor(5)};
    CHECK_FALSE(detail::round_all_if_unchanged(m, index, split, cos_cap, cos_needle));
    CHECK(m.point(split[0]).y() == tiny);
    CHECK(m.point(split[1]) == third);
    CHECK_FALSE(round_if_unchanged(m, index, split[0], cos_cap, cos_needle));
    CHECK(round_if_unchanged(m, index, split[1], cos_cap, cos_needle));
  }
}

namespace {

/// A closed prism over a regular n-gon as CAD exports a cylinder: each side
/// a long thin rectangle split by a diagonal, each end a fan from its centre.
Soup cad_prism(int n, double radius, double length) {
  Soup s;
  for (int end = 0; end < 2; ++end)
    for (int k = 0; k < n; ++k)
      s.points.push_back({radius * std::cos(2 * M_PI * k / n), radius * std::sin(2 * M_PI * k / n), end * length});
  s.points.push_back({0, 0, 0});
  s.points.push_back({0, 0, length});
  const Index c0 = static_cast<Index>(2 * n), c1 = c0 + 1;
  for (int k = 0; k < n; ++k) {
    const Index a = static_cast<Index>(k), b = static_cast<Index>((k + 1) % n), a1 = a + n, b1 = b + n;
    for (const std::array<Index, 3>& f : {std::array<Index, 3>{a, b, b1}, {a, b1, a1}, {c0, b, a}, {c1, a1, b1}})
      s.add_face(f.begin(), f.end());
  }
  return s;
}

/// The prism of n strips 29 times longer than wide (halves of a strip,
/// atan(2/29) = 3.9 deg, are still needles; thirds, 5.9 deg, are not),
/// repaired and checked; each strip's two faces are needles before.
DegenerateResult strips_29_to_1(int n) {
  const double width = 2 * std::sin(M_PI / n);
  const Soup input = cad_prism(n, 1.0, 29 * width);
  DegenerateResult r = run(input);
  CHECK(r.report.before.needles == std::size_t(2 * n));
  WARN(n << " strips: " << input.face_count() << " faces -> " << r.soup.face_count() << " ("
         << r.report.strip_points << " points on " << r.report.strips_staggered << " strips, "
         << r.report.needle_slices << " needle cuts, " << r.report.collapses << " collapses)");
  return r;
}

}  // namespace

TEST_CASE("degenerate: a CAD cylinder's strips get staggered points on their sides, 4 triangles each",
          "[repair][degenerate]") {
  // Cuts across the strips put points on both sides at the same places, 6
  // triangles per strip (300 faces out after what the decimation removes);
  // one point per side, at 1/3 on one and 2/3 on the next, makes a zigzag of
  // 4 triangles of about 5.9 degrees — the side's point serves the strips on
  // both sides of it. The strips are too far apart in angle (9 degrees) to
  // be merged within the tolerance.
  const int n = 40;
  const DegenerateResult r = strips_29_to_1(n);
  CHECK(r.report.strips_staggered == std::size_t(n));
  CHECK(r.soup.face_count() <= 2 * n + 4 * n);
}

TEST_CASE("degenerate: in a ring of an odd number of strips the last one is aligned, and repaired too",
          "[repair][degenerate]") {
  // Staggering alternates around the ring; with 41 strips the last strip's
  // two sides have their points at the same place (thirds: halves of 29:1
  // strips are needles), which the needle rounds repair.
  const int n = 41;
  const DegenerateResult r = strips_29_to_1(n);
  CHECK(r.soup.face_count() <= 2 * n + 4 * n + 8);
}

TEST_CASE("degenerate: a long thin cylinder's strips become zigzags of many points", "[repair][degenerate]") {
  // 24 strips 153 times longer than wide need 15 pieces a side (atan(15/153)
  // = 5.6 deg): 7 points on each side. From the fans the split leaves, the
  // decimation's flips stalled (131 needles left); the strips are
  // retriangulated as the zigzag directly, q + 1 = 16 triangles each.
  // Before staggering the same prism kept 100 needles.
  const int n = 24;
  const Soup input = cad_prism(n, 1.0, 40.0);
  const DegenerateResult r = run(input);
  CHECK(r.report.before.needles == std::size_t(2 * n));
  CHECK(r.report.strip_zigzags == std::size_t(n));
  CHECK(r.soup.face_count() <= 2 * n + 16 * n);
}

TEST_CASE("degenerate: a finely faceted cylinder is coarsened, not staggered", "[repair][degenerate]") {
  // 60 strips of 20:1, 6 degrees apart: with a tolerance a fifth of their
  // width a strip's neighbour lies within it of the strip's plane (the
  // side's sagitta is 0.26 of it), and decimation merges neighbouring
  // strips, halving their aspect; staggered points would add faces instead.
  const int n = 60;
  const double width = 2 * std::sin(M_PI / n);
  const Soup input = cad_prism(n, 1.0, 20 * width);
  DegenerateOptions o;
  o.tolerance = 0.2 * width;
  const DegenerateResult r = run(input, o);
  CHECK(r.report.strips_staggered == 0);
  WARN("fine CAD prism: " << input.face_count() << " faces -> " << r.soup.face_count());
  CHECK(r.soup.face_count() < input.face_count());
}

namespace {

/// A CAD cone as exporters write it (polyheal_gen cone): the side a fan of n
/// triangles around the tip (0, 0, height), each a needle there unless the
/// cone is wide and n small; the base fanned from one corner of its n-gon.
Soup cad_cone(int n, double radius, double height) {
  Soup s;
  for (int k = 0; k < n; ++k)
    s.points.push_back({radius * std::cos(2 * M_PI * k / n), radius * std::sin(2 * M_PI * k / n), 0});
  s.points.push_back({0, 0, height});
  const Index tip = static_cast<Index>(n);
  for (int k = 0; k < n; ++k) {
    const std::array<Index, 3> f{static_cast<Index>(k), static_cast<Index>((k + 1) % n), tip};
    s.add_face(f.begin(), f.end());
  }
  for (int k = 1; k + 1 < n; ++k) {
    const std::array<Index, 3> f{0, static_cast<Index>(k + 1), static_cast<Index>(k)};
    s.add_face(f.begin(), f.end());
  }
  return s;
}

bool has_point(const Soup& s, const Point3d& p) { return std::find(s.points.begin(), s.points.end(), p) != s.points.end(); }

}  // namespace

TEST_CASE("degenerate: a CAD cone's tip fan is graded in rings, its base around its centre", "[repair][degenerate]") {
  // 100 sectors of 2.5 degrees at the tip of a 45-degree cone: at most 46
  // faces there clear 5.5 degrees, and merging spokes moves the surface by
  // the sagitta of their chord, beyond the tolerance away from the tip. The
  // tip's star is graded (every spoke outside, fewer inside, within the
  // tolerance), and the base, fanned from one corner (1.8 degrees there),
  // is graded around its centroid. Before: 19 needles left.
  const Soup input = cad_cone(100, 10, 10);
  const DegenerateResult r = run(input);
  CHECK(r.report.before.needles >= 196);
  CHECK(r.report.apex_fans == 1);
  CHECK(r.report.planar_fans == 1);
  CHECK(r.report.apexes_moved == 0);
  CHECK(has_point(r.soup, {0, 0, 10}));  // the tip keeps its exact coordinates
  WARN("cone 100 x 45 deg: " << input.face_count() << " faces -> " << r.soup.face_count());
}

TEST_CASE("degenerate: the tip of a cone too narrow for any fan there moves inward, within the tolerance",
          "[repair][degenerate]") {
  // 30 segments, 20 times taller than its radius: 18 degrees around the tip,
  // and three spokes 120 degrees apart make 4.95 degrees each, so no fan at
  // the tip clears the needle angle. The tip moves along the axis by the
  // least distance that does, at most half the tolerance, and says so.
  // Before: 111 needles left along the side.
  const Soup input = cad_cone(30, 1, 20);
  const DegenerateResult r = run(input);
  CHECK(r.report.apexes_moved == 1);
  CHECK(r.report.max_displacement > 0);
  CHECK(r.report.max_displacement <= 0.5 * r.report.tolerance);
  CHECK_FALSE(has_point(r.soup, {0, 0, 20}));
  WARN("cone 30 x 20:1: " << input.face_count() << " faces -> " << r.soup.face_count());
}

TEST_CASE("degenerate: cones of other proportions are certified too", "[repair][degenerate]") {
  for (const auto& [n, radius, height] : std::vector<std::tuple<int, double, double>>{
           {64, 5, 20}, {100, 1, 10}, {200, 10, 10}, {48, 2, 40}, {128, 10, 5}}) {
    INFO(n << " segments, radius " << radius << ", height " << height);
    const Soup input = cad_cone(n, radius, height);
    const DegenerateResult r = run(input);
    CHECK(r.report.apex_fans + r.report.planar_fans >= 1);
  }
}

// The thin-walled tube's end rings: each outer chord (2.39 long) has an inner
// ring vertex 0.055 from it, a triangle of 2.6-degree angles at both ends of
// the chord and 174.8 degrees at the apex — a needle almost a cap, flat on
// its long edge. A halving cut leaves both halves needles; two cuts placed
// for the middle piece's angles, the split points on the inner ring then
// removed across the ring's crease, leave 4 triangles per chord on the ring
// (a hand construction's count: 416 faces in all). Halving cuts gave 476
// (1.53x the input, over the 1.5x target).
TEST_CASE("degenerate: flat needles on a tube's end rings are cut twice, within 1.5x the faces",
          "[repair][degenerate]") {
  const Soup in = read_soup(test::fixture("tube_edge2.42.off"));
  const Report before = inspect(in);
  REQUIRE(before.needles.size() == 26);
  REQUIRE(before.caps.empty());
  const DegenerateResult r = run(in);
  CHECK(r.report.needle_slices > 0);
  CHECK(r.soup.face_count() <= in.face_count() * 3 / 2);
  // nothing moved off the planes: the end rings and walls are the input's
  CHECK(r.report.hausdorff < 1e-12 * r.report.bbox_diagonal);
}
