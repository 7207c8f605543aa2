// polyheal deintersect (Yamakawa & Shimada): each case checks the output
// with the exact oracle on the soup as written (inspect(), independent of
// the repair's own bookkeeping), measures displacement itself, and for
// closed meshes asks TetGen, the user's next step.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <set>

#include "polyheal/inspect/report.h"
#include "polyheal/io/read.h"
#include "polyheal/io/write.h"
#include "polyheal/mesh/errors.h"
#include "polyheal/repair/deintersect.h"
#include "support/builders.h"

using namespace polyheal;

namespace {

double distance(const Point3d& a, const Point3d& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/// Largest vertex move between two soups with the same vertices in the
/// same order (what deintersect keeps for a welded input).
double max_move(const Soup& in, const Soup& out) {
  REQUIRE(in.points.size() == out.points.size());
  double m = 0;
  for (std::size_t i = 0; i < in.points.size(); ++i) m = std::max(m, distance(in.points[i], out.points[i]));
  return m;
}

/// Writes the output to scratch(`name`) and reads it back: the tests
/// check the file, as the CLI does. `path` (if given) receives its path.
Soup written(const DeintersectResult& result, const std::string& name, std::string* path = nullptr) {
  const std::string p = test::scratch(name);
  write_soup(result.soup, p);
  if (path) *path = p;
  return read_soup(p);
}

/// A horizontal square plate at height z, two triangles, corners at ±h.
Soup plate(double z, double h = 2.0) {
  return test::soup({{-h, -h, z}, {h, -h, z}, {h, h, z}, {-h, h, z}}, {{0, 1, 2}, {0, 2, 3}});
}

/// A tent (Fig. 5/6): apex (x, y, top) over a hexagon of radius `radius` at
/// height `rim`, open at the bottom; its six apex edges go up through
/// whatever lies between.
Soup tent(double top, double x = 0, double y = 0, double radius = 1, double rim = -1) {
  Soup s;
  s.points.push_back({x, y, top});
  for (int k = 0; k < 6; ++k) {
    const double a = k * 3.14159265358979323846 / 3;
    s.points.push_back({x + radius * std::cos(a), y + radius * std::sin(a), rim});
  }
  for (Index k = 0; k < 6; ++k) s.add_triangle(0, 1 + k, 1 + (k + 1) % 6);
  return s;
}

/// One operation alone (&DeintersectOptions::swap, ::hammer or ::lift),
/// for a toy scene where the defect is a large part of it.
DeintersectOptions only(bool DeintersectOptions::*op) {
  DeintersectOptions o;
  o.swap = o.hammer = o.lift = o.group = o.pair = false;
  o.*op = true;
  o.max_displacement = 2.0;
  return o;
}

/// Face lifting alone, with an absolute clearance.
DeintersectOptions lift_only(double clearance) {
  DeintersectOptions o = only(&DeintersectOptions::lift);
  o.clearance_mode = ClearanceMode::absolute;
  o.clearance = clearance;
  return o;
}

}  // namespace

TEST_CASE("deintersect: thin-walled tube at edge 3.0 and 4.0 comes out intersection-free (Fig. 3)",
          "[repair][deintersect][tetgen]") {
  for (const char* name : {"tube_edge3.0.off", "tube_edge4.0.off"}) {
    INFO(name);
    const Soup in = read_soup(test::fixture(name));
    REQUIRE_FALSE(inspect(in).self_intersections.empty());
    REQUIRE_FALSE(test::tetgen_meshes(test::fixture(name), std::string("deintersect_in_") + name));

    const DeintersectResult result = remove_self_intersections(in);
    std::string path;
    const Soup out = written(result, std::string("deintersect_") + name, &path);
    CHECK_CERTIFIED(out);
    CHECK(topology_of(inspect(out)) == topology_of(inspect(in)));
    CHECK(result.report.certified);
    CHECK(result.report.intersecting_faces_out == 0);
    // Wall clearance 0.2 (radii 5.0 / 4.8): the repair moves no vertex by
    // more than twice that.
    const double moved = max_move(in, out);
    CHECK(moved > 0);
    CHECK(moved <= 2 * 0.2);
    CHECK(result.report.max_displacement == Approx(moved));
    CHECK(test::tetgen_meshes(path, std::string("deintersect_out_") + name));
  }
}

TEST_CASE("deintersect: a wall poking through another moves back as one group (tube at edge 4.5)",
          "[repair][deintersect][tetgen]") {
  // The inner ring pokes 0.30 through the outer wall (1.5x the 0.2 wall
  // clearance); each inner vertex must move about 0.3 inwards, and moving
  // any one of them alone leaves its faces crossing through its neighbours'
  // faces. Allowed twice the clearance, the paper's operations alone free
  // nothing; the group move frees every face within the limit.
  const Soup in = read_soup(test::fixture("tube_edge4.5.off"));
  REQUIRE_FALSE(inspect(in).self_intersections.empty());
  REQUIRE_FALSE(test::tetgen_meshes(test::fixture("tube_edge4.5.off"), "deintersect_in_tube_edge4.5.off"));
  DeintersectOptions o;
  o.max_displacement = 2 * 0.2;
  o.group = o.pair = false;
  const DeintersectResult alone = remove_self_intersections(in, o);
  CHECK(alone.report.intersecting_faces_out == alone.report.intersecting_faces_in);
  CHECK(alone.soup.points == in.points);

  o.group = true;
  const DeintersectResult result = remove_self_intersections(in, o);
  std::string path;
  const Soup out = written(result, "deintersect_tube_edge4.5.off", &path);
  CHECK_CERTIFIED(out);
  CHECK(topology_of(inspect(out)) == topology_of(inspect(in)));
  CHECK(result.report.group_moves >= 1);
  const double moved = max_move(in, out);
  CHECK(moved > 0.29);  // at least the poke itself (0.295)
  CHECK(moved <= 2 * 0.2);
  CHECK(test::tetgen_meshes(path, "deintersect_out_tube_edge4.5.off"));
}

TEST_CASE("deintersect: the clean tube at edge 2.42 comes out untouched", "[repair][deintersect]") {
  const Soup in = read_soup(test::fixture("tube_edge2.42.off"));
  REQUIRE(inspect(in).certified_clean());
  const DeintersectResult result = remove_self_intersections(in);
  CHECK(result.soup.points == in.points);
  CHECK(result.soup.indices == in.indices);
  CHECK(result.report.swaps + result.report.hammers + result.report.lifts == 0);
  CHECK(result.report.faces_changed == 0);
}

TEST_CASE("deintersect: edge hammering frees a tent apex poking through a plate (Fig. 5/6a)",
          "[repair][deintersect]") {
  // The apex at z = 0.3 pokes through the plate at z = 0: all six apex
  // edges cross it once. Hammering the apex (one vertex) is the cheapest
  // fix; the plate, away from what moves, keeps its exact coordinates.
  const Soup in = test::concat(plate(0.0), tent(0.3));
  REQUIRE_FALSE(inspect(in).self_intersections.empty());
  const DeintersectResult result = remove_self_intersections(in, only(&DeintersectOptions::hammer));
  const Soup out = written(result, "deintersect_hammer.off");
  const Report r = inspect(out);
  CHECK(r.self_intersections.empty());
  CHECK(r.degenerate_faces.empty());
  CHECK(result.report.hammers >= 1);
  for (Index v = 0; v < 4; ++v) CHECK(out.points[v] == in.points[v]);  // the plate
  CHECK(out.points[4][2] < 0.0);                                       // the apex went under it
  for (Index v = 5; v < 11; ++v) CHECK(out.points[v] == in.points[v]);  // the tent's rim
}

TEST_CASE("deintersect: an edge crossing two plates moves between them first (Fig. 6b-d)",
          "[repair][deintersect]") {
  // Apex at z = 1 above plates at z = 0.5 and z = 0: each apex edge crosses
  // both. The paper's candidate for several crossings lies between the first
  // two, so one hammer frees the upper plate without touching the lower one;
  // rounds continue until the apex is under both.
  const Soup in = test::concat(test::concat(plate(0.5), plate(0.0)), tent(1.0));
  REQUIRE_FALSE(inspect(in).self_intersections.empty());
  const DeintersectResult result = remove_self_intersections(in, only(&DeintersectOptions::hammer));
  const Soup out = written(result, "deintersect_hammer2.off");
  CHECK(inspect(out).self_intersections.empty());
  CHECK(result.report.hammers >= 2);
  CHECK(result.report.rounds >= 2);
  for (Index v = 0; v < 8; ++v) CHECK(out.points[v] == in.points[v]);  // both plates
  CHECK(out.points[8][2] < 0.0);
}

TEST_CASE("deintersect: face lifting clears a face crossed by several edges (Fig. 7/8a-c)",
          "[repair][deintersect]") {
  // A triangle T at z = 0 (inradius 0.35 about the axis) crossed by all six
  // apex edges of a tent (apex 0.4, rim at -1): the crossing section of the
  // tent lies inside T, so only T can be lifted. T has no neighbours, so
  // both n(d_max+ε) and n(d_min-ε) free it; the smaller move wins (up past
  // the apex: 0.4 + ε, against 1 + ε down). The tent does not move.
  const Soup t = test::soup({{0, 0.7, 0}, {-0.606, -0.35, 0}, {0.606, -0.35, 0}}, {{0, 1, 2}});
  const Soup in = test::concat(t, tent(0.4));
  REQUIRE_FALSE(inspect(in).self_intersections.empty());
  const DeintersectResult result = remove_self_intersections(in, lift_only(0.05));
  const Soup out = written(result, "deintersect_lift.off");
  CHECK(inspect(out).self_intersections.empty());
  CHECK(result.report.lifts == 1);
  for (Index v = 0; v < 3; ++v) {
    CHECK(out.points[v][0] == in.points[v][0]);
    CHECK(out.points[v][1] == in.points[v][1]);
    CHECK(out.points[v][2] == Approx(0.4 + 0.05));
  }
  for (Index v = 3; v < 10; ++v) CHECK(out.points[v] == in.points[v]);
}

TEST_CASE("deintersect: a lift that would hit an intersection-free face is refused (Fig. 8d)",
          "[repair][deintersect]") {
  // T (z = 0) in a flat fan of three faces; a tent inside T pokes up through
  // it (apex 0.8, rim -0.2): lifting down by d_min-ε = 0.25 is the smaller
  // move, but T would then cut a small free tilted plate under its corner
  // (z from -0.1 to -0.4). The criteria refuse it (no intersection-free
  // face may start intersecting); T goes up by d_max+ε = 0.85 instead.
  const Soup fan = test::soup({{0, 0, 0}, {3, 0, 0}, {0, 3, 0}, {-3, -3, 0}}, {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}});
  const Soup cone = tent(0.8, 1, 1, 0.3, -0.2);
  const Soup blocker = test::soup({{2.0, 0.2, -0.1}, {2.6, 0.2, -0.4}, {2.3, 0.5, -0.25}}, {{0, 1, 2}});
  const Soup in = test::concat(test::concat(fan, cone), blocker);
  REQUIRE_FALSE(inspect(in).self_intersections.empty());
  const DeintersectResult result = remove_self_intersections(in, lift_only(0.05));
  const Soup out = written(result, "deintersect_lift_up.off");
  CHECK(inspect(out).self_intersections.empty());
  CHECK(result.report.lifts == 1);
  for (Index v = 0; v < 3; ++v) CHECK(out.points[v][2] == Approx(0.85));  // T went up, over the apex
  CHECK(out.points[3] == in.points[3]);
  for (Index v = 4; v < 14; ++v) CHECK(out.points[v] == in.points[v]);  // cone and blocker
}

TEST_CASE("deintersect: edge swapping removes a ridge edge piercing a plate (Fig. 4)", "[repair][deintersect]") {
  // Quad a b c d folded along ab (a ridge at z = 0, sides down to -1); a
  // small vertical plate in x = 0 is pierced by ab. Swapping ab for cd (a
  // valley at z = -1, below the plate) frees it; nothing moves.
  const Soup quad = test::soup({{-1, 0, 0}, {1, 0, 0}, {0, 1, -1}, {0, -1, -1}}, {{0, 1, 2}, {1, 0, 3}});
  const Soup wall = test::soup({{0, -0.1, -0.3}, {0, 0.1, -0.3}, {0, 0, 0.3}}, {{0, 1, 2}});
  const Soup in = test::concat(quad, wall);
  REQUIRE(inspect(in).self_intersections.size() == 2);
  const DeintersectResult result = remove_self_intersections(in, only(&DeintersectOptions::swap));
  const Soup out = written(result, "deintersect_swap.off");
  CHECK(inspect(out).self_intersections.empty());
  CHECK(result.report.swaps == 1);
  CHECK(out.points == in.points);
  CHECK(result.report.max_displacement == 0);
}

TEST_CASE("deintersect: an open mesh from the corpus (scan dragon with a boundary)", "[repair][deintersect]") {
  // ChineseDragon-10kv: 20k faces, an open boundary, 38 intersecting pairs
  // (../shared/corpus MANIFEST). Everything else keeps its coordinates.
  const Soup in = read_soup(test::fixture("ChineseDragon-10kv.off"));
  const Report before = inspect(in);
  REQUIRE_FALSE(before.self_intersections.empty());
  REQUIRE_FALSE(before.closed);
  const DeintersectResult result = remove_self_intersections(in);
  const Soup out = written(result, "deintersect_dragon.off");
  const Report after = inspect(out);
  CHECK(after.self_intersections.empty());
  CHECK(after.degenerate_faces.size() <= before.degenerate_faces.size());
  CHECK(topology_of(after) == topology_of(before));
  CHECK(result.report.certified);
  // Minimal repair: a handful of vertices move; every other one is bitwise the input's.
  std::size_t moved = 0;
  for (std::size_t i = 0; i < in.points.size(); ++i) moved += in.points[i] == out.points[i] ? 0 : 1;
  CHECK(moved == result.report.moved_vertices);
  CHECK(moved < 100);
  CHECK(max_move(in, out) <= 0.01 * result.report.bbox_diagonal);
}

TEST_CASE("deintersect: a closed corpus mesh TetGen refuses comes out meshable", "[repair][deintersect][tetgen]") {
  // V-HACD's drum: 29k faces, closed, 160 intersecting pairs (MANIFEST).
  const Soup in = read_soup(test::fixture("drum.off"));
  REQUIRE_FALSE(inspect(in).self_intersections.empty());
  REQUIRE_FALSE(test::tetgen_meshes(test::fixture("drum.off"), "deintersect_drum_in.off"));
  const DeintersectResult result = remove_self_intersections(in);
  std::string path;
  const Soup out = written(result, "deintersect_drum.off", &path);
  CHECK_CERTIFIED(out);
  CHECK(topology_of(inspect(out)) == topology_of(inspect(in)));
  CHECK(max_move(in, out) <= 0.02 * result.report.bbox_diagonal);  // the default limit
  CHECK(test::tetgen_meshes(path, "deintersect_drum_out.off"));
}

TEST_CASE("deintersect: a CAD STL with pinch vertices keeps them and comes out intersection-free",
          "[repair][deintersect]") {
  // trimesh's angle_block: 33 vertices whose faces form several fans (pinch
  // points), 102 intersecting pairs. Each fan gets a pinned copy of its
  // pinch point, which the oracle treats as one vertex; the copies weld
  // again in the written file.
  const Soup in = read_soup(test::fixture("angle_block.stl"));
  const Report before = inspect(in);
  REQUIRE(before.nonmanifold_vertices.size() == 33);
  REQUIRE_FALSE(before.self_intersections.empty());
  const DeintersectResult result = remove_self_intersections(in);
  const Soup out = written(result, "deintersect_angle_block.stl");
  const Report after = inspect(out);
  CHECK(after.self_intersections.empty());
  CHECK(topology_of(after) == topology_of(before));
  CHECK(after.nonmanifold_vertices.size() == 33);
  CHECK(after.degenerate_faces.size() <= before.degenerate_faces.size());
  CHECK(result.report.certified);
  // Every pinch point is still there, at its exact input position.
  std::set<Point3d> pinches_in, points_out(out.points.begin(), out.points.end());
  for (Index v : before.nonmanifold_vertices) pinches_in.insert(in.points[v]);
  for (const Point3d& p : pinches_in) CHECK(points_out.count(p) == 1);
}

TEST_CASE("deintersect: a swap never joins two pinch copies' edges (the file's topology stays)",
          "[repair][deintersect]") {
  // V-HACD's shark_b (42 pinch points, 20 intersecting pairs): a swap made
  // an edge c-d while another copy of c's point already had an edge to d's;
  // welded in the file, that was one edge of three faces: components 5 -> 4,
  // Euler -57 -> -56, two non-manifold edges.
  const Soup in = read_soup(test::fixture("corpus/vhacd__shark_b.off"));
  const Report before = inspect(in);
  REQUIRE_FALSE(before.nonmanifold_vertices.empty());
  REQUIRE_FALSE(before.self_intersections.empty());
  const DeintersectResult result = remove_self_intersections(in);
  const Report after = inspect(written(result, "deintersect_shark_b.off"));
  CHECK(result.report.swaps > 0);
  CHECK(after.self_intersections.size() < before.self_intersections.size());
  CHECK(topology_of(after) == topology_of(before));
  CHECK(after.nonmanifold_edges.empty());
  CHECK(result.report.topology_out == result.report.topology_in);
}

namespace {

/// A corpus mesh that needs operation `op` (one of our own, switched off
/// for the comparison): without it faces are left; with every operation the
/// written file is intersection-free, with the input's topology, no new
/// degenerate face and no vertex moved past the limit. Returns the report.
DeintersectReport freed_only_with(const std::string& name, bool DeintersectOptions::*op) {
  const Soup in = read_soup(test::fixture("corpus/" + name));
  const Report before = inspect(in);
  REQUIRE_FALSE(before.self_intersections.empty());
  DeintersectOptions o;
  o.*op = false;
  CHECK(remove_self_intersections(in, o).report.intersecting_faces_out > 0);

  const DeintersectResult result = remove_self_intersections(in);
  const Report after = inspect(written(result, "deintersect_" + name + ".off"));
  CHECK(after.self_intersections.empty());
  CHECK(result.report.certified);
  CHECK(topology_of(after) == topology_of(before));
  CHECK(after.degenerate_faces.size() <= before.degenerate_faces.size());
  CHECK(result.report.max_displacement <= result.report.max_displacement_allowed);
  return result.report;
}

}  // namespace

TEST_CASE("deintersect: pair moves free two bumps crossing on nearly coincident sheets (pig)",
          "[repair][deintersect]") {
  // CGAL's pig.stl (open, pinch points): at two mirror-image spots a thin
  // fin's two sides are fans whose middle vertices (three edges each) bulge
  // through each other. Flattening either bump alone frees nothing, so the
  // paper's operations and the group moves stop with faces left; flattening
  // a corner of each of two crossing faces at once frees them.
  CHECK(freed_only_with("cgal__pig.stl", &DeintersectOptions::pair).pair_moves >= 1);
}

TEST_CASE("deintersect: a push frees a large CAD face overlapped by a nearly coplanar fan (ALSTOM_TEST4)",
          "[repair][deintersect]") {
  // CGAL's ALSTOM_TEST4: one large face crossed at a shallow angle (normals
  // within 5 degrees) by a fan of nine faces. Lifting the large face past
  // all the nodes drives it into its other neighbours and no node alone
  // clears it; pushing the nodes on one side of its plane past it together
  // frees every face.
  CHECK(freed_only_with("cgal__ALSTOM_TEST4.off", &DeintersectOptions::group).group_moves >= 1);
}

TEST_CASE("deintersect: faces it cannot free are reported, never hidden", "[repair][deintersect]") {
  // Two spheres crossing deeply: no local move frees them. Whatever is left
  // must be exactly what the oracle finds in the written file.
  const Soup in = read_soup(test::fixture("spheres_intersecting.off"));
  const DeintersectResult result = remove_self_intersections(in);
  const Soup out = written(result, "deintersect_spheres.off");
  const Report after = inspect(out);
  CHECK_FALSE(result.report.certified);
  CHECK(after.self_intersections.size() == result.report.intersecting_pairs_out);
  CHECK(result.report.intersecting_faces_out > 0);
  CHECK(result.report.intersecting_faces_out < result.report.intersecting_faces_in);  // never worse
  CHECK(topology_of(after) == topology_of(inspect(in)));
}

TEST_CASE("deintersect: no vertex moves further than --max-displacement", "[repair][deintersect]") {
  // The tent apex 0.3 above the plate must drop about 0.33 to clear it.
  // Allowed 0.1, no vertex can move that far: faces are left and reported,
  // and every point is bitwise the input's (a swap moves none). Allowed 0.5,
  // it is repaired.
  const Soup in = test::concat(plate(0.0), tent(0.3));
  DeintersectOptions o;
  o.max_displacement = 0.1;
  const DeintersectResult held = remove_self_intersections(in, o);
  CHECK_FALSE(held.report.certified);
  CHECK(held.report.intersecting_faces_out > 0);
  CHECK(held.report.max_displacement == 0);
  CHECK(held.soup.points == in.points);
  o.max_displacement = 0.5;
  const DeintersectResult freed = remove_self_intersections(in, o);
  CHECK(freed.report.certified);
  CHECK(freed.report.max_displacement > 0.1);
  CHECK(freed.report.max_displacement <= 0.5);
  CHECK(max_move(in, written(freed, "deintersect_capped.off")) <= 0.5);
}

TEST_CASE("deintersect: fixed points never move (a region cut out of a larger surface)", "[repair][deintersect]") {
  // The tent apex 0.3 above the plate: freed by moving the apex down, or
  // (fixed) by moving the plate's corners instead; with the apex and the
  // plate both fixed, nothing may move and the faces are left, reported.
  const Soup in = test::concat(plate(0.0), tent(0.3));
  const Index apex = 4;  // the plate's four corners come first
  DeintersectOptions o;
  o.max_displacement = 0.5;
  const DeintersectResult free = remove_self_intersections(in, o);
  REQUIRE(free.report.certified);
  REQUIRE(distance(free.soup.points[apex], in.points[apex]) > 0);  // the case is at stake: the apex is what moves
  std::vector<char> fixed(in.points.size(), 0);
  fixed[apex] = 1;
  o.fixed_points = &fixed;
  const DeintersectResult held = remove_self_intersections(in, o);
  REQUIRE(held.soup.points.size() == in.points.size());
  CHECK(held.soup.points[apex] == in.points[apex]);
  for (Index v = 0; v < 4; ++v) fixed[v] = 1;
  const DeintersectResult none = remove_self_intersections(in, o);
  CHECK(none.report.max_displacement == 0);
  CHECK(none.report.intersecting_faces_out > 0);
  for (std::size_t v = 0; v < in.points.size(); ++v)
    if (fixed[v]) CHECK(none.soup.points[v] == in.points[v]);
  // a pinch point (two fans at the apex: a second tent upside down on it)
  // gets copies; they come after the input's points, where it is
  Soup pinched = in;
  const Index top = Index(pinched.points.size());
  for (int k = 0; k < 6; ++k) {
    const double a = k * 3.14159265358979323846 / 3;
    pinched.points.push_back({std::cos(a), std::sin(a), 1.6});
  }
  for (Index k = 0; k < 6; ++k) pinched.add_triangle(apex, top + (k + 1) % 6, top + k);
  std::vector<char> plate_fixed(pinched.points.size(), 0);
  for (Index v = 0; v < 4; ++v) plate_fixed[v] = 1;
  DeintersectOptions p = o;
  p.fixed_points = &plate_fixed;
  const DeintersectResult split = remove_self_intersections(pinched, p);
  REQUIRE(split.soup.points.size() > pinched.points.size());  // the case is at stake: a copy was made
  for (Index v = 0; v < 4; ++v) CHECK(split.soup.points[v] == pinched.points[v]);
  for (std::size_t j = pinched.points.size(); j < split.soup.points.size(); ++j)
    CHECK(split.soup.points[j] == split.soup.points[apex]);
  // point i of the result is point i of the input only without welds
  Soup twin = in;
  twin.points.push_back(twin.points[0]);
  fixed.push_back(0);
  CHECK_THROWS_AS(remove_self_intersections(twin, o), UnsupportedInput);
}

TEST_CASE("deintersect: operations tried and retracted leave no trace", "[repair][deintersect]") {
  // With a clearance of a fifth of the edge length no lift fits the default
  // displacement limit, and on this tube no swap alone helps: every trial is
  // made and undone. The output must be the input, index for index (an
  // undone swap once left its faces' corners rotated).
  const Soup in = read_soup(test::fixture("tube_edge4.0.off"));
  DeintersectOptions o = only(&DeintersectOptions::swap);
  o.lift = true;
  o.max_displacement = -1;  // the default limit
  o.clearance_mode = ClearanceMode::tet_aspect;
  o.clearance = 5;
  const DeintersectResult result = remove_self_intersections(in, o);
  REQUIRE(result.report.trials > 0);
  REQUIRE(result.report.swaps + result.report.lifts == 0);
  CHECK(result.soup.points == in.points);
  CHECK(result.soup.indices == in.indices);
  CHECK(result.report.faces_changed == 0);
}

TEST_CASE("deintersect: rounds that skip what nothing changed near end exactly as rounds that retry all",
          "[repair][deintersect]") {
  // bones: seven rounds, most of its stuck faces far from what each round
  // applies. Skipping them must change nothing: the same operations, the
  // same surface, bit for bit.
  const Soup in = read_soup(test::fixture("bones.off"));
  DeintersectOptions all;
  all.skip_unchanged = false;
  const DeintersectResult slow = remove_self_intersections(in, all);
  const DeintersectResult fast = remove_self_intersections(in);
  REQUIRE(slow.report.rounds > 2);
  REQUIRE(slow.report.sources_skipped == 0);
  CHECK(fast.report.sources_skipped > 0);
  CHECK(fast.report.trials < slow.report.trials);
  CHECK(fast.report.rounds == slow.report.rounds);
  CHECK(fast.report.swaps == slow.report.swaps);
  CHECK(fast.report.hammers == slow.report.hammers);
  CHECK(fast.report.lifts == slow.report.lifts);
  CHECK(fast.report.group_moves + fast.report.pair_moves == slow.report.group_moves + slow.report.pair_moves);
  CHECK(fast.soup.points == slow.soup.points);
  CHECK(fast.soup.indices == slow.soup.indices);
  CHECK(fast.report.intersecting_pairs_out == slow.report.intersecting_pairs_out);
}

TEST_CASE("deintersect: a work budget stops the moves, what they did is valid and what is left reported",
          "[repair][deintersect]") {
  // bones takes seven rounds. With a third of its trials the moves stop
  // inside a round: the operations found by then are still applied (each
  // re-validated), so the written file must hold no intersecting face the
  // input did not have, fewer than the input, the same topology, and the
  // report must say so. A budget above what it needs changes nothing.
  const Soup in = read_soup(test::fixture("bones.off"));
  const DeintersectResult free_run = remove_self_intersections(in);
  REQUIRE(free_run.report.rounds > 2);
  REQUIRE_FALSE(free_run.report.out_of_trials);
  DeintersectOptions o;
  o.max_trials = free_run.report.trials / 3;
  const DeintersectResult held = remove_self_intersections(in, o);
  CHECK(held.report.out_of_trials);
  CHECK(held.report.trials >= o.max_trials);
  CHECK(held.report.trials < free_run.report.trials);
  CHECK(held.report.rounds <= free_run.report.rounds);
  const Soup out = written(held, "deintersect_budget.off");
  const Report before = inspect(in), after = inspect(out);
  CHECK(after.self_intersections.size() == held.report.intersecting_pairs_out);
  CHECK(held.report.intersecting_faces_out > free_run.report.intersecting_faces_out);
  CHECK(held.report.intersecting_faces_out < held.report.intersecting_faces_in);
  std::set<std::size_t> was;
  for (const FacePair& p : before.self_intersections) was.insert({p.first, p.second});
  for (const FacePair& p : after.self_intersections) {
    CHECK(was.count(p.first));  // faces keep their ids: none started intersecting
    CHECK(was.count(p.second));
  }
  CHECK(topology_of(after) == topology_of(before));
  o.max_trials = free_run.report.trials + 1;
  const DeintersectResult ample = remove_self_intersections(in, o);
  CHECK_FALSE(ample.report.out_of_trials);
  CHECK(ample.soup.points == free_run.soup.points);
  CHECK(ample.soup.indices == free_run.soup.indices);
}

TEST_CASE("deintersect: a non-manifold soup is refused", "[repair][deintersect]") {
  // Three triangles on one edge.
  const Soup in = test::soup({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}},
                             {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
  CHECK_THROWS_AS(remove_self_intersections(in), UnsupportedInput);
}
